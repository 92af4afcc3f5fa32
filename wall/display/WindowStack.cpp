#include "wall/display/WindowStack.h"

#include <algorithm>
#include <atomic>
#include <iterator>

#include "base/Error.h"

namespace wall {

// One window's part of one display: what the job's node uploads goes into a buffer of its own
// (the node uploads every pixel of each frame); swap() stages it for the window's commit.
class WindowStack::Layer : public Presenter {
 public:
  Layer(WindowStack& stack, Entry& entry, size_t index)
      : stack_(stack), entry_(entry), index_(index), part_(entry.layers[index].part) {}

  void beginFrame(int, int) override { ensure(); }
  void uploadAt(const std::uint32_t* first, int stride, const dfb::Region& rect) override {
    if (rect.x0 < 0 || rect.y0 < 0 || rect.x1 > part_.width() || rect.y1 > part_.height())
      throw base::Error("an upload outside a window's part of a display");
    ensure();
    for (int y = 0; y < rect.height(); ++y)
      std::copy_n(first + static_cast<std::ptrdiff_t>(y) * stride, rect.width(),
                  pending_->pixels.begin() +
                      static_cast<std::ptrdiff_t>(rect.y0 + y) * pending_->width + rect.x0);
  }
  void draw() override {}
  void swap() override {
    ensure();
    bool committed = false;
    {
      std::lock_guard lock(stack_.mutex_);
      Shown& s = entry_.layers[index_];
      if (!s.staged) ++entry_.staged;
      s.staged = std::move(pending_);
      if (entry_.staged == static_cast<int>(entry_.layers.size())) {
        // The last of the window's layers: every display gets this frame of the window at once.
        for (Shown& each : entry_.layers) {
          std::shared_ptr<const Image> old = std::move(each.pixels);
          each.pixels = std::move(each.staged);
          // A frame no composition holds any more is the next frame's buffer.
          // (The fence orders the composer's last reads, released with its reference, before
          // the next frame's writes.)
          if (old && old.use_count() == 1) {
            std::atomic_thread_fence(std::memory_order_acquire);
            each.spare = std::const_pointer_cast<Image>(old);
          }
          stack_.dirty_[static_cast<size_t>(each.display)] = 1;
        }
        entry_.staged = 0;
        committed = true;
      }
    }
    if (committed && stack_.changed_) stack_.changed_();
  }
  Image readBack() override {
    std::lock_guard lock(stack_.mutex_);
    const Shown& s = entry_.layers[index_];
    return s.pixels ? *s.pixels : Image(part_.width(), part_.height());
  }
  std::string describe() const override { return "a window's part of a display"; }

 private:
  void ensure() {
    if (pending_) return;
    {
      std::lock_guard lock(stack_.mutex_);
      pending_ = std::move(entry_.layers[index_].spare);
    }
    if (!pending_) pending_ = std::make_shared<Image>(part_.width(), part_.height());
  }

