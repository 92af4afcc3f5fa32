#pragma once
// Reading and writing the fields of a wall-service message after its MessageHeader
// (wall/service/protocol/Protocol.h): fixed-size values in the host's byte order (every dfbwall
// host is little-endian x86-64 or arm64), texts with a 16-bit length. Reads past the end throw
// base::Error naming the message: nothing from the wire is trusted.
#include <cstring>
#include <string>

#include "base/Error.h"
#include "wall/service/protocol/Protocol.h"

namespace wall::service {

class Writer {
 public:
  explicit Writer(Kind kind, std::uint64_t session) {
    // Room for a header and the fields after it: fewer reallocations, and GCC 12 at -O3 no
    // longer sees a growth from the header's exact size that it warns about falsely
    // (-Wstringop-overflow in BatchWriter::start).
    bytes_.reserve(kReservedBytes);
    MessageHeader h;
    h.kind = static_cast<std::uint16_t>(kind);
    h.session = session;
    raw(&h, sizeof h);
  }
  // resize + memcpy rather than insert: GCC 12 at -O2 warns (-Wstringop-overflow, a false
  // positive) about the inlined vector::insert into the fresh 16-byte header, which
  // DFBWALL_WERROR turns into a build error.
  void raw(const void* p, std::size_t n) {
    if (n == 0) return;
    const std::size_t at = bytes_.size();
    bytes_.resize(at + n);
    std::memcpy(bytes_.data() + at, p, n);
  }
  template <typename T>
  void put(T value) {
    raw(&value, sizeof value);
  }
  void text(const std::string& s) {
    if (s.size() > kMaxStringBytes)
      throw base::Error("a text field of " + std::to_string(s.size()) + " bytes (at most " +
                        std::to_string(kMaxStringBytes) + ")");
    put<std::uint16_t>(static_cast<std::uint16_t>(s.size()));
    raw(s.data(), s.size());
  }
  messaging::Bytes take() { return std::move(bytes_); }

 private:
  static constexpr std::size_t kReservedBytes = 64;
  messaging::Bytes bytes_;
};

// Reads fields in order; any read past the end throws, naming the message.
class Reader {
 public:
  Reader(const std::byte* data, std::size_t size, const char* what)
      : data_(data), size_(size), what_(what) {
    skip(sizeof(MessageHeader));
  }
  void raw(void* p, std::size_t n) {
    need(n);
    if (n == 0) return;  // `p` may be null then (an empty vector's data())
    std::memcpy(p, data_ + at_, n);
    at_ += n;
  }
  template <typename T>
  T get() {
    T value;
    raw(&value, sizeof value);
    return value;
  }
  std::string text() {
    const std::size_t n = get<std::uint16_t>();
    if (n > kMaxStringBytes) fail("a text field longer than " + std::to_string(kMaxStringBytes));
    need(n);
    std::string s(reinterpret_cast<const char*>(data_ + at_), n);
    at_ += n;
    return s;
  }
  const std::byte* span(std::size_t n) {
    need(n);
    const std::byte* p = data_ + at_;
    at_ += n;
    return p;
  }
  void skip(std::size_t n) { span(n); }
  std::size_t left() const { return size_ - at_; }
  void end() {
    if (at_ != size_) fail(std::to_string(size_ - at_) + " bytes too many");
  }
  [[noreturn]] void fail(const std::string& why) const {
    throw base::Error(std::string("malformed ") + what_ + ": " + why);
  }

 private:
  void need(std::size_t n) const {
    if (n > size_ - at_)
      fail("ends after " + std::to_string(size_) + " bytes, " + std::to_string(n) +
           " more needed at byte " + std::to_string(at_));
  }
  const std::byte* data_;
  std::size_t size_, at_ = 0;
  const char* what_;
};

}  // namespace wall::service
