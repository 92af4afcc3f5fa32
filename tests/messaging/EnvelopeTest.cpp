#include "messaging/Envelope.h"

#include <gtest/gtest.h>

#include <cstring>

#include "base/Error.h"

namespace messaging {
namespace {

Bytes text(const char* s) {
  const auto* p = reinterpret_cast<const std::byte*>(s);
  return Bytes(p, p + std::strlen(s));
}

// The trailer as another rank would write it, for hostile variants.
Bytes withTrailer(Bytes body, ObjectId object, std::uint32_t rawBytes, std::uint32_t flags) {
  const size_t at = body.size();
  body.resize(at + kEnvelopeBytes);
  std::memcpy(body.data() + at, &object, 8);
  std::memcpy(body.data() + at + 8, &rawBytes, 4);
  std::memcpy(body.data() + at + 12, &flags, 4);
  return body;
}

TEST(Envelope, PlainRoundTripKeepsObjectAndPayload) {
  Bytes payload;
  const Envelope e = openEnvelope(sealEnvelope(text("tile pixels"), 42, false), 1 << 20, payload);
  EXPECT_EQ(e.object, 42u);
  EXPECT_EQ(e.rawBytes, 11u);
  EXPECT_EQ(payload, text("tile pixels"));
}

TEST(Envelope, CompressesOnlyWhenItShrinks) {
  bool compressed = false;
  const Bytes repetitive(10000, std::byte{7});
  const Bytes wire = sealEnvelope(repetitive, 9, true, &compressed);
  EXPECT_TRUE(compressed);
  EXPECT_LT(wire.size(), repetitive.size() / 10);
  Bytes payload;
  EXPECT_EQ(openEnvelope(Bytes(wire), 1 << 20, payload).object, 9u);
  EXPECT_EQ(payload, repetitive);

  sealEnvelope(text("ab"), 9, true, &compressed);
  EXPECT_FALSE(compressed);
}

TEST(Envelope, PeekDoesNotConsume) {
  const Bytes wire = sealEnvelope(text("x"), 5, false);
  EXPECT_EQ(peekEnvelope(wire).object, 5u);
  EXPECT_EQ(wire.size(), 1 + kEnvelopeBytes);
}

TEST(Envelope, RejectsTruncatedUnknownFlagsWrongSizesAndHugeAnnouncements) {
  Bytes payload;
  EXPECT_THROW(openEnvelope(Bytes(15), 1 << 20, payload), base::Error);
  EXPECT_THROW(openEnvelope(withTrailer(text("abc"), 1, 3, 2), 1 << 20, payload), base::Error);
  EXPECT_THROW(openEnvelope(withTrailer(text("abc"), 1, 4, 0), 1 << 20, payload), base::Error);
  // A 20-byte message announcing 4 GiB of compressed payload fails before allocating it.
  EXPECT_THROW(openEnvelope(withTrailer(text("abcd"), 1, 0xFFFFFFFFu, 1), 1 << 20, payload),
               base::Error);
  try {
    openEnvelope(withTrailer(text("abcd"), 77, 2000000, 0), 1 << 20, payload);
    FAIL();
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("object id 77"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("limit"), std::string::npos) << e.what();
  }
}

TEST(Envelope, OneSizeCapForBothSides) {
  const std::size_t gib = std::size_t{1} << 30;
  // 2.5 GiB would wrap MPI's int count: above any limit a messenger can have.
  try {
    checkPayloadSize(5 * gib / 2, 4 * gib, "message to object id 3");
    FAIL();
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("message to object id 3 of 2684354560 bytes"),
              std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(checkPayloadSize(kLargestPayload, 4 * gib, "m"));
  EXPECT_THROW(checkPayloadSize(kLargestPayload + 1, 4 * gib, "m"), base::Error);
  EXPECT_THROW(checkPayloadSize(1025, 1024, "m"), base::Error);
  // The receiver applies the same cap to what a message announces.
  Bytes payload;
  EXPECT_THROW(openEnvelope(withTrailer(text("abcd"), 1, 1025, 0), 1024, payload), base::Error);
}

}  // namespace
}  // namespace messaging
