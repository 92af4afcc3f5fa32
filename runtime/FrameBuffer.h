#pragma once
// The DFB options every job starts from, whichever program renders it: the canvas, its tiles, the
// frame's deadline, tone mapping, and compression of the gather where it crosses hosts.
#include <chrono>

#include "dfb/DistributedFrameBuffer.h"
#include "messaging/Messenger.h"

namespace runtime {

struct FrameBufferSettings {
  int width = 0, height = 0;
  int tileSize = 64;
  std::chrono::milliseconds timeout{60000};
  float exposure = 1;
  bool filmic = false;
  bool compress = true;  // the messenger's compression is on
  // Whether rank 0 needs the image every frame (a wall in gather mode, a program reading it)
  // or only after the last one.
  bool gatherEveryFrame = true;
};

dfb::DfbOptions frameBufferOptions(const FrameBufferSettings& settings,
                                   const messaging::Messenger& messenger);

}  // namespace runtime
