#include "renderers/scivis/io/formats/StoredArray.h"

#include <bzlib.h>
#include <fcntl.h>
#include <lz4.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "base/Error.h"

namespace renderers::scivis {
namespace {

thread_local std::uint64_t bytesRead = 0;

class File {
 public:
  explicit File(const std::string& path) : path_(path), fd_(::open(path.c_str(), O_RDONLY)) {
    if (fd_ < 0)
      throw base::Error(path + ": cannot open the volume data file (" + std::strerror(errno) + ")");
  }
  ~File() { ::close(fd_); }
  File(const File&) = delete;
  File& operator=(const File&) = delete;
  std::uint64_t size() const { return static_cast<std::uint64_t>(status().st_size); }
  // Which file, in which version: equal for the same unchanged file.
  std::array<std::int64_t, 5> identity() const {
    const struct stat st = status();
    return {static_cast<std::int64_t>(st.st_dev), static_cast<std::int64_t>(st.st_ino),
            static_cast<std::int64_t>(st.st_size), static_cast<std::int64_t>(st.st_mtim.tv_sec),
            static_cast<std::int64_t>(st.st_mtim.tv_nsec)};
  }
  // Up to `bytes` bytes at `offset` (fewer only at the end of the file).
  std::size_t readSome(std::uint64_t offset, std::byte* to, std::size_t bytes) const {
    std::size_t done = 0;
    while (done < bytes) {
      const ssize_t n = ::pread(fd_, to + done, bytes - done, static_cast<off_t>(offset + done));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0)
        throw base::Error(path_ + ": read failed at byte " + std::to_string(offset + done) + ": " +
                          std::strerror(errno));
      if (n == 0) break;
      done += static_cast<std::size_t>(n);
    }
    bytesRead += done;
    return done;
  }
  void read(std::uint64_t offset, std::byte* to, std::size_t bytes) const {
    if (readSome(offset, to, bytes) != bytes)
      throw base::Error(path_ + ": the file ends before byte " + std::to_string(offset + bytes) +
                        " of the volume data");
  }

 private:
  struct stat status() const {
    struct stat st {};
    if (::fstat(fd_, &st) != 0) throw base::Error(path_ + ": cannot stat: " + std::strerror(errno));
    return st;
  }

  std::string path_;
  int fd_;
};

// Decoded bytes in order: an inflated or bunzipped stream, or text turned into voxels. Only as
// much input is decoded as the reads ask for.
class ByteStream {
 public:
  virtual ~ByteStream() = default;
  // The next `bytes` bytes into `to`, or dropped when `to` is null.
  void read(std::byte* to, std::uint64_t bytes) {
    if (!to) return skip(bytes);
    while (bytes > 0) {
      const std::size_t got =
          readSome(to, static_cast<std::size_t>(std::min<std::uint64_t>(bytes, 1u << 30)));
      to += got;
      bytes -= got;
      produced_ += got;
    }
  }
  // A copy of the stream where it is now, to resume from later; null when the decoder cannot be
  // copied (then a read going back starts over).
  virtual std::unique_ptr<ByteStream> snapshot() const { return nullptr; }

 protected:
  // Drops the next `bytes` bytes (decoding them, unless the stream can jump).
  virtual void skip(std::uint64_t bytes) {
    std::byte scratch[16384];
    while (bytes > 0) {
      const std::size_t got = readSome(
          scratch, static_cast<std::size_t>(std::min<std::uint64_t>(bytes, sizeof scratch)));
      bytes -= got;
      produced_ += got;
    }
  }
  ByteStream(const File& file, std::string path, std::uint64_t offset)
      : file_(file), path_(std::move(path)), offset_(offset) {}
  // Between 1 and `bytes` decoded bytes into `to`; throws at the end of the data.
  virtual std::size_t readSome(std::byte* to, std::size_t bytes) = 0;
  // The next chunk of the file's bytes (empty at its end).
  std::size_t fill(std::byte* to, std::size_t bytes) {
    const std::size_t n = file_.readSome(offset_, to, bytes);
    offset_ += n;
    return n;
  }
  [[noreturn]] void ended(const char* what = "stream") const {
    throw base::Error(path_ + ": the " + what + " ends after " + std::to_string(produced_) +
                      " bytes, before the voxels the header calls for");
  }

  const File& file_;
  std::string path_;
  std::uint64_t offset_;
  std::uint64_t produced_ = 0;
};

// A zlib or gzip stream (concatenated gzip members too).
class InflateStream final : public ByteStream {
 public:
  InflateStream(const File& file, const std::string& path, std::uint64_t offset)
      : ByteStream(file, path, offset), in_(kChunk) {
    if (inflateInit2(&z_, 15 + 32) != Z_OK) throw base::Error(path + ": cannot start zlib");
  }
  ~InflateStream() override { inflateEnd(&z_); }
  InflateStream(const InflateStream&) = delete;
  InflateStream& operator=(const InflateStream&) = delete;

