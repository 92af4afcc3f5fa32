// The plane-delta pre-filter (messaging/Compression.h). For RGBA8 (4 channels) an SSSE3 kernel
// takes 16 pixels at a time: a byte shuffle and a 4x4 transpose split them into four 16-byte
// planes, and the delta is one subtract against the plane shifted by a byte (decode: a prefix sum
// in four shifted adds): the byte loop cost more than Snappy on a piece (docs/benchmarks.md,
// "Measurements behind the code"). tests/messaging/CompressionTest.cpp checks both against the
// definition on random sizes.
#include <cstdint>

#include "messaging/Compression.h"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define DFB_PLANE_DELTA_SSSE3 1
#endif

namespace messaging {
namespace {

using Byte = unsigned char;

// From pixel `from` on, continuing the planes' deltas from the pixel before it.
void encodeScalar(const Byte* pixels, std::size_t count, int channels, Byte* out,
                  std::size_t from) {
  const std::size_t n = static_cast<std::size_t>(channels);
  for (std::size_t c = 0; c < n; ++c) {
    Byte previous = from > 0 ? pixels[(from - 1) * n + c] : 0;
    Byte* plane = out + c * count;
    for (std::size_t i = from; i < count; ++i) {
      const Byte value = pixels[i * n + c];
      plane[i] = static_cast<Byte>(value - previous);
      previous = value;
    }
  }
}

void decodeScalar(const Byte* encoded, std::size_t count, int channels, Byte* out,
                  std::size_t from) {
  const std::size_t n = static_cast<std::size_t>(channels);
  for (std::size_t c = 0; c < n; ++c) {
    Byte previous = from > 0 ? out[(from - 1) * n + c] : 0;
    const Byte* plane = encoded + c * count;
    for (std::size_t i = from; i < count; ++i) {
      previous = static_cast<Byte>(previous + plane[i]);
      out[i * n + c] = previous;
    }
  }
}

#ifdef DFB_PLANE_DELTA_SSSE3

bool haveSsse3() {
  static const bool have = __builtin_cpu_supports("ssse3");
  return have;
}

// Returns how many pixels it did (a multiple of 16); the caller finishes the rest.
__attribute__((target("ssse3"))) std::size_t encodeRgba8Ssse3(const Byte* pixels, std::size_t count,
                                                              Byte* out) {
  // Within 16 bytes (4 pixels): R0 R1 R2 R3 G0 .. A3; the 4x4 byte transpose is its own inverse.
  const __m128i split = _mm_setr_epi8(0, 4, 8, 12, 1, 5, 9, 13, 2, 6, 10, 14, 3, 7, 11, 15);
  __m128i previous[4] = {_mm_setzero_si128(), _mm_setzero_si128(), _mm_setzero_si128(),
                         _mm_setzero_si128()};
  std::size_t i = 0;
  for (; i + 16 <= count; i += 16) {
    const Byte* at = pixels + 4 * i;
    const __m128i a0 =
        _mm_shuffle_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(at)), split);
    const __m128i a1 =
        _mm_shuffle_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(at + 16)), split);
    const __m128i a2 =
        _mm_shuffle_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(at + 32)), split);
    const __m128i a3 =
        _mm_shuffle_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(at + 48)), split);
    const __m128i t0 = _mm_unpacklo_epi32(a0, a1), t1 = _mm_unpackhi_epi32(a0, a1);
    const __m128i t2 = _mm_unpacklo_epi32(a2, a3), t3 = _mm_unpackhi_epi32(a2, a3);
    const __m128i planes[4] = {_mm_unpacklo_epi64(t0, t2), _mm_unpackhi_epi64(t0, t2),
                               _mm_unpacklo_epi64(t1, t3), _mm_unpackhi_epi64(t1, t3)};
    for (std::size_t c = 0; c < 4; ++c) {
      // Each byte minus the one before it; byte 0 minus the previous block's byte 15.
      const __m128i before = _mm_alignr_epi8(planes[c], previous[c], 15);
      _mm_storeu_si128(reinterpret_cast<__m128i*>(out + c * count + i),
                       _mm_sub_epi8(planes[c], before));
      previous[c] = planes[c];
    }
  }
  return i;
}

