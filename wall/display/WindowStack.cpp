#include "wall/display/WindowStack.h"

#include <algorithm>

#include "base/Error.h"

namespace wall {

// One job's window part on a shared display: it keeps what the job uploads (a frame the job has
// not swapped yet), and hands it to the stack at swap().
class WindowStack::Layer : public Presenter {
 public:
  Layer(WindowStack& stack, Shown& shown)
      : stack_(stack), shown_(shown), pending_(shown.part.width(), shown.part.height()) {}
  ~Layer() override { stack_.remove(&shown_); }
  const Shown& shown() const { return shown_; }

  void beginFrame(int, int) override {}
  void uploadAt(const std::uint32_t* first, int stride, const dfb::Region& rect) override {
    if (rect.x0 < 0 || rect.y0 < 0 || rect.x1 > pending_.width || rect.y1 > pending_.height)
      throw base::Error("an upload outside a window's part of a display");
    for (int y = 0; y < rect.height(); ++y)
      std::copy_n(first + static_cast<std::ptrdiff_t>(y) * stride, rect.width(),
                  pending_.pixels.begin() +
                      static_cast<std::ptrdiff_t>(rect.y0 + y) * pending_.width + rect.x0);
  }
  void draw() override {}
  void swap() override {
    std::lock_guard lock(stack_.mutex_);
    shown_.pixels = pending_;
    shown_.any = true;
    stack_.presentLocked();
  }
  Image readBack() override {
    std::lock_guard lock(stack_.mutex_);
    return shown_.pixels;
  }
  bool closeRequested() const override { return stack_.display_.closeRequested(); }
  std::string describe() const override { return stack_.display_.describe(); }

 private:
  WindowStack& stack_;
  Shown& shown_;
  Image pending_;
};

WindowStack::WindowStack(Presenter& display, int width, int height, std::uint32_t background)
    : display_(display),
      width_(width),
      height_(height),
      background_(background),
      frame_(width, height) {}

WindowStack::~WindowStack() = default;

std::unique_ptr<Presenter> WindowStack::add(const dfb::Region& part) {
  std::uint64_t top = 0;
  {
    std::lock_guard lock(mutex_);
    if (!shown_.empty()) top = shown_.back().order;
  }
  return add(part, top);
}

std::unique_ptr<Presenter> WindowStack::add(const dfb::Region& part, std::uint64_t order) {
  if (part.empty() || part.x0 < 0 || part.y0 < 0 || part.x1 > width_ || part.y1 > height_)
    throw base::Error("a window's part of a display lies outside it");
  std::lock_guard lock(mutex_);
  shown_.push_back({part, order, Image(part.width(), part.height()), false});
  Shown& added = shown_.back();  // a list's elements stay where they are when it is re-linked
  placeLocked(std::prev(shown_.end()));
  return std::make_unique<Layer>(*this, added);
}

void WindowStack::setOrder(const Presenter& layer, std::uint64_t order) {
  const auto* ours = dynamic_cast<const Layer*>(&layer);
  if (!ours) throw base::Error("WindowStack::setOrder: not a layer of a window stack");
  std::lock_guard lock(mutex_);
  const auto found = std::find_if(shown_.begin(), shown_.end(),
                                  [&](const Shown& s) { return &s == &ours->shown(); });
  if (found == shown_.end()) throw base::Error("WindowStack::setOrder: not a layer of this stack");
  found->order = order;
  placeLocked(found);
  presentLocked();
}

void WindowStack::placeLocked(std::list<Shown>::iterator shown) {
  // Above every layer of a lower or equal order, below the first of a higher one.
  auto before = shown_.begin();
  while (before != shown_.end() && (before == shown || before->order <= shown->order)) ++before;
  shown_.splice(before, shown_, shown);
}

void WindowStack::present() {
  std::lock_guard lock(mutex_);
  presentLocked();
}

std::size_t WindowStack::layers() const {
  std::lock_guard lock(mutex_);
  return shown_.size();
}

void WindowStack::presentLocked() {
  std::fill(frame_.pixels.begin(), frame_.pixels.end(), background_);
  for (const Shown& s : shown_) {
    if (!s.any) continue;
    for (int y = 0; y < s.part.height(); ++y)
      std::copy_n(
          s.pixels.pixels.begin() + static_cast<std::ptrdiff_t>(y) * s.pixels.width, s.pixels.width,
          frame_.pixels.begin() + static_cast<std::ptrdiff_t>(s.part.y0 + y) * width_ + s.part.x0);
  }
  display_.present(frame_.pixels.data(), width_, height_);
}

// A job that ends closes its window at once. A destructor does not throw: a display that fails
// here fails again at the next present, where it is reported.
void WindowStack::remove(const Shown* shown) {
  std::lock_guard lock(mutex_);
  shown_.remove_if([&](const Shown& s) { return &s == shown; });
  try {
    presentLocked();
  } catch (const std::exception&) {
  }
}

}  // namespace wall