  std::unique_ptr<ByteStream> snapshot() const override {
    auto copy = std::make_unique<InflateStream>(file_, path_, offset_);
    inflateEnd(&copy->z_);
    if (inflateCopy(&copy->z_, const_cast<z_stream*>(&z_)) != Z_OK)
      throw base::Error(path_ + ": cannot copy the zlib stream");
    copy->in_ = in_;
    if (z_.next_in)
      copy->z_.next_in = reinterpret_cast<Bytef*>(copy->in_.data()) +
                         (z_.next_in - reinterpret_cast<const Bytef*>(in_.data()));
    copy->produced_ = produced_;
    return copy;
  }

 private:
  static constexpr std::size_t kChunk = 1 << 16;

  std::size_t readSome(std::byte* to, std::size_t bytes) override {
    z_.next_out = reinterpret_cast<Bytef*>(to);
    z_.avail_out = static_cast<uInt>(bytes);
    while (z_.avail_out == bytes) {
      if (z_.avail_in == 0) {
        const std::size_t n = fill(in_.data(), in_.size());
        if (n == 0) ended("compressed stream");
        z_.next_in = reinterpret_cast<Bytef*>(in_.data());
        z_.avail_in = static_cast<uInt>(n);
      }
      const int rc = inflate(&z_, Z_NO_FLUSH);
      if (rc == Z_STREAM_END) {
        // Another gzip member may follow; anything else is the end of the data.
        if (z_.avail_out != bytes) break;
        if (inflateReset(&z_) != Z_OK) ended("compressed stream");
        continue;
      }
      if (rc != Z_OK && rc != Z_BUF_ERROR)
        throw base::Error(path_ + ": compressed volume data is corrupt after " +
                          std::to_string(produced_) + " inflated bytes (" +
                          (z_.msg ? z_.msg : "zlib error " + std::to_string(rc)) + ")");
    }
    return bytes - z_.avail_out;
  }

  std::vector<std::byte> in_;
  z_stream z_{};
};

// A bzip2 stream (concatenated ones too, as pbzip2 writes).
class Bunzip2Stream final : public ByteStream {
 public:
  Bunzip2Stream(const File& file, const std::string& path, std::uint64_t offset)
      : ByteStream(file, path, offset), in_(kChunk) {
    if (BZ2_bzDecompressInit(&z_, 0, 0) != BZ_OK) throw base::Error(path + ": cannot start bzip2");
  }
  ~Bunzip2Stream() override { BZ2_bzDecompressEnd(&z_); }
  Bunzip2Stream(const Bunzip2Stream&) = delete;
  Bunzip2Stream& operator=(const Bunzip2Stream&) = delete;

 private:
  static constexpr std::size_t kChunk = 1 << 16;

  std::size_t readSome(std::byte* to, std::size_t bytes) override {
    z_.next_out = reinterpret_cast<char*>(to);
    z_.avail_out = static_cast<unsigned>(bytes);
    while (z_.avail_out == bytes) {
      if (z_.avail_in == 0) {
        const std::size_t n = fill(in_.data(), in_.size());
        if (n == 0) ended("bzip2 stream");
        z_.next_in = reinterpret_cast<char*>(in_.data());
        z_.avail_in = static_cast<unsigned>(n);
      }
      const int rc = BZ2_bzDecompress(&z_);
      if (rc == BZ_STREAM_END) {
        if (z_.avail_out != bytes) break;
        // Another stream may follow: start over on the input that is left.
        char* next = z_.next_in;
        const unsigned left = z_.avail_in;
        BZ2_bzDecompressEnd(&z_);
        z_ = bz_stream{};
        if (BZ2_bzDecompressInit(&z_, 0, 0) != BZ_OK) ended("bzip2 stream");
        z_.next_in = next, z_.avail_in = left;
        z_.next_out = reinterpret_cast<char*>(to), z_.avail_out = static_cast<unsigned>(bytes);
        continue;
      }
      if (rc != BZ_OK)
        throw base::Error(path_ + ": bzip2 volume data is corrupt after " +
                          std::to_string(produced_) + " decoded bytes (bzip2 error " +
                          std::to_string(rc) + ")");
    }
    return bytes - z_.avail_out;
  }

  std::vector<std::byte> in_;
  bz_stream z_{};
};

// More of the file's bytes (fewer at its end, none past it).
using ByteStreamFill = std::function<std::size_t(std::byte*, std::size_t)>;

// Text read a character at a time from the file, buffered.
class TextInput {
 public:
  int next(ByteStreamFill fill) {
    if (at_ == size_) {
      size_ = fill(buffer_.data(), buffer_.size());
      at_ = 0;
      if (size_ == 0) return -1;
    }
    return static_cast<unsigned char>(buffer_[at_++]);
  }

