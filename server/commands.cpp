#include "commands.hpp"

namespace tumble::server {

CommandResult command_error(unsigned status, std::string message, std::string field) {
  return {status, {{"error", std::move(message)}, {"field", std::move(field)}}};
}

void CommandQueue::push(Command command) {
  {
    std::lock_guard lock(mutex_);
    if (!closed_) {
      queue_.push_back(std::move(command));
      cv_.notify_one();
      return;
    }
  }
  if (command.done) command.done(command_error(503, "the server is shutting down", ""));
}

std::deque<Command> CommandQueue::drain() {
  std::lock_guard lock(mutex_);
  return std::exchange(queue_, {});
}

void CommandQueue::wait() {
  std::unique_lock lock(mutex_);
  cv_.wait(lock, [this] { return closed_ || !queue_.empty(); });
}

void CommandQueue::wait_until(std::chrono::steady_clock::time_point deadline) {
  std::unique_lock lock(mutex_);
  cv_.wait_until(lock, deadline, [this] { return closed_ || !queue_.empty(); });
}

void CommandQueue::close() {
  std::lock_guard lock(mutex_);
  closed_ = true;
  cv_.notify_all();
}

bool CommandQueue::closed() const {
  std::lock_guard lock(mutex_);
  return closed_;
}

}  // namespace tumble::server
