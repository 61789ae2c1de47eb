#include "engine/solver/window_clocks.h"

#include <ctime>

namespace facets {

WindowClocks& WindowClocks::operator+=(const WindowClocks& o) {
  runs += o.runs;
  iterations += o.iterations;
  prepare += o.prepare;
  occluders += o.occluders;
  occluder_scenes += o.occluder_scenes;
  cast += o.cast;
  linearise += o.linearise;
  solve += o.solve;
  update += o.update;
  finish += o.finish;
  return *this;
}

WindowClocks WindowClocks::operator-(const WindowClocks& o) const {
  WindowClocks d;
  d.runs = runs - o.runs;
  d.iterations = iterations - o.iterations;
  d.prepare = prepare - o.prepare;
  d.occluders = occluders - o.occluders;
  d.occluder_scenes = occluder_scenes - o.occluder_scenes;
  d.cast = cast - o.cast;
  d.linearise = linearise - o.linearise;
  d.solve = solve - o.solve;
  d.update = update - o.update;
  d.finish = finish - o.finish;
  return d;
}

void WindowClockSink::Add(const WindowClocks& clocks) {
  std::lock_guard<std::mutex> lock(mutex_);
  sum_ += clocks;
}

WindowClocks WindowClockSink::Read() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return sum_;
}

double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double ThreadCpuLap(double* since) {
  const double now = ThreadCpuSeconds();
  const double lap = now - *since;
  *since = now;
  return lap;
}

}  // namespace facets
