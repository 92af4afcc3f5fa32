#include "wall/display/WallCaptures.h"

#include <utility>

namespace wall {

WallCaptures::WallCaptures(const Layout& layout, int process, std::vector<Presenter*> presenters,
                           std::shared_ptr<const base::ConfinedFolder> dir, int every,
                           std::uint64_t quota, std::function<void(const std::string&)> log)
    : layout_(layout),
      mine_(layout.displaysOfProcess(process)),
      presenters_(std::move(presenters)),
      every_(every > 0 ? every : 1),
      log_(std::move(log)),
      writer_(std::move(dir), "", quota, "the wall's captures") {
  if (presenters_.size() != mine_.size())
    throw base::Error("wall captures: " + std::to_string(presenters_.size()) +
                      " presenters for the " + std::to_string(mine_.size()) +
                      " displays of wall process " + std::to_string(process));
  thread_ = std::thread([this] { run(); });
}

WallCaptures::~WallCaptures() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

void WallCaptures::presented(std::uint64_t wallFrame) {
  if (wallFrame == 0 || wallFrame % static_cast<std::uint64_t>(every_) != 0) return;
  {
    std::unique_lock lock(mutex_);
    if (failed_) return;
    // Back-pressure rather than a frame silently left out: the writer is kMaxQueued behind.
    changed_.wait(lock, [this] { return queue_.size() < kMaxQueued || failed_; });
    if (failed_) return;
  }
  Frame frame{wallFrame, {}};
  for (Presenter* p : presenters_) frame.displays.push_back(p->readBack());
  {
    std::lock_guard lock(mutex_);
    if (failed_) return;  // while this frame was read back
    queue_.push_back(std::move(frame));
  }
  changed_.notify_all();
}

void WallCaptures::flush() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [this] { return (queue_.empty() && !writing_) || failed_; });
}

void WallCaptures::run() {
  while (true) {
    Frame frame;
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [this] { return !queue_.empty() || stop_; });
      if (queue_.empty()) return;  // stopped, everything written
      frame = std::move(queue_.front());
      queue_.pop_front();
      writing_ = true;
    }
    changed_.notify_all();  // a place in the queue is free
    std::string failure;
    // Frame names are 32-bit like a job's; past 2^32 frames they wrap (years at 60 Hz).
    const auto id = static_cast<std::uint32_t>(frame.wallFrame);
    for (size_t i = 0; i < mine_.size() && failure.empty(); ++i) {
      try {
        writer_.writeDisplay(layout_, mine_[i], id, frame.displays[i].pixels.data());
      } catch (const std::exception& e) {
        failure = e.what();
      }
    }
    // Said before flush() can return on it.
    if (!failure.empty() && log_) log_("the wall's captures stop: " + failure);
    {
      std::lock_guard lock(mutex_);
      writing_ = false;
      if (!failure.empty()) {
        failed_ = true;
        queue_.clear();
      }
    }
    changed_.notify_all();
  }
}

}  // namespace wall
