// Image-parallel write: one input per tile and frame, taken as it is.
#include <string>

#include "base/Error.h"
#include "dfb/TileOperation.h"

namespace dfb {
namespace {

class WriteOperation final : public TileOperation {
 public:
  explicit WriteOperation(const Region& region) : region_(region) {}

  void newFrame(const FrameInfo&, std::uint32_t, int) override { received_ = 0; }

  InputNeeds needs() const override { return {.displayPixelsForColor = true}; }

  bool process(Tile&& input) override {
    if (++received_ > 1)
      throw base::Error("tile at (" + std::to_string(region_.x0) + ", " +
                        std::to_string(region_.y0) +
                        ") got a second input in one frame; the write operation takes exactly one");
    finished_ = std::move(input);  // the image-parallel hot path: no copy
    return true;
  }

  const Tile& finished() const override { return finished_; }
  std::vector<std::uint32_t> takeDisplayPixels() override { return std::move(finished_.rgba8); }

 private:
  Region region_;
  Tile finished_;
  int received_ = 0;
};

}  // namespace

TileOperationFactory writeOperation() {
  return [](const Region& region) { return std::make_unique<WriteOperation>(region); };
}

}  // namespace dfb
