// SIGINT (Ctrl-C) and SIGTERM while a command writes its output folder: the handler only
// writes the signal's number into a pipe (async-signal-safe); a watcher thread reads it
// and, unless the command has finished, calls on_stop (remove the temporary folder,
// write the failure log, say so) and ends the process with status 128 + signal. The
// command's own end takes the same lock (Finish), so a stop and a finished run never
// report both, and a signal after the finish changes nothing. Outside a StopOnSignal (from
// start-up on, before main), the two signals end the process at once with the same status
// and "facets: error: stopped by SIGINT": nothing is being written then.
#pragma once

#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace facets {

class StopOnSignal {
 public:
  // on_stop gets the signal's name ("SIGINT", "SIGTERM"). Installs the handlers (the
  // previous ones come back in the destructor unless Finish ran).
  explicit StopOnSignal(std::function<void(const std::string&)> on_stop);
  ~StopOnSignal();
  StopOnSignal(const StopOnSignal&) = delete;
  StopOnSignal& operator=(const StopOnSignal&) = delete;

  // Runs `finish` (commit the output, or report a failure) so that no stop interleaves
  // with it; signals after it are ignored, also after the destructor (the process is
  // about to end with the command's own status).
  void Finish(const std::function<void()>& finish);

 private:
  void Watch();

  std::function<void(const std::string&)> on_stop_;
  std::mutex mutex_;
  bool finished_ = false;
  int pipe_[2] = {-1, -1};
  std::thread watcher_;
};

}  // namespace facets