 private:
  std::vector<std::byte> buffer_ = std::vector<std::byte>(1 << 16);
  std::size_t at_ = 0, size_ = 0;
};

// A character of text for a message: itself when printable, else its code.
std::string shown(int c) {
  if (c >= 32 && c < 127) return "'" + std::string(1, static_cast<char>(c)) + "'";
  char code[16];
  std::snprintf(code, sizeof code, "byte 0x%02x", c & 0xff);
  return code;
}

// Text for a message: bytes that do not print as '?'.
std::string printable(std::string text) {
  for (char& c : text)
    if (c < 32 || c >= 127) c = '?';
  return text;
}

// NRRD's hex encoding: two hex digits a byte, whitespace anywhere between bytes.
class HexStream final : public ByteStream {
 public:
  HexStream(const File& file, const std::string& path, std::uint64_t offset)
      : ByteStream(file, path, offset) {}

 private:
  std::size_t readSome(std::byte* to, std::size_t bytes) override {
    const ByteStreamFill more = [this](std::byte* b, std::size_t n) { return fill(b, n); };
    for (std::size_t n = 0; n < bytes; ++n) {
      int digits[2];
      for (int& d : digits) {
        int c;
        do c = text_.next(more);
        while (c == ' ' || c == '\n' || c == '\r' || c == '\t');
        if (c < 0) {
          produced_ += n;
          ended("hex data");
        }
        d = c >= '0' && c <= '9'   ? c - '0'
            : c >= 'a' && c <= 'f' ? c - 'a' + 10
            : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                   : -1;
        if (d < 0)
          throw base::Error(path_ + ": hex volume data has " + shown(c) + " after " +
                            std::to_string(produced_ + n) + " bytes, not a hex digit");
      }
      to[n] = static_cast<std::byte>(digits[0] * 16 + digits[1]);
    }
    return bytes;
  }

  TextInput text_;
};

// NRRD's ascii (text) encoding: numbers separated by whitespace or commas, each turned into one
// voxel of the stored type in this machine's byte order.
class AsciiStream final : public ByteStream {
 public:
  AsciiStream(const File& file, const std::string& path, std::uint64_t offset, FileType type)
      : ByteStream(file, path, offset), type_(type), width_(fileTypeBytes(type)) {}

 private:
  std::size_t readSome(std::byte* to, std::size_t bytes) override {
    std::size_t n = 0;
    while (n < bytes) {
      if (pendingAt_ == pending_.size()) {
        if (n > 0) return n;  // what is decoded so far counts before the next value is read
        nextValue();
      }
      const std::size_t take = std::min(bytes - n, pending_.size() - pendingAt_);
      std::memcpy(to + n, pending_.data() + pendingAt_, take);
      pendingAt_ += take, n += take;
    }
    return n;
  }

  void nextValue() {
    const ByteStreamFill more = [this](std::byte* b, std::size_t k) { return fill(b, k); };
    std::string token;
    int c;
    do c = text_.next(more);
    while (c == ' ' || c == '\n' || c == '\r' || c == '\t' || c == ',');
    while (c >= 0 && c != ' ' && c != '\n' && c != '\r' && c != '\t' && c != ',') {
      if (token.size() > 64) break;
      token.push_back(static_cast<char>(c));
      c = text_.next(more);
    }
    if (token.empty()) ended("text data");
    double v = 0;
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
    const bool integral = type_ != FileType::Float32 && type_ != FileType::Float64;
    double lo = 0, hi = 0;
    if (integral) limits(lo, hi);
    if (ec != std::errc() || end != token.data() + token.size() || std::isnan(v) ||
        (integral && (v != std::floor(v) || v < lo || v > hi)))
      throw base::Error(path_ + ": text volume data: value " + std::to_string(values_ + 1) + ", '" +
                        printable(token.substr(0, 40)) + "', is not " +
                        (integral ? "an integer that fits " : "a number for ") +
                        fileTypeName(type_));
    ++values_;
    pending_.resize(width_);
    pendingAt_ = 0;
    store(v);
  }

  void limits(double& lo, double& hi) const {
    switch (type_) {
      case FileType::Int8:
        lo = -128, hi = 127;
        break;
      case FileType::UInt8:
        lo = 0, hi = 255;
        break;
      case FileType::Int16:
        lo = -32768, hi = 32767;
        break;
      case FileType::UInt16:
        lo = 0, hi = 65535;
        break;
      case FileType::Int32:
        lo = -2147483648.0, hi = 2147483647.0;
        break;
      default:
        lo = 0, hi = 4294967295.0;
    }
  }

