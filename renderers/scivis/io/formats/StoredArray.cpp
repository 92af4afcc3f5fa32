#include "renderers/scivis/io/formats/StoredArray.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
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

// The inflated bytes of a zlib or gzip stream (concatenated gzip members too), in order; only
// as much input is inflated as the reads ask for.
class InflateStream {
 public:
  InflateStream(const File& file, const std::string& path, std::uint64_t offset)
      : file_(file), path_(path), offset_(offset), in_(kChunk) {
    if (inflateInit2(&z_, 15 + 32) != Z_OK) throw base::Error(path + ": cannot start zlib");
  }
  ~InflateStream() { inflateEnd(&z_); }
  InflateStream(const InflateStream&) = delete;
  InflateStream& operator=(const InflateStream&) = delete;

  // A copy of the stream where it is now (zlib's inflateCopy), to resume from later.
  std::unique_ptr<InflateStream> snapshot() const {
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

  // The next `bytes` bytes into `to`, or dropped when `to` is null.
  void read(std::byte* to, std::uint64_t bytes) {
    std::byte scratch[16384];
    while (bytes > 0) {
      const std::size_t want =
          to ? static_cast<std::size_t>(std::min<std::uint64_t>(bytes, 1u << 30))
             : static_cast<std::size_t>(std::min<std::uint64_t>(bytes, sizeof scratch));
      std::byte* dst = to ? to : scratch;
      const std::size_t got = inflateSome(dst, want);
      if (to) to += got;
      bytes -= got;
      produced_ += got;
    }
  }

 private:
  static constexpr std::size_t kChunk = 1 << 16;

  std::size_t inflateSome(std::byte* to, std::size_t bytes) {
    z_.next_out = reinterpret_cast<Bytef*>(to);
    z_.avail_out = static_cast<uInt>(bytes);
    while (z_.avail_out == bytes) {
      if (z_.avail_in == 0) {
        const std::size_t n = file_.readSome(offset_, in_.data(), in_.size());
        if (n == 0) ended();
        offset_ += n;
        z_.next_in = reinterpret_cast<Bytef*>(in_.data());
        z_.avail_in = static_cast<uInt>(n);
      }
      const int rc = inflate(&z_, Z_NO_FLUSH);
      if (rc == Z_STREAM_END) {
        // Another gzip member may follow; anything else is the end of the data.
        if (z_.avail_out != bytes) break;
        if (inflateReset(&z_) != Z_OK) ended();
        continue;
      }
      if (rc != Z_OK && rc != Z_BUF_ERROR)
        throw base::Error(path_ + ": compressed volume data is corrupt after " +
                          std::to_string(produced_) + " inflated bytes (" +
                          (z_.msg ? z_.msg : "zlib error " + std::to_string(rc)) + ")");
    }
    return bytes - z_.avail_out;
  }

  [[noreturn]] void ended() const {
    throw base::Error(path_ + ": the compressed stream ends after " + std::to_string(produced_) +
                      " bytes, before the voxels the header calls for");
  }

  const File& file_;
  std::string path_;
  std::uint64_t offset_;
  std::vector<std::byte> in_;
  z_stream z_{};
  std::uint64_t produced_ = 0;
};

// The last compressed stream this thread read, kept where the read stopped, and a copy of it
// at the start of the read's last slab: reading bricks or shell layers of one file in
// increasing z inflates it once, not once per read (a ShadingShell reads a brick's shell one
// layer of macrocells at a time, each layer starting at the previous one's last voxel plane).
// Holds streams' states only (zlib's window and one input chunk each), never voxels.
struct StreamCache {
  std::string path;
  std::uint64_t fileOffset = 0, streamSkip = 0;
  std::array<std::int64_t, 5> identity{};
  std::unique_ptr<File> file;
  std::unique_ptr<InflateStream> stream;  // reads `file`: declared after it, destroyed first
  std::uint64_t at = 0;                   // bytes consumed after streamSkip
  std::unique_ptr<InflateStream> mark;    // a copy of `stream` at markAt
  std::uint64_t markAt = 0;
};
thread_local StreamCache streamCache;

// The stream of `a` positioned at byte `at` after its skip: the cached one when it is the same
// unchanged file and not past `at`, else a new one.
InflateStream& streamAt(const StoredArray& a, const std::array<std::int64_t, 5>& identity,
                        std::uint64_t at) {
  StreamCache& c = streamCache;
  const bool same = c.stream && c.path == a.path && c.fileOffset == a.fileOffset &&
                    c.streamSkip == a.streamSkip && c.identity == identity;
  if (same && c.at > at && c.mark && c.markAt <= at) {  // resume from the mark
    c.stream = std::move(c.mark);
    c.at = c.markAt;
  }
  if (!(same && c.stream && c.at <= at)) {
    c.mark.reset();
    c.stream.reset();
    c.file = std::make_unique<File>(a.path);
    c.stream = std::make_unique<InflateStream>(*c.file, a.path, a.fileOffset);
    c.path = a.path, c.fileOffset = a.fileOffset, c.streamSkip = a.streamSkip;
    c.identity = identity;
    c.at = 0;
    c.stream->read(nullptr, a.streamSkip);
  }
  c.stream->read(nullptr, at - c.at);  // discard what lies before
  c.at = at;
  return *c.stream;
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

void checkStoredArray(const StoredArray& array, Index3 dims) {
  const File file(array.path);
  if (array.compressed) return;
  const std::uint64_t need =
      array.fileOffset + static_cast<std::uint64_t>(dims.x) * static_cast<std::uint64_t>(dims.y) *
                             static_cast<std::uint64_t>(dims.z) * fileTypeBytes(array.type);
  const std::uint64_t found = file.size();
  if (found < need)
    throw base::Error(
        array.path + ": the volume data file is " + std::to_string(found) +
        " bytes, shorter than the " + std::to_string(need) + " the header calls for (" +
        std::to_string(dims.x) + "x" + std::to_string(dims.y) + "x" + std::to_string(dims.z) + " " +
        fileTypeName(array.type) + " voxels from byte " + std::to_string(array.fileOffset) + ")");
}

Volume readStoredBox(const StoredArray& array, const GridGeometry& grid, const VoxelBox& box) {
  const File file(array.path);
  Volume v;
  v.grid = grid;
  v.box = box;
  v.type = heldVoxelType(array);
  const std::size_t width = fileTypeBytes(array.type), heldWidth = voxelBytes(v.type);
  v.voxels = allocateVoxelBytes(box, v.type);
  const Index3 d = grid.dims, s = box.size();
  // Runs of voxels contiguous in the file: rows, or whole slabs, or the whole box.
  const bool wholeRows = s.x == d.x, wholeSlabs = wholeRows && s.y == d.y;
  const int runsPerSlab = wholeRows ? 1 : s.y, slabsPerRun = wholeSlabs ? s.z : 1;
  const std::size_t runVoxels = static_cast<std::size_t>(s.x) *
                                static_cast<std::size_t>(wholeRows ? s.y : 1) *
                                static_cast<std::size_t>(slabsPerRun);
  // Converting runs go through a buffer of at most ~4 MiB at a time.
  const std::size_t pieceVoxels = std::max<std::size_t>(1, std::min(runVoxels, (4u << 20) / width));
  std::vector<std::byte> piece(pieceVoxels * width);
  InflateStream* stream = nullptr;
  const std::array<std::int64_t, 5> identity =
      array.compressed ? file.identity() : std::array<std::int64_t, 5>{};
  struct DropCacheOnError {  // a stream that failed part-way is not resumed
    bool armed = true;
    ~DropCacheOnError() {
      if (armed) streamCache = StreamCache{};
    }
  } dropOnError;
  std::byte* to = v.voxels.data();
  for (int k = box.lo.z; k < box.hi.z; k += slabsPerRun)
    for (int r = 0; r < runsPerSlab; ++r) {
      const std::uint64_t voxel = (static_cast<std::uint64_t>(k) * static_cast<std::uint64_t>(d.y) +
                                   static_cast<std::uint64_t>(box.lo.y + r)) *
                                      static_cast<std::uint64_t>(d.x) +
                                  static_cast<std::uint64_t>(box.lo.x);
      std::uint64_t at = voxel * width;
      if (array.compressed) {
        stream = &streamAt(array, identity, at);      // skips what lies before
        if (k + slabsPerRun >= box.hi.z && r == 0) {  // the last slab: mark where it starts
          streamCache.mark = stream->snapshot();
          streamCache.markAt = at;
        }
      }
      for (std::size_t done = 0; done < runVoxels;) {
        const std::size_t n = std::min(pieceVoxels, runVoxels - done);
        if (stream) {
          stream->read(piece.data(), n * width);
          streamCache.at += n * width;
        } else {
          file.read(array.fileOffset + at, piece.data(), n * width);
        }
        convert(array, v.type, piece.data(), to, n);
        to += n * heldWidth;
        at += n * width;
        done += n;
      }
    }
  dropOnError.armed = false;
  v.updateRange();
  return v;
}

std::uint64_t storedBytesRead() { return bytesRead; }

}  // namespace renderers::scivis
