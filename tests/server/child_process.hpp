#pragma once
/// A child process (the tumble-server binary) with its output on a pipe, for the tests that
/// check the binary itself (exit codes, the URL line, signals) and for the load tool.
/// Not thread-safe: one owner drives it.
#include <sys/types.h>

#include <cstdio>
#include <string>
#include <vector>

namespace tumble::server::test {

/// A spawned process; killed with SIGKILL and reaped on destruction if still running.
class ChildProcess {
 public:
  /// Spawns argv[0] with argv; its stdout (and stderr when merge_stderr) goes to a pipe.
  /// pid() is -1 when the spawn failed.
  explicit ChildProcess(std::vector<std::string> argv, bool merge_stderr = true);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  /// The process id, -1 if the spawn failed or the process was reaped.
  pid_t pid() const { return pid_; }
  /// The next output line with its newline; empty at end of output.
  std::string line();
  /// All remaining output up to end of file.
  std::string rest();
  /// Sends `signal` (no-op once reaped).
  void signal(int signal);
  /// Waits for exit: the exit code, or 128 + signal number; -1 if there is no process.
  int wait();
  /// SIGTERM, then wait().
  int stop();

 private:
  pid_t pid_ = -1;
  FILE* out_ = nullptr;
};

}  // namespace tumble::server::test