  void store(double v) {
    auto put = [&](auto x) { std::memcpy(pending_.data(), &x, sizeof x); };
    switch (type_) {
      case FileType::Int8:
        return put(static_cast<std::int8_t>(v));
      case FileType::UInt8:
        return put(static_cast<std::uint8_t>(v));
      case FileType::Int16:
        return put(static_cast<std::int16_t>(v));
      case FileType::UInt16:
        return put(static_cast<std::uint16_t>(v));
      case FileType::Int32:
        return put(static_cast<std::int32_t>(v));
      case FileType::UInt32:
        return put(static_cast<std::uint32_t>(v));
      case FileType::Float32:
        return put(static_cast<float>(v));
      case FileType::Float64:
        return put(v);
    }
  }

  FileType type_;
  std::size_t width_;
  TextInput text_;
  std::vector<std::byte> pending_;
  std::size_t pendingAt_ = 0;
  std::uint64_t values_ = 0;
};

// Base64 text read at any decoded byte: the text is one unbroken run of base64 from `start`
// (as VTK writes it), so decoded byte p lies in the 4 characters at start + 4 (p / 3).
void base64Read(const File& file, const std::string& path, std::uint64_t start,
                std::uint64_t position, std::byte* to, std::size_t bytes) {
  // Each character's 6 bits; 64 for the '=' padding, -1 for anything else.
  static constexpr auto kValue = [] {
    std::array<signed char, 128> v{};
    v.fill(-1);
    const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (int i = 0; i < 64; ++i)
      v[static_cast<unsigned char>(alphabet[i])] = static_cast<signed char>(i);
    v['='] = 64;
    return v;
  }();
  while (bytes > 0) {
    const std::uint64_t group = position / 3;
    const std::size_t skipInGroup = static_cast<std::size_t>(position % 3);
    const std::size_t groups = std::min<std::size_t>((skipInGroup + bytes + 2) / 3, 4096);
    char text[4 * 4096];
    const std::size_t got =
        file.readSome(start + 4 * group, reinterpret_cast<std::byte*>(text), 4 * groups);
    if (got < 4 * groups)
      throw base::Error(path + ": the base64 data ends after " + std::to_string(position) +
                        " decoded bytes, before the voxels the header calls for");
    for (std::size_t g = 0; g < groups && bytes > 0; ++g) {
      int v[4];
      for (int c = 0; c < 4; ++c) {
        const auto ch = static_cast<unsigned char>(text[4 * g + c]);
        v[c] = ch < 128 ? kValue[ch] : -1;
        if (v[c] < 0)
          throw base::Error(path + ": base64 data broken by '" + std::string(1, text[4 * g + c]) +
                            "' at byte " + std::to_string(start + 4 * (group + g) + c) +
                            " (dfbwall reads base64 written without line breaks, as VTK does)");
        if (v[c] == 64) v[c] = 0;  // '=' padding
      }
      const std::byte decoded[3] = {static_cast<std::byte>((v[0] << 2) | (v[1] >> 4)),
                                    static_cast<std::byte>(((v[1] & 15) << 4) | (v[2] >> 2)),
                                    static_cast<std::byte>(((v[2] & 3) << 6) | v[3])};
      const std::size_t from = g == 0 ? skipInGroup : 0;
      const std::size_t take = std::min<std::size_t>(3 - from, bytes);
      std::memcpy(to, decoded + from, take);
      to += take, bytes -= take, position += take;
    }
  }
}

// VTK's compressed arrays: a header (block count, block size, last block's size, each block's
// compressed size; UInt32 or UInt64 in the file's byte order), then the blocks, each compressed
// on its own (zlib or LZ4), raw or as base64 (the header then being base64 of its own). A skip
// jumps whole blocks without decompressing them.
class VtkBlockStream final : public ByteStream {
 public:
  VtkBlockStream(const File& file, const std::string& path, std::uint64_t offset,
                 const StoredArray& a)
      : ByteStream(file, path, offset), lz4_(a.encoding == Encoding::Lz4Blocks), base64_(a.base64) {
    const int width = a.blockHeaderBytes;
    const auto number = [&](const std::byte* p) {
      std::uint64_t v = 0;
      for (int b = 0; b < width; ++b) {
        const int shift = 8 * (a.bigEndian ? width - 1 - b : b);
        v |= static_cast<std::uint64_t>(p[b]) << shift;
      }
      return v;
    };
    std::byte first[8];
    readEncoded(0, first, static_cast<std::size_t>(width), true);
    const std::uint64_t blocks = number(first);
    if (blocks > (1u << 24))
      throw base::Error(path + ": the compressed array's header claims " + std::to_string(blocks) +
                        " blocks, more than dfbwall believes (16777216)");
    const std::size_t headerBytes = static_cast<std::size_t>((3 + blocks) * width);
    if (headerBytes > file.size() - std::min(file.size(), offset))
      throw base::Error(path + ": the compressed array's header claims " + std::to_string(blocks) +
                        " blocks, more than the file holds");
    std::vector<std::byte> header(headerBytes);
    readEncoded(0, header.data(), headerBytes, true);
    blockSize_ = number(header.data() + width);
    lastSize_ = number(header.data() + 2 * width);
    if (lastSize_ == 0) lastSize_ = blockSize_;
    if (blockSize_ == 0 || blockSize_ > kMaxBlock || lastSize_ > blockSize_)
      throw base::Error(path + ": the compressed array's header claims blocks of " +
                        std::to_string(blockSize_) + " bytes (the last " +
                        std::to_string(lastSize_) + "); dfbwall reads blocks up to " +
                        std::to_string(kMaxBlock));
    std::uint64_t at = 0;
    for (std::uint64_t b = 0; b < blocks; ++b) {
      const std::uint64_t size = number(header.data() + (3 + b) * width);
      if (size > 2 * kMaxBlock)
        throw base::Error(path + ": block " + std::to_string(b) + " claims " +
                          std::to_string(size) + " compressed bytes");
      starts_.push_back(at);
      at += size;
    }
    starts_.push_back(at);
    if (at > file.size())
      throw base::Error(path + ": the compressed array's header claims " + std::to_string(at) +
                        " bytes of blocks, more than the file's " + std::to_string(file.size()));
    // Base64: the blocks' text starts after the header's (padded to whole groups).
    dataStart_ = base64_ ? offset + 4 * ((headerBytes + 2) / 3) : offset + headerBytes;
  }

