#include "apps/StatusBoard.h"

namespace app {

void StatusBoard::publish(RunStatus status) {
  const auto now = std::chrono::steady_clock::now();
  std::lock_guard lock(mutex_);
  if (status.frame != status_.frame) {
    frameTimes_.push_back(now);
    if (frameTimes_.size() > 16) frameTimes_.pop_front();
  }
  if (status.idle) frameTimes_.clear();
  status.fps = 0;
  if (frameTimes_.size() >= 2) {
    const double seconds =
        std::chrono::duration<double>(frameTimes_.back() - frameTimes_.front()).count();
    if (seconds > 0) status.fps = static_cast<double>(frameTimes_.size() - 1) / seconds;
  }
  status.errors.clear();
  status_ = std::move(status);
  everPublished_ = true;
  published_.notify_all();
}

bool StatusBoard::waitForFirstPublish(std::chrono::milliseconds wait) const {
  std::unique_lock lock(mutex_);
  return published_.wait_for(lock, wait, [this] { return everPublished_; });
}

void StatusBoard::addError(std::string message) {
  std::lock_guard lock(mutex_);
  errors_.push_back(std::move(message));
  if (errors_.size() > 20) errors_.pop_front();
}

void StatusBoard::setLostDisplays(std::vector<std::string> names) {
  std::lock_guard lock(mutex_);
  lostDisplays_ = std::move(names);
}

void StatusBoard::setDisplays(std::vector<std::string> names) {
  std::lock_guard lock(mutex_);
  displays_ = std::move(names);
}

RunStatus StatusBoard::snapshot() const {
  std::lock_guard lock(mutex_);
  RunStatus out = status_;
  out.errors.assign(errors_.begin(), errors_.end());
  out.lostDisplays = lostDisplays_;
  out.displays = displays_;
  return out;
}

}  // namespace app
