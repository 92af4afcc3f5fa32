#include "runtime/FrameBuffer.h"

namespace runtime {

dfb::DfbOptions frameBufferOptions(const FrameBufferSettings& settings,
                                   const messaging::Messenger& messenger) {
  dfb::DfbOptions options;
  options.width = settings.width;
  options.height = settings.height;
  options.tileSize = settings.tileSize;
  options.frameTimeout = settings.timeout;
  // Like the messenger: compress the gather only where it crosses hosts.
  options.compressGather = settings.compress && !messenger.sameHost(0);
  options.toneMap.exposure = settings.exposure;
  options.toneMap.filmic = settings.filmic;
  options.gatherEveryFrame = settings.gatherEveryFrame;
  return options;
}

}  // namespace runtime
