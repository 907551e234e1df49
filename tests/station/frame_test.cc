#include "station/frame.h"

#include <gtest/gtest.h>

#include <cctype>
#include <cstdio>

#include "base/check.h"

namespace irdist {
namespace {

TEST(Frame, Crc8CheckValue) {
  EXPECT_EQ(Crc8("123456789"), 0xF4);  // CRC-8 (poly 0x07, init 0) check value
  EXPECT_EQ(Crc8(""), 0x00);
}

TEST(Frame, EncodeRequestHasSeqCommandAndChecksum) {
  const std::string line = EncodeRequest(17, "MOVE 250000,1000,0");
  ASSERT_EQ(line.substr(0, 23), "#17 MOVE 250000,1000,0*");
  char hex[3];
  std::snprintf(hex, sizeof(hex), "%02X", Crc8("#17 MOVE 250000,1000,0"));
  EXPECT_EQ(line.substr(23), hex);
  EXPECT_THROW(EncodeRequest(10000, "POS?"), CheckError);
  EXPECT_THROW(EncodeRequest(1, "POS?\x01"), CheckError);
  EXPECT_THROW(EncodeRequest(1, "#POS?"), CheckError);
  EXPECT_EQ(EncodeRequest(3, "*IDN?").substr(0, 9), "#3 *IDN?*");
}

std::string Framed(const std::string& text) {
  char hex[3];
  std::snprintf(hex, sizeof(hex), "%02X", Crc8(text));
  return text + "*" + hex;
}

TEST(Frame, DecodeOkReplyWithPayload) {
  std::string why;
  const auto reply = DecodeReply(Framed("#42 OK 250000,-1050,0"), &why);
  ASSERT_TRUE(reply) << why;
  EXPECT_EQ(reply->seq, 42);
  EXPECT_TRUE(reply->ok);
  EXPECT_EQ(reply->payload, "250000,-1050,0");
  const auto bare = DecodeReply(Framed("#0 OK"), &why);
  ASSERT_TRUE(bare);
  EXPECT_TRUE(bare->ok);
  EXPECT_EQ(bare->payload, "");
}

TEST(Frame, DecodeErrReply) {
  std::string why;
  const auto reply = DecodeReply(Framed("#7 ERR -222,\"Data out of range\""), &why);
  ASSERT_TRUE(reply) << why;
  EXPECT_FALSE(reply->ok);
  EXPECT_EQ(reply->seq, 7);
  EXPECT_EQ(reply->error_code, -222);
  EXPECT_EQ(reply->error_text, "Data out of range");
}

TEST(Frame, LowercaseChecksumAccepted) {
  std::string line = Framed("#3 OK IDLE,ABCDEF01");
  for (std::size_t i = line.size() - 2; i < line.size(); ++i) line[i] = std::tolower(line[i]);
  EXPECT_TRUE(DecodeReply(line, nullptr));
}

TEST(Frame, EveryCorruptedByteIsRejected) {
  const std::string good = Framed("#1234 OK 100000,0,-4500");
  ASSERT_TRUE(DecodeReply(good, nullptr));
  for (std::size_t i = 0; i < good.size(); ++i) {
    for (int delta : {1, 7, 32}) {
      std::string bad = good;
      bad[i] = static_cast<char>(((bad[i] - 0x20 + delta) % 95) + 0x20);
      if (i + 2 >= good.size() && std::tolower(bad[i]) == std::tolower(good[i])) continue;
      std::string why;
      EXPECT_FALSE(DecodeReply(bad, &why)) << "byte " << i << " delta " << delta << ": " << bad;
    }
  }
}

TEST(Frame, MalformedLinesRejected) {
  for (const std::string& bad :
       {std::string(""), std::string("OK"), std::string("#12 OK*"), Framed("12 OK"),
        Framed("#x OK"), Framed("#12 MAYBE"), Framed("#12OK"), Framed("#12 ERR abc"),
        std::string("#12 OK\x01*00"),
        // Found by fuzz_station_reply: a sign without digits once reached std::stoi and threw.
        Framed("#9 ERR -,\"x\""), Framed("#9 ERR -")}) {
    std::string why;
    EXPECT_FALSE(DecodeReply(bad, &why)) << bad;
    EXPECT_FALSE(why.empty());
  }
}

}  // namespace
}  // namespace irdist
