#include "apps/stop_on_signal.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <iostream>
#include <stdexcept>

namespace facets {
namespace {

// The write end of the one active watcher's pipe (one command per process).
volatile sig_atomic_t g_pipe_write = -1;
struct sigaction g_previous_int {}, g_previous_term {};

void OnSignal(int signal_number) {
  const int saved = errno;
  const unsigned char byte = static_cast<unsigned char>(signal_number);
  if (g_pipe_write >= 0) {
    [[maybe_unused]] const ssize_t ignored = ::write(g_pipe_write, &byte, 1);
  }
  errno = saved;
}

// SIGINT and SIGTERM while no StopOnSignal holds them (from start-up, while the program
// reads its arguments and inputs, until a command has an output to clean up, and after
// it): no output is being written, so the process says it stopped and ends with
// 128 + signal, as a stopped command does. Async-signal-safe: write and _exit only.
void StopAtOnce(int signal_number) {
  static constexpr char kInt[] = "facets: error: stopped by SIGINT\n";
  static constexpr char kTerm[] = "facets: error: stopped by SIGTERM\n";
  if (signal_number == SIGINT) {
    [[maybe_unused]] const ssize_t ignored = ::write(STDERR_FILENO, kInt, sizeof(kInt) - 1);
  } else {
    [[maybe_unused]] const ssize_t ignored = ::write(STDERR_FILENO, kTerm, sizeof(kTerm) - 1);
  }
  ::_exit(128 + signal_number);
}

// Installed before main, by the executable's first initialiser (the shared libraries'
// own run before it and cannot be covered). A caller may start facets with the two
// signals blocked; a signal sent meanwhile waits and arrives here.
[[gnu::constructor]] void InstallStopAtOnce() {
  struct sigaction action {};
  action.sa_handler = StopAtOnce;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, nullptr);
  ::sigaction(SIGTERM, &action, nullptr);
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  ::sigprocmask(SIG_UNBLOCK, &signals, nullptr);
}

}  // namespace

StopOnSignal::StopOnSignal(std::function<void(const std::string&)> on_stop) : on_stop_(std::move(on_stop)) {
  if (::pipe2(pipe_, O_CLOEXEC) != 0) throw std::runtime_error("cannot make the signal pipe");
  g_pipe_write = pipe_[1];
  watcher_ = std::thread([this] { Watch(); });
  struct sigaction action {};
  action.sa_handler = OnSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  ::sigaction(SIGINT, &action, &g_previous_int);
  ::sigaction(SIGTERM, &action, &g_previous_term);
}

StopOnSignal::~StopOnSignal() {
  // After Finish the command's output is final (committed, or reported as unchanged): a
  // signal from here until the process ends must not say "stopped" (and end with 130) over
  // a finished run, so the two signals are ignored; before it, the previous handlers return.
  bool finished = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    finished = finished_;
  }
  if (finished) {
    struct sigaction ignore {};
    ignore.sa_handler = SIG_IGN;
    sigemptyset(&ignore.sa_mask);
    ::sigaction(SIGINT, &ignore, nullptr);
    ::sigaction(SIGTERM, &ignore, nullptr);
  } else {
    ::sigaction(SIGINT, &g_previous_int, nullptr);
    ::sigaction(SIGTERM, &g_previous_term, nullptr);
  }
  const unsigned char stop = 0;
  [[maybe_unused]] const ssize_t ignored = ::write(pipe_[1], &stop, 1);
  watcher_.join();
  g_pipe_write = -1;
  ::close(pipe_[0]);
  ::close(pipe_[1]);
}

void StopOnSignal::Finish(const std::function<void()>& finish) {
  std::lock_guard<std::mutex> lock(mutex_);
  finished_ = true;
  finish();
}

void StopOnSignal::Watch() {
  for (;;) {
    unsigned char byte = 0;
    const ssize_t got = ::read(pipe_[0], &byte, 1);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0 || byte == 0) return;
    std::lock_guard<std::mutex> lock(mutex_);
    if (finished_) continue;
    const int signal_number = byte;
    on_stop_(signal_number == SIGINT ? "SIGINT" : signal_number == SIGTERM ? "SIGTERM" : "signal " + std::to_string(signal_number));
    std::cout.flush();
    std::cerr.flush();
    std::_Exit(128 + signal_number);
  }
}

}  // namespace facets
