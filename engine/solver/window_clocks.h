// CPU seconds of the window adjustments' phases, summed over every window run of a
// reconstruction (the run's profile, engine/pipeline/run_profile.h). Each phase is read
// from the CPU clock of the thread that runs the window (CLOCK_THREAD_CPUTIME_ID), once
// per phase and iteration: the share of a phase's nested parallel loops that other
// threads take is not in it (it stays in the surrounding stage's process CPU).
#pragma once

#include <memory>
#include <mutex>

namespace facets {

struct WindowClocks {
  long long runs = 0;        // window runs (WindowAdjustment::Run)
  long long iterations = 0;  // their iterations
  double prepare = 0.0;      // creases, tessellation, Embree scene, normal-equation pattern (s)
  double occluders = 0.0;    // the occluders' selection and Embree scene (s; its build threads not counted)
  long long occluder_scenes = 0;  // occluder scenes attached (one per window run, more when the window moved far)
  double cast = 0.0;         // rays from the images' pixels onto the surface (s)
  double linearise = 0.0;    // observation equations accumulated into the normal equations (s)
  double solve = 0.0;        // LDL^T or PCG (s)
  double update = 0.0;       // vertices, normals, tessellation, Embree scene refit (s)
  double finish = 0.0;       // the window's report and precision (s)

  double Sum() const { return prepare + occluders + cast + linearise + solve + update + finish; }
  WindowClocks& operator+=(const WindowClocks& o);
  WindowClocks operator-(const WindowClocks& o) const;
};

// Where the windows of one reconstruction add their clocks; windows of a group run in
// parallel, so adding is locked (once per window run).
class WindowClockSink {
 public:
  void Add(const WindowClocks& clocks);
  WindowClocks Read() const;

 private:
  mutable std::mutex mutex_;
  WindowClocks sum_;
};

// CPU seconds of the calling thread.
double ThreadCpuSeconds();
// The calling thread's CPU seconds since *since, which becomes now.
double ThreadCpuLap(double* since);

}  // namespace facets
