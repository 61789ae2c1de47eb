#include "engine/pipeline/run_profile.h"

#include <chrono>
#include <cstdio>
#include <ctime>

namespace facets {
namespace {

template <typename... T>
std::string Format(const char* format, T... values) {
  char text[96];
  std::snprintf(text, sizeof(text), format, values...);
  return text;
}

}  // namespace

ClockReading ReadClocks() {
  timespec cpu{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &cpu);
  ClockReading r;
  r.wall = std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  r.cpu = static_cast<double>(cpu.tv_sec) + 1e-9 * static_cast<double>(cpu.tv_nsec);
  return r;
}

RunProfile::RunProfile() : window_clocks_(std::make_shared<WindowClockSink>()) {}

RunProfile::Scope::Scope(RunProfile* profile, int entry)
    : profile_(profile), entry_(entry), start_(ReadClocks()), windows_(profile->window_clocks_->Read()) {}

RunProfile::Scope::~Scope() {
  const ClockReading now = ReadClocks();
  ProfileEntry& e = profile_->entries_[entry_];
  ++e.calls;
  e.wall += now.wall - start_.wall;
  e.cpu += now.cpu - start_.cpu;
  e.windows += profile_->window_clocks_->Read() - windows_;
  if (e.part.empty()) profile_->open_stage_.clear();
}

int RunProfile::Entry(int level, int cycle, const std::string& stage, const std::string& part) {
  for (size_t k = 0; k < entries_.size(); ++k) {
    const ProfileEntry& e = entries_[k];
    if (e.level == level && e.cycle == cycle && e.stage == stage && e.part == part) return static_cast<int>(k);
  }
  ProfileEntry e;
  e.level = level;
  e.cycle = cycle;
  e.stage = stage;
  e.part = part;
  entries_.push_back(e);
  return static_cast<int>(entries_.size()) - 1;
}

RunProfile::Scope RunProfile::Stage(int level, int cycle, const std::string& stage) {
  open_level_ = level;
  open_cycle_ = cycle;
  open_stage_ = stage;
  return Scope(this, Entry(level, cycle, stage, ""));
}

void RunProfile::AddStage(int level, int cycle, const std::string& stage, const ClockReading& since) {
  const ClockReading now = ReadClocks();
  ProfileEntry& e = entries_[Entry(level, cycle, stage, "")];
  ++e.calls;
  e.wall += now.wall - since.wall;
  e.cpu += now.cpu - since.cpu;
}

RunProfile::Scope RunProfile::Part(const std::string& part) {
  if (open_stage_.empty()) return Scope(this, Entry(-1, 0, "other", part));
  return Scope(this, Entry(open_level_, open_cycle_, open_stage_, part));
}

void RunProfile::AddToTotal(const ClockReading& more) {
  total_.wall += more.wall;
  total_.cpu += more.cpu;
}

double RunProfile::CategoryCpu(const std::string& name) const {
  const WindowClocks windows = WindowTotals();
  if (name == "prepare") return windows.prepare;
  if (name == "occluders") return windows.occluders;
  if (name == "cast") return windows.cast;
  if (name == "linearise") return windows.linearise;
  if (name == "solve") return windows.solve;
  if (name == "update") return windows.update;
  if (name == "finish") return windows.finish;
  double sum = 0.0;
  for (const ProfileEntry& e : entries_) {
    if (e.part == name || (e.part.empty() && e.stage == name)) sum += e.cpu;
  }
  return sum;
}

WindowClocks RunProfile::WindowTotals() const {
  WindowClocks sum;
  for (const ProfileEntry& e : entries_) {
    if (e.part.empty()) sum += e.windows;
  }
  return sum;
}

double RunProfile::StagesCpu() const {
  double sum = 0.0;
  for (const ProfileEntry& e : entries_) {
    if (e.part.empty()) sum += e.cpu;
  }
  return sum;
}

const std::vector<std::string>& RunProfile::Categories() {
  static const std::vector<std::string> names = {
      "images",         "start",     "descent",   "prepare",           "occluders",         "cast",
      "linearise",      "solve",     "update",    "finish",            "normal search",
      "plane propagation", "trial re-adjustment", "crossing counts", "untangling", "products"};
  return names;
}

std::string RunProfile::Table() const {
  const double total = total_.cpu > 0.0 ? total_.cpu : 1.0;
  std::string out = Format("profile: %.1f CPU s, ", total_.cpu) +
                    Format("%.1f s wall (CPU s of all threads; share of the run's CPU s)\n", total_.wall);
  out += "  level stage / part                     calls    CPU s  share   wall s\n";
  for (const ProfileEntry& e : entries_) {
    std::string level = e.level < 0 ? std::string("run") : Format("%d", e.level);
    if (e.cycle > 0) level += Format("v%d", e.cycle);  // a V-cycle's pass
    const std::string name = e.part.empty() ? e.stage : Format("  %s", e.part.c_str());
    out += Format("  %-5s %-34s", level.c_str(), name.c_str()) + Format("%6d", e.calls) +
           Format(" %8.1f", e.cpu) + Format(" %5.1f%%", 100.0 * e.cpu / total) + Format(" %8.1f\n", e.wall);
    if (e.part.empty() && e.windows.runs > 0) {
      const WindowClocks& w = e.windows;
      out += Format("        windows: %lld runs, ", w.runs) + Format("%lld iterations; ", w.iterations) +
             Format("cast %.1f, ", w.cast) + Format("linearise %.1f, ", w.linearise) +
             Format("solve %.1f, ", w.solve) + Format("update %.1f, ", w.update) +
             Format("prepare %.1f, ", w.prepare) + Format("occluders %.1f ", w.occluders) +
             Format("(%lld scenes), ", w.occluder_scenes) + Format("finish %.1f\n", w.finish);
    }
  }
  out += "  by category (CPU s, share):";
  for (const std::string& name : Categories()) {
    const double cpu = CategoryCpu(name);
    out += Format(" %s ", name.c_str()) + Format("%.1f", cpu) + Format(" (%.1f%%);", 100.0 * cpu / total);
  }
  out += "\n";
  return out;
}

}  // namespace facets
