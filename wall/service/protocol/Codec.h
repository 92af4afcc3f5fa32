#pragma once
// The pixel codecs of the wall service: how a render job packs a piece of a tile (an RGBA8
// rectangle, typically 64x64 or cut at a display border) for the TCP link to a remote wall
// process. Chosen per job with `--codec raw|snappy|jpeg[:QUALITY[:444|422|420]]`.
//  - raw:    the pixels as they are (4 bytes a pixel, rows packed).
//  - snappy: the plane-delta filter (messaging/Compression.h) then Snappy; lossless. One flag byte
//            first: kSnappyStored (the filtered bytes follow, Snappy did not shrink them) or
//            kSnappyCompressed (a Snappy stream of the filtered bytes follows).
//  - jpeg:   baseline JPEG through TurboJPEG; alpha is dropped (display pixels are opaque) and
//            decodes to 255.
// Pixels are std::uint32_t with R in the low byte (bytes R, G, B, A in memory), as
// wall/image/Image.h holds them.
#include <cstddef>
#include <cstdint>
#include <string>

#include "messaging/Compression.h"

namespace wall::service {

enum class Codec : std::uint8_t { Raw = 0, Snappy = 1, Jpeg = 2 };
enum class ChromaSubsampling : std::uint8_t { S444 = 0, S422 = 1, S420 = 2 };

struct CodecSpec {
  Codec codec = Codec::Raw;
  int jpegQuality = 90;  // 1..100
  ChromaSubsampling subsampling = ChromaSubsampling::S420;
  bool operator==(const CodecSpec&) const = default;
};

// The first byte of a Snappy-coded piece.
constexpr std::uint8_t kSnappyStored = 0;
constexpr std::uint8_t kSnappyCompressed = 1;

// Rectangles the codecs take: sides of 1 to 65535 pixels (JPEG's limit) and at most 1 GiB of
// pixels (the largest message payload, docs/design.md "Hostile input").
constexpr int kMaxCodecSide = 65535;
constexpr std::size_t kMaxCodecPixelBytes = std::size_t{1} << 30;

// "raw", "snappy", "jpeg", "jpeg:QUALITY", "jpeg:QUALITY:444|422|420" (QUALITY 1..100, default
// 90; subsampling default 420). Throws base::Error with a message naming the option (--codec)
// and what is allowed.
CodecSpec parseCodec(const std::string& text);
// "raw", "snappy" or "jpeg:QUALITY:SUBSAMPLING"; parseCodec(codecName(spec)) == spec for every
// spec parseCodec returns (a raw or snappy spec's JPEG fields are not part of its name).
std::string codecName(const CodecSpec& spec);
// A codec byte read from the wire; throws base::Error on an unknown value.
Codec codecFromByte(std::uint8_t value);

// Appends the encoding of the width x height RGBA8 rectangle whose rows are `stride` pixels
// apart to `out`. Thread-safe (TurboJPEG handles and scratch buffers are per thread). Throws
// base::Error on a rectangle outside the limits above, a stride below the width, or a spec
// outside its ranges.
void encodePixels(const CodecSpec& spec, const std::uint32_t* pixels, int width, int height,
                  int stride, messaging::Bytes& out);

// Decodes exactly width x height pixels into dest (rows destStride pixels apart). Never trusts
// the data: malformed, truncated or oversized input, and a JPEG whose header gives another size,
// another colour space or a progressive / multi-scan / arithmetic-coded frame (which libjpeg
// would buffer whole), throw base::Error. Nothing is read or written out of
// bounds, and nothing larger than the rectangle (plus a small constant) is allocated.
// Thread-safe. On an error, dest may hold part of the rectangle.
void decodePixels(Codec codec, const std::byte* data, std::size_t size, int width, int height,
                  std::uint32_t* dest, int destStride);

}  // namespace wall::service