 private:
  static constexpr std::uint64_t kMaxBlock = 1u << 26;

  void readEncoded(std::uint64_t position, std::byte* to, std::size_t bytes, bool header) {
    const std::uint64_t start = header ? offset_ : dataStart_;
    if (base64_) return base64Read(file_, path_, start, position, to, bytes);
    if (file_.readSome(start + position, to, bytes) != bytes)
      throw base::Error(path_ + ": the compressed array ends before byte " +
                        std::to_string(start + position + bytes) + " its header calls for");
  }

  std::size_t sizeOf(std::size_t block) const {
    return static_cast<std::size_t>(block + 1 == blockCount() ? lastSize_ : blockSize_);
  }
  std::size_t blockCount() const { return starts_.size() - 1; }

  void load(std::size_t block) {
    if (block >= blockCount()) ended("compressed array");
    const std::size_t want = sizeOf(block);
    const auto packedSize = static_cast<std::size_t>(starts_[block + 1] - starts_[block]);
    packed_.resize(packedSize);
    readEncoded(starts_[block], packed_.data(), packedSize, false);
    block_.resize(want);
    bool ok;
    if (lz4_) {
      ok = LZ4_decompress_safe(reinterpret_cast<const char*>(packed_.data()),
                               reinterpret_cast<char*>(block_.data()), static_cast<int>(packedSize),
                               static_cast<int>(want)) == static_cast<int>(want);
    } else {
      uLongf got = want;
      ok = uncompress(reinterpret_cast<Bytef*>(block_.data()), &got,
                      reinterpret_cast<const Bytef*>(packed_.data()), packedSize) == Z_OK &&
           got == want;
    }
    if (!ok)
      throw base::Error(path_ + ": compressed block " + std::to_string(block) + " is corrupt (" +
                        (lz4_ ? "LZ4" : "zlib") + ": not " + std::to_string(want) +
                        " bytes as the header says)");
    loaded_ = block;
    at_ = 0;
  }

  std::size_t readSome(std::byte* to, std::size_t bytes) override {
    if (loaded_ == kNone || at_ == block_.size()) load(loaded_ == kNone ? next_ : loaded_ + 1);
    const std::size_t take = std::min(bytes, block_.size() - at_);
    std::memcpy(to, block_.data() + at_, take);
    at_ += take;
    return take;
  }

