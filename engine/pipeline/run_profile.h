// The run's profile (report.json "profile" and the table at the end of a run): wall and
// CPU seconds of each stage of each pass over a level and of the run's own stages
// (images, start, products), of parts inside the stages (normal search, plane
// propagation, the trials' local re-adjustments, crossing counts, untangling), and the
// phases of the window adjustments that ran inside each (engine/solver/window_clocks.h).
// CPU seconds are the process's (all threads, CLOCK_PROCESS_CPUTIME_ID) over the stage:
// stages run one after another, so they add up; the machine's other load is not in them.
// Clocks are read once per stage, part or window run, never per pixel or vertex.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "engine/solver/window_clocks.h"

namespace facets {

// Wall seconds (steady clock) and process CPU seconds.
struct ClockReading {
  double wall = 0.0;
  double cpu = 0.0;
};
ClockReading ReadClocks();

struct ProfileEntry {
  int level = -1;     // pyramid level of the pass; -1: the run's own stages
  int cycle = 0;      // 0: the descent; 1..: V-cycles
  std::string stage;  // e.g. "adjust", "wall corners", "products"
  std::string part;   // empty: the stage itself; else a part inside it (parts may overlap)
  int calls = 0;
  double wall = 0.0;  // s
  double cpu = 0.0;   // s
  WindowClocks windows;  // phases of the window runs inside (thread CPU, s)
};

class RunProfile {
 public:
  RunProfile();

  // Clocks one stage or part while alive; adds its seconds to the profile at the end.
  class Scope {
   public:
    Scope(RunProfile* profile, int entry);
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;
    ~Scope();

   private:
    RunProfile* profile_;
    int entry_;
    ClockReading start_;
    WindowClocks windows_;
  };

  // A stage of a pass over `level` (cycle: the pass's V-cycle), or of the run (level -1).
  // Stages do not nest: the parts opened meanwhile belong to it.
  Scope Stage(int level, int cycle, const std::string& stage);
  // A stage clocked by its caller: from `since` until now (no window clocks).
  void AddStage(int level, int cycle, const std::string& stage, const ClockReading& since);
  // A part of the open stage (none open: of the run's stage "other").
  Scope Part(const std::string& part);
  // The whole run (the stages and parts lie inside it).
  void SetTotal(const ClockReading& total) { total_ = total; }
  void AddToTotal(const ClockReading& more);

  WindowClockSink* window_clocks() const { return window_clocks_.get(); }
  const std::vector<ProfileEntry>& entries() const { return entries_; }
  const ClockReading& total() const { return total_; }
  // CPU seconds of the run's stages in the named category summed over the levels
  // ("cast", "linearise", "solve" from the window clocks; other names: parts or stages).
  double CategoryCpu(const std::string& name) const;
  // Sum of the stages' (not the parts') CPU seconds.
  double StagesCpu() const;
  // The window clocks summed over the stages.
  WindowClocks WindowTotals() const;
  // The categories of CategoryCpu in the table's and report.json's order.
  static const std::vector<std::string>& Categories();
  // The profile as a compact table, one line per stage and part.
  std::string Table() const;

 private:
  int Entry(int level, int cycle, const std::string& stage, const std::string& part);

  std::vector<ProfileEntry> entries_;
  std::shared_ptr<WindowClockSink> window_clocks_;  // shared by copies of the report
  int open_level_ = -1, open_cycle_ = 0;
  std::string open_stage_;
  ClockReading total_;
};

}  // namespace facets
