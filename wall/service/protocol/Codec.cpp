#include "wall/service/protocol/Codec.h"

#include <turbojpeg.h>

#include <climits>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "base/Error.h"

namespace wall::service {
namespace {

const char* const kAllowed =
    "allowed: raw, snappy, jpeg, jpeg:QUALITY or jpeg:QUALITY:444|422|420, QUALITY 1 to 100";

base::Error badCodec(const std::string& text, const std::string& why) {
  return base::Error("--codec '" + text + "': " + why + " (" + kAllowed + ")");
}

std::string sizeText(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// The rectangle's pixel bytes, after checking it against the codecs' limits; `stride` is the
// distance between its rows in the caller's buffer.
std::size_t checkedPixelBytes(const char* what, int width, int height, int stride) {
  if (width < 1 || height < 1 || width > kMaxCodecSide || height > kMaxCodecSide ||
      stride < width || stride > INT_MAX / 4 ||
      4 * static_cast<std::size_t>(width) * static_cast<std::size_t>(height) > kMaxCodecPixelBytes)
    throw base::Error(
        std::string(what) + ": a " + sizeText(width, height) + " rectangle with rows " +
        std::to_string(stride) + " pixels apart is outside the codecs' limits (sides 1 to " +
        std::to_string(kMaxCodecSide) + ", rows at least as far apart as the width, at most " +
        std::to_string(kMaxCodecPixelBytes) + " pixel bytes)");
  return 4 * static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
}

const std::byte* row(const std::uint32_t* pixels, int stride, int y) {
  return reinterpret_cast<const std::byte*>(pixels + static_cast<std::size_t>(y) *
                                                         static_cast<std::size_t>(stride));
}

// The rectangle's pixels in one run: its own memory when its rows are packed, else its rows
// gathered into `scratch`.
const std::byte* packedPixels(const std::uint32_t* pixels, int width, int height, int stride,
                              messaging::Bytes& scratch) {
  if (stride == width) return reinterpret_cast<const std::byte*>(pixels);
  const std::size_t rowBytes = 4 * static_cast<std::size_t>(width);
  scratch.resize(rowBytes * static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y)
    std::memcpy(scratch.data() + static_cast<std::size_t>(y) * rowBytes, row(pixels, stride, y),
                rowBytes);
  return scratch.data();
}

// Copies packed rows to a destination whose rows are `destStride` pixels apart.
void unpackRows(const std::byte* packed, int width, int height, std::uint32_t* dest,
                int destStride) {
  const std::size_t rowBytes = 4 * static_cast<std::size_t>(width);
  for (int y = 0; y < height; ++y)
    std::memcpy(dest + static_cast<std::size_t>(y) * static_cast<std::size_t>(destStride),
                packed + static_cast<std::size_t>(y) * rowBytes, rowBytes);
}

void append(messaging::Bytes& out, const std::byte* bytes, std::size_t size) {
  out.insert(out.end(), bytes, bytes + size);
}

// ---- Snappy: the plane-delta filter, then Snappy when it shrinks the filtered bytes. ----

void encodeSnappy(const std::uint32_t* pixels, int width, int height, int stride,
                  std::size_t pixelBytes, messaging::Bytes& out) {
  thread_local messaging::Bytes gathered, filtered, compressed;
  const std::byte* run = packedPixels(pixels, width, height, stride, gathered);
  filtered.resize(pixelBytes);
  messaging::planeDeltaEncode(std::span<const std::byte>(run, pixelBytes), 4, filtered.data());
  const bool shrank = messaging::compressIfSmaller(filtered, compressed);
  const messaging::Bytes& body = shrank ? compressed : filtered;
  out.reserve(out.size() + 1 + body.size());
  out.push_back(static_cast<std::byte>(shrank ? kSnappyCompressed : kSnappyStored));
  append(out, body.data(), body.size());
}

void decodeSnappy(const std::byte* data, std::size_t size, int width, int height,
                  std::size_t pixelBytes, std::uint32_t* dest, int destStride) {
  if (size < 1) throw base::Error("snappy piece of " + sizeText(width, height) + " is empty");
  const auto flag = static_cast<std::uint8_t>(data[0]);
  const std::span<const std::byte> body(data + 1, size - 1);
  thread_local messaging::Bytes decompressed, unfiltered;
  const std::byte* filtered = nullptr;
  if (flag == kSnappyStored) {
    if (body.size() != pixelBytes)
      throw base::Error("snappy piece of " + sizeText(width, height) + " stores " +
                        std::to_string(body.size()) + " bytes, its rectangle needs " +
                        std::to_string(pixelBytes));
    filtered = body.data();
  } else if (flag == kSnappyCompressed) {
    try {  // checks the announced size against pixelBytes before it allocates
      messaging::decompress(body, pixelBytes, decompressed);
    } catch (const base::Error& e) {
      throw base::Error("snappy piece of " + sizeText(width, height) + ": " + e.what());
    }
    filtered = decompressed.data();
  } else {
    throw base::Error("snappy piece of " + sizeText(width, height) + " has an unknown flag byte " +
                      std::to_string(flag));
  }
  const std::span<const std::byte> encoded(filtered, pixelBytes);
  if (destStride == width) {
    messaging::planeDeltaDecode(encoded, 4, reinterpret_cast<std::byte*>(dest));
    return;
  }
  unfiltered.resize(pixelBytes);
  messaging::planeDeltaDecode(encoded, 4, unfiltered.data());
  unpackRows(unfiltered.data(), width, height, dest, destStride);
}

// ---- JPEG through TurboJPEG: one compressor and one decompressor per thread. ----

// A thread's TurboJPEG instance, created when first used and again after a failure:
// tjDecompressHeader3 (libjpeg-turbo 2.1) returns from an error without aborting the
// decompression it started, and every later call on that instance then failed ("Bogus marker
// length" on valid JPEGs), so one corrupt piece would have broken the thread's decoding for good.
class TurboJpegInstance {
 public:
  explicit TurboJpegInstance(tjhandle (*init)(), const char* what) : init_(init), what_(what) {}
  ~TurboJpegInstance() { reset(); }
  TurboJpegInstance(const TurboJpegInstance&) = delete;
  TurboJpegInstance& operator=(const TurboJpegInstance&) = delete;

  tjhandle get() {
    if (!handle_) handle_ = init_();
    if (!handle_)
      throw base::Error(std::string("TurboJPEG could not create a ") + what_ + ": " +
                        message(nullptr));
    return handle_;
  }
  // The instance's error message; the instance is dropped, the next get() makes a fresh one.
  std::string failure() {
    std::string text = message(handle_);
    reset();
    return text;
  }

 private:
  static std::string message(tjhandle handle) {
    const char* text = tjGetErrorStr2(handle);
    return text ? text : "unknown TurboJPEG error";
  }
  void reset() {
    if (handle_) tjDestroy(handle_);
    handle_ = nullptr;
  }

  tjhandle (*init_)();
  const char* what_;
  tjhandle handle_ = nullptr;
};

TurboJpegInstance& compressor() {
  thread_local TurboJpegInstance instance(tjInitCompress, "compressor");
  return instance;
}

TurboJpegInstance& decompressor() {
  thread_local TurboJpegInstance instance(tjInitDecompress, "decompressor");
  return instance;
}

int turboJpegSubsampling(ChromaSubsampling subsampling) {
  switch (subsampling) {
    case ChromaSubsampling::S444:
      return TJSAMP_444;
    case ChromaSubsampling::S422:
      return TJSAMP_422;
    case ChromaSubsampling::S420:
      return TJSAMP_420;
  }
  throw base::Error("unknown chroma subsampling " +
                    std::to_string(static_cast<unsigned>(subsampling)));
}

void encodeJpeg(const CodecSpec& spec, const std::uint32_t* pixels, int width, int height,
                int stride, messaging::Bytes& out) {
  if (spec.jpegQuality < 1 || spec.jpegQuality > 100)
    throw base::Error("JPEG quality " + std::to_string(spec.jpegQuality) + " is outside 1 to 100");
  const int subsampling = turboJpegSubsampling(spec.subsampling);
  // The worst case for the rectangle, so TurboJPEG never reallocates this thread's buffer.
  const unsigned long bound = tjBufSize(width, height, subsampling);
  if (bound == static_cast<unsigned long>(-1))
    throw base::Error("TurboJPEG: no size bound for a " + sizeText(width, height) + " image");
  thread_local std::vector<unsigned char> buffer;
  if (buffer.size() < bound) buffer.resize(bound);
  unsigned char* jpeg = buffer.data();
  unsigned long jpegSize = bound;
  TurboJpegInstance& instance = compressor();
  if (tjCompress2(instance.get(), reinterpret_cast<const unsigned char*>(pixels), width, 4 * stride,
                  height, TJPF_RGBA, &jpeg, &jpegSize, subsampling, spec.jpegQuality,
                  TJFLAG_NOREALLOC) != 0)
    throw base::Error("TurboJPEG could not compress a " + sizeText(width, height) +
                      " piece: " + instance.failure());
  append(out, reinterpret_cast<const std::byte*>(jpeg), jpegSize);
}

bool isStartOfFrame(unsigned marker) {  // SOF0..SOF15 but DHT (C4), JPG (C8) and DAC (CC)
  return marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
}

// Walks the markers up to the first scan and refuses what libjpeg would decode through a
// whole-image coefficient buffer (progressive or arithmetic-coded frames, or a first scan that
// does not hold every component: several times the rectangle's memory) or could only warn about
// (bytes between markers). A baseline, interleaved, Huffman-coded frame, which is what
// encodePixels writes, decodes one row of blocks at a time.
void checkJpegStructure(const unsigned char* data, std::size_t size, int width, int height) {
  const auto fail = [&](const std::string& why) {
    return base::Error("jpeg piece of " + sizeText(width, height) + " (" + std::to_string(size) +
                       " bytes): " + why);
  };
  if (size < 4 || data[0] != 0xFF || data[1] != 0xD8) throw fail("not a JPEG (no SOI marker)");
  std::size_t at = 2;
  unsigned frameComponents = 0;
  for (;;) {
    if (at >= size) throw fail("truncated before its first scan");
    if (data[at] != 0xFF) throw fail("stray bytes between markers");
    while (at < size && data[at] == 0xFF) ++at;  // fill bytes
    if (at >= size) throw fail("truncated before its first scan");
    const unsigned marker = data[at++];
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;  // no length
    if (marker == 0x00 || marker == 0xD8 || marker == 0xD9)
      throw fail("unexpected marker before its first scan");
    if (size - at < 2) throw fail("truncated in a marker segment");
    const std::size_t length = std::size_t{data[at]} << 8 | data[at + 1];
    if (length < 2 || length > size - at) throw fail("a marker segment overruns the data");
    const unsigned char* segment = data + at + 2;
    const std::size_t segmentSize = length - 2;
    if (isStartOfFrame(marker)) {
      if (marker != 0xC0 && marker != 0xC1)
        throw fail("not a baseline, Huffman-coded JPEG (SOF marker 0x" +
                   std::string(1, "0123456789ABCDEF"[marker >> 4]) +
                   std::string(1, "0123456789ABCDEF"[marker & 15]) + ")");
      if (frameComponents != 0) throw fail("two frame headers");
      if (segmentSize < 6) throw fail("frame header too short");
      frameComponents = segment[5];
      if (frameComponents == 0) throw fail("a frame with no components");
    } else if (marker == 0xDA) {
      if (frameComponents == 0) throw fail("a scan before the frame header");
      if (segmentSize < 1 || segment[0] != frameComponents)
        throw fail("its first scan does not hold every component (multi-scan JPEG)");
      return;
    }
    at += length;
  }
}

void decodeJpeg(const std::byte* data, std::size_t size, int width, int height, std::uint32_t* dest,
                int destStride) {
  const auto* jpeg = reinterpret_cast<const unsigned char*>(data);
  checkJpegStructure(jpeg, size, width, height);
  TurboJpegInstance& instance = decompressor();
  int jpegWidth = 0, jpegHeight = 0, subsampling = 0, colorspace = 0;
  if (tjDecompressHeader3(instance.get(), jpeg, size, &jpegWidth, &jpegHeight, &subsampling,
                          &colorspace) != 0)
    throw base::Error("jpeg piece of " + sizeText(width, height) +
                      ": bad header: " + instance.failure());
  if (jpegWidth != width || jpegHeight != height)
    throw base::Error("jpeg piece of " + sizeText(width, height) + " holds a " +
                      sizeText(jpegWidth, jpegHeight) + " image");
  if (colorspace != TJCS_YCbCr) {
    const char* const names[] = {"RGB", "YCbCr", "greyscale", "CMYK", "YCCK"};
    throw base::Error(
        "jpeg piece of " + sizeText(width, height) + " is " +
        (colorspace >= 0 && colorspace < 5 ? names[colorspace] : "of an unknown colour space") +
        ", not YCbCr");
  }
  // Warnings (a truncated or corrupt stream, which libjpeg would fill in with grey) are errors.
  if (tjDecompress2(instance.get(), jpeg, size, reinterpret_cast<unsigned char*>(dest), width,
                    4 * destStride, height, TJPF_RGBA,
                    TJFLAG_STOPONWARNING | TJFLAG_LIMITSCANS) != 0)
    throw base::Error("jpeg piece of " + sizeText(width, height) + ": " + instance.failure());
}

}  // namespace

CodecSpec parseCodec(const std::string& text) {
  if (text == "raw") return CodecSpec{Codec::Raw};
  if (text == "snappy") return CodecSpec{Codec::Snappy};
  std::vector<std::string_view> parts;
  for (std::size_t from = 0;;) {
    const std::size_t colon = text.find(':', from);
    parts.emplace_back(std::string_view(text).substr(from, colon - from));
    if (colon == std::string::npos) break;
    from = colon + 1;
  }
  if (parts[0] != "jpeg") throw badCodec(text, "unknown codec");
  if (parts.size() > 3) throw badCodec(text, "too many fields");
  CodecSpec spec{Codec::Jpeg};
  if (parts.size() >= 2) {
    const std::string_view quality = parts[1];
    if (quality.empty() || quality.size() > 3 ||
        quality.find_first_not_of("0123456789") != std::string_view::npos)
      throw badCodec(text, "the JPEG quality must be a number from 1 to 100");
    int value = 0;
    for (const char digit : quality) value = 10 * value + (digit - '0');
    if (value < 1 || value > 100)
      throw badCodec(text, "the JPEG quality must be a number from 1 to 100");
    spec.jpegQuality = value;
  }
  if (parts.size() == 3) {
    if (parts[2] == "444")
      spec.subsampling = ChromaSubsampling::S444;
    else if (parts[2] == "422")
      spec.subsampling = ChromaSubsampling::S422;
    else if (parts[2] == "420")
      spec.subsampling = ChromaSubsampling::S420;
    else
      throw badCodec(text, "the chroma subsampling must be 444, 422 or 420");
  }
  return spec;
}

std::string codecName(const CodecSpec& spec) {
  switch (spec.codec) {
    case Codec::Raw:
      return "raw";
    case Codec::Snappy:
      return "snappy";
    case Codec::Jpeg:
      break;
  }
  if (spec.codec != Codec::Jpeg)
    throw base::Error("unknown codec " + std::to_string(static_cast<unsigned>(spec.codec)));
  const char* subsampling = spec.subsampling == ChromaSubsampling::S444   ? "444"
                            : spec.subsampling == ChromaSubsampling::S422 ? "422"
                                                                          : "420";
  return "jpeg:" + std::to_string(spec.jpegQuality) + ":" + subsampling;
}

Codec codecFromByte(std::uint8_t value) {
  if (value > static_cast<std::uint8_t>(Codec::Jpeg))
    throw base::Error("unknown codec " + std::to_string(value) + " (0 raw, 1 snappy, 2 jpeg)");
  return static_cast<Codec>(value);
}

void encodePixels(const CodecSpec& spec, const std::uint32_t* pixels, int width, int height,
                  int stride, messaging::Bytes& out) {
  const std::size_t pixelBytes = checkedPixelBytes("encodePixels", width, height, stride);
  switch (spec.codec) {
    case Codec::Raw: {
      const std::size_t rowBytes = 4 * static_cast<std::size_t>(width);
      out.reserve(out.size() + pixelBytes);
      for (int y = 0; y < height; ++y) append(out, row(pixels, stride, y), rowBytes);
      return;
    }
    case Codec::Snappy:
      encodeSnappy(pixels, width, height, stride, pixelBytes, out);
      return;
    case Codec::Jpeg:
      encodeJpeg(spec, pixels, width, height, stride, out);
      return;
  }
  throw base::Error("encodePixels: unknown codec " +
                    std::to_string(static_cast<unsigned>(spec.codec)));
}

void decodePixels(Codec codec, const std::byte* data, std::size_t size, int width, int height,
                  std::uint32_t* dest, int destStride) {
  const std::size_t pixelBytes = checkedPixelBytes("decodePixels", width, height, destStride);
  if (size > 0 && !data) throw base::Error("decodePixels: no data");
  switch (codec) {
    case Codec::Raw:
      if (size != pixelBytes)
        throw base::Error("raw piece of " + sizeText(width, height) + " has " +
                          std::to_string(size) + " bytes, its rectangle needs " +
                          std::to_string(pixelBytes));
      unpackRows(data, width, height, dest, destStride);
      return;
    case Codec::Snappy:
      decodeSnappy(data, size, width, height, pixelBytes, dest, destStride);
      return;
    case Codec::Jpeg:
      decodeJpeg(data, size, width, height, dest, destStride);
      return;
  }
  throw base::Error("decodePixels: unknown codec " + std::to_string(static_cast<unsigned>(codec)));
}

}  // namespace wall::service