  void skip(std::uint64_t bytes) override {
    produced_ += bytes;
    if (loaded_ != kNone) {
      const std::size_t inBlock =
          static_cast<std::size_t>(std::min<std::uint64_t>(bytes, block_.size() - at_));
      at_ += inBlock, bytes -= inBlock;
      if (bytes == 0) return;
      next_ = loaded_ + 1;
    }
    // Whole blocks are jumped; the one the skip ends in is decompressed from its start.
    next_ += static_cast<std::size_t>(bytes / blockSize_);
    const std::size_t rest = static_cast<std::size_t>(bytes % blockSize_);
    loaded_ = kNone;
    if (rest > 0) {
      load(next_);
      if (rest > block_.size()) ended("compressed array");
      at_ = rest;
    }
  }

  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  bool lz4_, base64_;
  std::uint64_t blockSize_ = 0, lastSize_ = 0, dataStart_ = 0;
  std::vector<std::uint64_t> starts_;  // each block's first compressed byte, then the end
  std::vector<std::byte> packed_, block_;
  std::size_t loaded_ = kNone, next_ = 0, at_ = 0;
};

std::unique_ptr<ByteStream> openStream(const StoredArray& a, const File& file,
                                       const std::string& path, std::uint64_t offset) {
  switch (a.encoding) {
    case Encoding::Zlib:
      return std::make_unique<InflateStream>(file, path, offset);
    case Encoding::Bzip2:
      return std::make_unique<Bunzip2Stream>(file, path, offset);
    case Encoding::Hex:
      return std::make_unique<HexStream>(file, path, offset);
    case Encoding::Ascii:
      return std::make_unique<AsciiStream>(file, path, offset, a.type);
    case Encoding::ZlibBlocks:
    case Encoding::Lz4Blocks:
      return std::make_unique<VtkBlockStream>(file, path, offset, a);
    case Encoding::Raw:
    case Encoding::Base64:
      break;
  }
  throw base::Error(path + ": raw data is not read as a stream");
}

// The last stream this thread read, kept where the read stopped, and a way back to the start of
// the read's last slab: reading bricks or shell layers of one file in increasing z decodes it
// once, not once per read (a ShadingShell reads a brick's shell one layer of macrocells at a
// time, each layer starting at the previous one's last voxel plane). The way back is a copy of
// the decoder (zlib can copy its state) or else the decoded bytes from there on, up to
// kMaxReplay (bzip2, ascii, hex). Holds decoders' states and at most that many bytes a thread.
constexpr std::size_t kMaxReplay = 32u << 20;

struct StreamCache {
  std::string path;
  std::uint64_t fileOffset = 0, streamSkip = 0;
  Encoding encoding = Encoding::Raw;
  FileType type = FileType::UInt8;
  std::array<std::int64_t, 5> identity{};
  std::unique_ptr<File> file;
  std::unique_ptr<ByteStream> stream;  // reads `file`: declared after it, destroyed first
  std::uint64_t at = 0;                // where the reader is, in bytes after streamSkip
  std::uint64_t streamPos = 0;         // where `stream` is: `at`, or ahead of it inside `replay`
  std::unique_ptr<ByteStream> mark;    // a copy of `stream` at markAt
  std::uint64_t markAt = 0;
  std::vector<std::byte> replay;  // decoded bytes from replayAt up to streamPos, when recording
  std::uint64_t replayAt = 0;
  bool recording = false;

  // The next `bytes` bytes into `to` (dropped when null): from the replay, then the stream.
  void read(std::byte* to, std::uint64_t bytes) {
    if (at < streamPos) {
      const std::uint64_t take = std::min(bytes, streamPos - at);
      if (to) std::memcpy(to, replay.data() + (at - replayAt), static_cast<std::size_t>(take));
      if (to) to += take;
      at += take, bytes -= take;
    }
    if (bytes == 0) return;
    if (recording && replay.size() + bytes > kMaxReplay) {
      recording = false;
      replay.clear();
    }
    if (recording) {
      const std::size_t old = replay.size();
      replay.resize(old + static_cast<std::size_t>(bytes));
      stream->read(replay.data() + old, bytes);
      if (to) std::memcpy(to, replay.data() + old, static_cast<std::size_t>(bytes));
    } else {
      stream->read(to, bytes);
    }
    at += bytes, streamPos += bytes;
  }