  WindowStack& stack_;
  Entry& entry_;
  size_t index_;
  dfb::Region part_;
  std::shared_ptr<Image> pending_;  // the frame being uploaded
};

WindowStack::Window::Window(WindowStack& stack, Entry& entry) : stack_(stack), entry_(entry) {
  for (size_t i = 0; i < entry.layers.size(); ++i)
    layers_.push_back(std::make_unique<Layer>(stack, entry, i));
}

WindowStack::Window::~Window() {
  layers_.clear();
  stack_.remove(&entry_);
}

std::vector<Presenter*> WindowStack::Window::presenters() const {
  std::vector<Presenter*> out;
  for (const auto& layer : layers_) out.push_back(layer.get());
  return out;
}

void WindowStack::Window::setOrder(std::uint64_t order) { stack_.setOrder(&entry_, order); }

std::vector<WindowStack::Window::Shown> WindowStack::Window::shown() const {
  std::lock_guard lock(stack_.mutex_);
  std::vector<Shown> out;
  for (const WindowStack::Shown& layer : entry_.layers)
    out.push_back({layer.display, layer.part, layer.pixels});
  return out;
}

WindowStack::WindowStack(std::vector<Size> displays, std::uint32_t background,
                         std::function<void()> changed)
    : sizes_(std::move(displays)),
      background_(background),
      changed_(std::move(changed)),
      dirty_(sizes_.size(), 0) {
  for (const Size& s : sizes_) frames_.emplace_back(s.width, s.height, background_);
}

WindowStack::~WindowStack() = default;

std::unique_ptr<WindowStack::Window> WindowStack::add(const std::vector<dfb::Region>& parts,
                                                      std::uint64_t tag, std::uint64_t order) {
  if (parts.size() != sizes_.size())
    throw base::Error("a window names " + std::to_string(parts.size()) + " display parts for " +
                      std::to_string(sizes_.size()) + " displays");
  Entry entry;
  entry.tag = tag;
  for (size_t d = 0; d < parts.size(); ++d) {
    const dfb::Region& part = parts[d];
    if (part.empty()) continue;
    if (part.x0 < 0 || part.y0 < 0 || part.x1 > sizes_[d].width || part.y1 > sizes_[d].height)
      throw base::Error("a window's part of a display lies outside it");
    entry.layers.push_back({part, static_cast<int>(d), nullptr, nullptr, nullptr});
  }
  std::unique_ptr<Window> window;
  {
    std::lock_guard lock(mutex_);
    window = addLocked(std::move(entry), order);
  }
  if (changed_) changed_();
  return window;
}

std::unique_ptr<WindowStack::Window> WindowStack::addLocked(Entry entry, std::uint64_t order) {
  if (order == kOnTop) order = windows_.empty() ? 0 : windows_.back().order;
  entry.order = order;
  if (windows_.empty()) markAll();
  windows_.push_back(std::move(entry));
  Entry& added = windows_.back();  // a list's elements stay where they are when it is re-linked
  // A window shows nothing before its first commit: no display changes by where it goes.
  placeLocked(std::prev(windows_.end()));
  return std::unique_ptr<Window>(new Window(*this, added));
}

void WindowStack::placeLocked(std::list<Entry>::iterator entry) {
  // Above every window of a lower or equal order, below the first of a higher one.
  auto before = windows_.begin();
  while (before != windows_.end() && (before == entry || before->order <= entry->order)) ++before;
  windows_.splice(before, windows_, entry);
}

// A raise: the window's committed frames show in their new place at the next composition.
void WindowStack::setOrder(Entry* entry, std::uint64_t order) {
  {
    std::lock_guard lock(mutex_);
    const auto found =
        std::find_if(windows_.begin(), windows_.end(), [&](const Entry& e) { return &e == entry; });
    if (found == windows_.end()) throw base::Error("a window that is not on its stack any more");
    found->order = order;
    placeLocked(found);
    for (const Shown& s : found->layers) dirty_[static_cast<size_t>(s.display)] = 1;
  }
  if (changed_) changed_();
}

void WindowStack::markAll() { std::fill(dirty_.begin(), dirty_.end(), 1); }

// A job that ends closes its window: what was under it shows at the next composition.
void WindowStack::remove(Entry* entry) {
  {
    std::lock_guard lock(mutex_);
    for (const Shown& s : entry->layers) dirty_[static_cast<size_t>(s.display)] = 1;
    windows_.remove_if([&](const Entry& e) { return &e == entry; });
  }
  if (changed_) changed_();
}

std::vector<int> WindowStack::compose() {
  // Under the lock only the choice of frames: each committed frame is immutable until no
  // composition holds it, so composing runs unlocked while the jobs go on swapping.
  std::vector<int> changed;
  std::vector<std::vector<std::shared_ptr<const Image>>> held;
  std::vector<std::vector<ComposedLayer>> layers;
  {
    std::lock_guard lock(mutex_);
    for (size_t d = 0; d < dirty_.size(); ++d) {
      if (!dirty_[d]) continue;
      dirty_[d] = 0;
      changed.push_back(static_cast<int>(d));
      held.emplace_back();
      layers.emplace_back();
      for (const Entry& e : windows_)
        for (const Shown& s : e.layers)
          if (s.display == static_cast<int>(d) && s.pixels) {
            held.back().push_back(s.pixels);
            layers.back().push_back({s.part, s.pixels.get()});
          }
    }
  }
  for (size_t i = 0; i < changed.size(); ++i)
    composeLayers(frames_[static_cast<size_t>(changed[i])], background_, layers[i]);
  return changed;
}

void WindowStack::dropChanges() {
  std::lock_guard lock(mutex_);
  std::fill(dirty_.begin(), dirty_.end(), 0);
}

std::uint64_t WindowStack::topAt(int display, int x, int y) const {
  std::lock_guard lock(mutex_);
  for (auto entry = windows_.rbegin(); entry != windows_.rend(); ++entry)
    for (const Shown& layer : entry->layers)
      if (layer.display == display && x >= layer.part.x0 && x < layer.part.x1 &&
          y >= layer.part.y0 && y < layer.part.y1)
        return entry->tag;
  return 0;
}

std::size_t WindowStack::windows() const {
  std::lock_guard lock(mutex_);
  return windows_.size();
}

void composeLayers(Image& frame, std::uint32_t background,
                   const std::vector<ComposedLayer>& layers) {
  const int width = frame.width, height = frame.height;
  if (width <= 0 || height <= 0) return;
  for (const ComposedLayer& l : layers)
    if (l.part.empty() || l.part.x0 < 0 || l.part.y0 < 0 || l.part.x1 > width ||
        l.part.y1 > height || l.pixels->width != l.part.width() ||
        l.pixels->height != l.part.height())
      throw base::Error("a layer that does not fit its part of the display");
  // Bands of rows that the same layers cover, each cut into spans of one source: the top layer
  // there (index into `layers`) or the background (-1).
  struct Span {
    int x0, x1, layer;
  };
  struct Band {
    int y0, y1;
    std::vector<Span> spans;
  };
  std::vector<int> ys{0, height};
  for (const ComposedLayer& l : layers) {
    ys.push_back(l.part.y0);
    ys.push_back(l.part.y1);
  }
  std::sort(ys.begin(), ys.end());
  ys.erase(std::unique(ys.begin(), ys.end()), ys.end());
  std::vector<Band> bands;
  for (size_t b = 0; b + 1 < ys.size(); ++b) {
    Band band{ys[b], ys[b + 1], {}};
    std::vector<int> xs{0, width};
    for (const ComposedLayer& l : layers)
      if (l.part.y0 <= band.y0 && l.part.y1 >= band.y1) {
        xs.push_back(l.part.x0);
        xs.push_back(l.part.x1);
      }
    std::sort(xs.begin(), xs.end());
    xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
    for (size_t i = 0; i + 1 < xs.size(); ++i) {
      int top = -1;
      for (int l = static_cast<int>(layers.size()) - 1; l >= 0; --l) {
        const dfb::Region& p = layers[static_cast<size_t>(l)].part;
        if (p.y0 <= band.y0 && p.y1 >= band.y1 && p.x0 <= xs[i] && p.x1 >= xs[i + 1]) {
          top = l;
          break;
        }
      }
      if (!band.spans.empty() && band.spans.back().layer == top)
        band.spans.back().x1 = xs[i + 1];
      else
        band.spans.push_back({xs[i], xs[i + 1], top});
    }
    bands.push_back(std::move(band));
  }
  // One thread: composing is a copy bound by memory bandwidth; TBB's threads bought nothing here
  // (docs/benchmarks.md, "Composition") and would take cores from the pieces' decoding.
  std::size_t b = 0;
  for (int y = 0; y < height; ++y) {
    if (y >= bands[b].y1) ++b;
    std::uint32_t* out = frame.pixels.data() + static_cast<std::ptrdiff_t>(y) * width;
    for (const Span& s : bands[b].spans) {
      if (s.layer < 0) {
        std::fill(out + s.x0, out + s.x1, background);
        continue;
      }
      const ComposedLayer& l = layers[static_cast<size_t>(s.layer)];
      const std::uint32_t* in = l.pixels->pixels.data() +
                                static_cast<std::ptrdiff_t>(y - l.part.y0) * l.part.width() +
                                (s.x0 - l.part.x0);
      std::copy(in, in + (s.x1 - s.x0), out + s.x0);
    }
  }
}

}  // namespace wall
