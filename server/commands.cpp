#include "commands.hpp"

namespace tumble::server {

CommandOutcome command_error(Failure failure, std::string message, std::string field) {
  return CommandError{failure, std::move(message), std::move(field)};
}

void CommandQueue::push(Command command) {
  bool queued = false;
  {
    std::lock_guard lock(mutex_);
    if (!closed_) {
      queue_.push_back(std::move(command));
      queued = true;
    }
  }
  if (queued) {
    if (wake_) wake_();
  } else if (command.done) {
    command.done(command_error(Failure::unavailable, "the server is shutting down", ""));
  }
}

std::deque<Command> CommandQueue::drain() {
  std::lock_guard lock(mutex_);
  return std::exchange(queue_, {});
}

void CommandQueue::close() {
  std::lock_guard lock(mutex_);
  closed_ = true;
}

bool CommandQueue::closed() const {
  std::lock_guard lock(mutex_);
  return closed_;
}

}  // namespace tumble::server