  // Marks `at` as the place a later read may go back to.
  void markHere() {
    if (at == streamPos) {
      if ((mark = stream->snapshot())) {
        markAt = at;
        return;
      }
    }
    if (recording && replayAt <= at) {  // keep what is recorded from here on
      replay.erase(replay.begin(), replay.begin() + static_cast<std::ptrdiff_t>(at - replayAt));
    } else {
      if (at != streamPos) return;
      replay.clear();
    }
    replayAt = at;
    recording = true;
  }
};
thread_local StreamCache streamCache;

// Positions the stream of file `path` of `a` (its data starting at `offset`) at byte `at` after
// the skip: the cached one when it is the same unchanged file and `at` is not behind it (or
// behind it where the mark or the replay reaches), else a new one.
void streamAt(const StoredArray& a, const std::string& path, std::uint64_t offset,
              const std::array<std::int64_t, 5>& identity, std::uint64_t at) {
  StreamCache& c = streamCache;
  bool same = c.stream && c.path == path && c.fileOffset == offset &&
              c.streamSkip == a.streamSkip && c.encoding == a.encoding && c.type == a.type &&
              c.identity == identity;
  if (same && at < c.at) {
    if (c.mark && c.markAt <= at) {  // resume from the copy
      c.stream = std::move(c.mark);
      c.at = c.streamPos = c.markAt;
      c.recording = false;
      c.replay.clear();
    } else if (c.recording && c.replayAt <= at) {  // replay what was recorded
      c.at = at;
    } else {
      same = false;
    }
  }
  if (!same) {
    c.mark.reset();
    c.stream.reset();
    c.file = std::make_unique<File>(path);
    c.stream = openStream(a, *c.file, path, offset);
    c.path = path, c.fileOffset = offset, c.streamSkip = a.streamSkip;
    c.encoding = a.encoding, c.type = a.type;
    c.identity = identity;
    c.at = c.streamPos = 0;
    c.recording = false;
    c.replay.clear();
    c.stream->read(nullptr, a.streamSkip);
  }
  c.read(nullptr, at - c.at);  // what lies before is dropped (or recorded)
}

template <class T>
T load(const std::byte* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

// `count` stored voxels (native byte order) as float.
float storedValue(FileType type, const std::byte* p) {
  switch (type) {
    case FileType::Int8:
      return static_cast<float>(load<std::int8_t>(p));
    case FileType::UInt8:
      return static_cast<float>(load<std::uint8_t>(p));
    case FileType::Int16:
      return static_cast<float>(load<std::int16_t>(p));
    case FileType::UInt16:
      return static_cast<float>(load<std::uint16_t>(p));
    case FileType::Int32:
      return static_cast<float>(load<std::int32_t>(p));
    case FileType::UInt32:
      return static_cast<float>(load<std::uint32_t>(p));
    case FileType::Float32:
      return load<float>(p);
    case FileType::Float64:
      return static_cast<float>(load<double>(p));
  }
  return 0;
}

// Converts `count` stored voxels at `from` (file byte order) into held voxels at `to`.
void convert(const StoredArray& a, VoxelType held, std::byte* from, std::byte* to,
             std::size_t count) {
  const std::size_t width = fileTypeBytes(a.type);
  if (width > 1 && a.bigEndian != (std::endian::native == std::endian::big))
    for (std::size_t n = 0; n < count; ++n) std::reverse(from + n * width, from + (n + 1) * width);
  if (held != VoxelType::Float32 || (a.type == FileType::Float32 && !a.scaled())) {
    std::memcpy(to, from, count * width);  // held as stored
    return;
  }
  for (std::size_t n = 0; n < count; ++n) {
    float v = storedValue(a.type, from + n * width);
    if (a.scaled()) v = v * a.slope + a.intercept;
    std::memcpy(to + n * 4, &v, 4);
  }
}

}  // namespace

std::size_t fileTypeBytes(FileType type) {
  switch (type) {
    case FileType::Int8:
    case FileType::UInt8:
      return 1;
    case FileType::Int16:
    case FileType::UInt16:
      return 2;
    case FileType::Int32:
    case FileType::UInt32:
    case FileType::Float32:
      return 4;
    case FileType::Float64:
      return 8;
  }
  return 1;
}

const char* fileTypeName(FileType type) {
  static const char* const names[] = {"int8",  "uint8",  "int16",   "uint16",
                                      "int32", "uint32", "float32", "float64"};
  return names[static_cast<int>(type)];
}

VoxelType heldVoxelType(const StoredArray& array) {
  if (array.scaled()) return VoxelType::Float32;
  if (array.type == FileType::UInt8) return VoxelType::UInt8;
  if (array.type == FileType::UInt16) return VoxelType::UInt16;
  return VoxelType::Float32;
}

namespace {

const std::string& fileOf(const StoredArray& a, std::size_t index) {
  return a.paths.empty() ? a.path : a.paths[index];
}

std::uint64_t voxelsPerFile(const StoredArray& a, Index3 dims) {
  return a.paths.empty() ? static_cast<std::uint64_t>(dims.x) * static_cast<std::uint64_t>(dims.y) *
                               static_cast<std::uint64_t>(dims.z)
                         : a.voxelsPerFile;
}

// Where the data of `file` starts: after `lineSkip` lines from fileOffset, or, for data that ends
// the file, its size less the data's.
std::uint64_t dataStart(const StoredArray& a, const File& file, const std::string& path,
                        std::uint64_t bytes) {
  if (a.atEnd) {
    const std::uint64_t size = file.size();
    if (size < bytes)
      throw base::Error(path + ": the volume data file is " + std::to_string(size) +
                        " bytes, shorter than the " + std::to_string(bytes) +
                        " the header calls for (its data ends the file: byte skip -1)");
    return size - bytes;
  }
  std::uint64_t at = a.fileOffset;
  std::byte chunk[16384];
  for (std::uint64_t lines = 0; lines < a.lineSkip;) {
    const std::size_t n = file.readSome(at, chunk, sizeof chunk);
    if (n == 0)
      throw base::Error(path + ": the file ends after " + std::to_string(lines) +
                        " lines, before the " + std::to_string(a.lineSkip) +
                        " its header skips (line skip)");
    std::size_t i = 0;
    for (; i < n && lines < a.lineSkip; ++i)
      if (chunk[i] == std::byte{'\n'}) ++lines;
    at += i;
  }
  return at + a.byteSkip;
}

}  // namespace

void checkStoredArray(const StoredArray& array, Index3 dims) {
  const std::uint64_t voxels = voxelsPerFile(array, dims);
  const std::size_t files = array.paths.empty() ? 1 : array.paths.size();
  for (std::size_t f = 0; f < files; ++f) {
    const std::string& path = fileOf(array, f);
    const File file(path);
    if (array.encoding != Encoding::Raw) continue;  // its length shows on reading
    const std::uint64_t bytes = voxels * fileTypeBytes(array.type);
    const std::uint64_t start = dataStart(array, file, path, bytes);
    const std::uint64_t found = file.size();
    if (found < start + bytes)
      throw base::Error(
          path + ": the volume data file is " + std::to_string(found) +
          " bytes, shorter than the " + std::to_string(start + bytes) + " the header calls for (" +
          (array.paths.empty() ? std::to_string(dims.x) + "x" + std::to_string(dims.y) + "x" +
                                     std::to_string(dims.z)
                               : std::to_string(voxels)) +
          " " + fileTypeName(array.type) + " voxels from byte " + std::to_string(start) + ")");
  }
}

Volume readStoredBox(const StoredArray& array, const GridGeometry& grid, const VoxelBox& box) {
  Volume v;
  v.grid = grid;
  v.box = box;
  v.type = heldVoxelType(array);
  const std::size_t width = fileTypeBytes(array.type), heldWidth = voxelBytes(v.type);
  v.voxels = allocateVoxelBytes(box, v.type);
  const Index3 d = grid.dims, s = box.size();
  const std::uint64_t perFile = voxelsPerFile(array, d);
  // Runs of voxels contiguous in the data: rows, or whole slabs, or the whole box; a run that
  // crosses from one file of a list to the next is read in parts.
  const bool wholeRows = s.x == d.x, wholeSlabs = wholeRows && s.y == d.y;
  const int runsPerSlab = wholeRows ? 1 : s.y, slabsPerRun = wholeSlabs ? s.z : 1;
  const std::size_t runVoxels = static_cast<std::size_t>(s.x) *
                                static_cast<std::size_t>(wholeRows ? s.y : 1) *
                                static_cast<std::size_t>(slabsPerRun);
  // Converting runs go through a buffer of at most ~4 MiB at a time.
  const std::size_t pieceVoxels = std::max<std::size_t>(1, std::min(runVoxels, (4u << 20) / width));
  std::vector<std::byte> piece(pieceVoxels * width);
  struct DropCacheOnError {  // a stream that failed part-way is not resumed
    bool armed = true;
    ~DropCacheOnError() {
      if (armed) streamCache = StreamCache{};
    }
  } dropOnError;
  // The file being read and where its data starts.
  std::size_t openIndex = static_cast<std::size_t>(-1);
  std::unique_ptr<File> file;
  std::uint64_t start = 0;
  std::array<std::int64_t, 5> identity{};
  const auto openFile = [&](std::size_t index) {
    if (index == openIndex) return;
    const std::string& path = fileOf(array, index);
    file = std::make_unique<File>(path);
    start = dataStart(array, *file, path, perFile * width);
    identity = array.streamed() ? file->identity() : std::array<std::int64_t, 5>{};
    openIndex = index;
  };
  std::byte* to = v.voxels.data();
  for (int k = box.lo.z; k < box.hi.z; k += slabsPerRun)
    for (int r = 0; r < runsPerSlab; ++r) {
      std::uint64_t voxel = (static_cast<std::uint64_t>(k) * static_cast<std::uint64_t>(d.y) +
                             static_cast<std::uint64_t>(box.lo.y + r)) *
                                static_cast<std::uint64_t>(d.x) +
                            static_cast<std::uint64_t>(box.lo.x);
      for (std::size_t left = runVoxels; left > 0;) {
        const auto index = static_cast<std::size_t>(voxel / perFile);
        const std::uint64_t local = voxel % perFile;
        const auto inFile =
            static_cast<std::size_t>(std::min<std::uint64_t>(left, perFile - local));
        openFile(index);
        std::uint64_t at = local * width;
        if (array.streamed()) {
          streamAt(array, fileOf(array, index), start, identity, at);  // skips what lies before
          if (k + slabsPerRun >= box.hi.z && r == 0 && left == runVoxels)
            streamCache.markHere();  // the last slab: the next read may start here
        }
        for (std::size_t done = 0; done < inFile;) {
          const std::size_t n = std::min(pieceVoxels, inFile - done);
          if (array.streamed()) {
            streamCache.read(piece.data(), n * width);
          } else if (array.encoding == Encoding::Base64) {
            base64Read(*file, fileOf(array, index), start, array.streamSkip + at, piece.data(),
                       n * width);
          } else {
            file->read(start + at, piece.data(), n * width);
          }
          convert(array, v.type, piece.data(), to, n);
          to += n * heldWidth;
          at += n * width;
          done += n;
        }
        voxel += inFile;
        left -= inFile;
      }
    }
  dropOnError.armed = false;
  v.updateRange();
  return v;
}

std::uint64_t storedBytesRead() { return bytesRead; }

}  // namespace renderers::scivis