__attribute__((target("ssse3"))) std::size_t decodeRgba8Ssse3(const Byte* encoded,
                                                              std::size_t count, Byte* out) {
  const __m128i split = _mm_setr_epi8(0, 4, 8, 12, 1, 5, 9, 13, 2, 6, 10, 14, 3, 7, 11, 15);
  const __m128i last = _mm_set1_epi8(15);
  __m128i previous[4] = {_mm_setzero_si128(), _mm_setzero_si128(), _mm_setzero_si128(),
                         _mm_setzero_si128()};
  std::size_t i = 0;
  for (; i + 16 <= count; i += 16) {
    __m128i planes[4];
    for (std::size_t c = 0; c < 4; ++c) {
      __m128i x = _mm_loadu_si128(reinterpret_cast<const __m128i*>(encoded + c * count + i));
      x = _mm_add_epi8(x, _mm_slli_si128(x, 1));  // prefix sum of the 16 deltas
      x = _mm_add_epi8(x, _mm_slli_si128(x, 2));
      x = _mm_add_epi8(x, _mm_slli_si128(x, 4));
      x = _mm_add_epi8(x, _mm_slli_si128(x, 8));
      x = _mm_add_epi8(x, _mm_shuffle_epi8(previous[c], last));  // + the value before the block
      planes[c] = previous[c] = x;
    }
    const __m128i u0 = _mm_unpacklo_epi32(planes[0], planes[1]);
    const __m128i u1 = _mm_unpacklo_epi32(planes[2], planes[3]);
    const __m128i u2 = _mm_unpackhi_epi32(planes[0], planes[1]);
    const __m128i u3 = _mm_unpackhi_epi32(planes[2], planes[3]);
    Byte* at = out + 4 * i;
    _mm_storeu_si128(reinterpret_cast<__m128i*>(at),
                     _mm_shuffle_epi8(_mm_unpacklo_epi64(u0, u1), split));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(at + 16),
                     _mm_shuffle_epi8(_mm_unpackhi_epi64(u0, u1), split));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(at + 32),
                     _mm_shuffle_epi8(_mm_unpacklo_epi64(u2, u3), split));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(at + 48),
                     _mm_shuffle_epi8(_mm_unpackhi_epi64(u2, u3), split));
  }
  return i;
}

#endif

}  // namespace

void planeDeltaEncode(std::span<const std::byte> pixels, int channels, std::byte* out) {
  const auto* in = reinterpret_cast<const Byte*>(pixels.data());
  auto* to = reinterpret_cast<Byte*>(out);
  const std::size_t count = pixels.size() / static_cast<std::size_t>(channels);
  std::size_t done = 0;
#ifdef DFB_PLANE_DELTA_SSSE3
  if (channels == 4 && haveSsse3()) done = encodeRgba8Ssse3(in, count, to);
#endif
  encodeScalar(in, count, channels, to, done);
}

void planeDeltaDecode(std::span<const std::byte> encoded, int channels, std::byte* out) {
  const auto* in = reinterpret_cast<const Byte*>(encoded.data());
  auto* to = reinterpret_cast<Byte*>(out);
  const std::size_t count = encoded.size() / static_cast<std::size_t>(channels);
  std::size_t done = 0;
#ifdef DFB_PLANE_DELTA_SSSE3
  if (channels == 4 && haveSsse3()) done = decodeRgba8Ssse3(in, count, to);
#endif
  decodeScalar(in, count, channels, to, done);
}

void planeDeltaEncode(std::span<const std::byte> pixels, int channels, Bytes& out) {
  out.resize(pixels.size());
  planeDeltaEncode(pixels, channels, out.data());
}

void planeDeltaDecode(std::span<const std::byte> encoded, int channels, Bytes& out) {
  out.resize(encoded.size());
  planeDeltaDecode(encoded, channels, out.data());
}

}  // namespace messaging
