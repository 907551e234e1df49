// The Zaber ASCII protocol's text (station/zaber_ascii_text.h), against the manual's grammar:
// "@device axis id flag status warning data:CC" with the LRC of the bytes between '@' and ':'.
#include "station/zaber_ascii_text.h"

#include <gtest/gtest.h>

#include <string>

namespace irdist::zaber_ascii_text {
namespace {

// The manual's checksum, summed here independently: two's complement of the byte sum mod 256.
std::string Checked(const std::string& line) {
  unsigned sum = 0;
  for (std::size_t i = 1; i < line.size(); ++i) sum += static_cast<unsigned char>(line[i]);
  const unsigned lrc = (256u - (sum % 256u)) % 256u;
  const char* hex = "0123456789ABCDEF";
  return line + ":" + hex[lrc >> 4] + hex[lrc & 15u];
}

TEST(ZaberAsciiText, TheLrcMakesTheBytesSumToZero) {
  for (const std::string body : {"01 1 12 OK IDLE -- 0", "1 0 get pos", "", "99 9 99 OK BUSY FF 5"}) {
    const std::string lrc = Lrc(body);
    ASSERT_EQ(lrc.size(), 2u);
    unsigned sum = std::stoul(lrc, nullptr, 16);
    for (unsigned char c : body) sum += c;
    EXPECT_EQ(sum % 256u, 0u) << body;
    EXPECT_EQ(lrc.find_first_not_of("0123456789ABCDEF"), std::string::npos);  // upper case
  }
}

TEST(ZaberAsciiText, AReplySplitsIntoItsFieldsAndItsChecksumIsVerified) {
  Reply r;
  bool checked = false;
  ASSERT_TRUE(ParseReply(Checked("@01 2 07 OK BUSY WR 1651 1652"), true, &r, &checked));
  EXPECT_TRUE(checked);
  EXPECT_EQ(r.type, '@');
  EXPECT_EQ(r.device, 1);
  EXPECT_EQ(r.axis, 2);
  EXPECT_EQ(r.id, 7);
  EXPECT_EQ(r.flag, "OK");
  EXPECT_EQ(r.status, "BUSY");
  EXPECT_EQ(r.warning, "WR");
  EXPECT_EQ(r.data, "1651 1652");
  // One flipped byte fails the checksum; no checksum fails where one is needed.
  std::string damaged = Checked("@01 2 07 OK BUSY WR 1651 1652");
  damaged[21] = '7';
  EXPECT_FALSE(ParseReply(damaged, false, &r, &checked));
  EXPECT_FALSE(ParseReply("@01 2 07 OK IDLE -- 0", true, &r, &checked));
  ASSERT_TRUE(ParseReply("@01 2 07 OK IDLE -- 0", false, &r, &checked));
  EXPECT_FALSE(checked);
  // Not a reply's grammar: a status or flag outside the manual's, a command echo.
  EXPECT_FALSE(ParseReply("@01 2 07 OK WAIT -- 0", false, &r, &checked));
  EXPECT_FALSE(ParseReply("@01 2 07 MAYBE IDLE -- 0", false, &r, &checked));
  EXPECT_FALSE(ParseReply("/1 2 07 get pos", false, &r, &checked));
  // An alert carries no id and may carry nothing else.
  ASSERT_TRUE(ParseReply("!01 1", false, &r, &checked));
  EXPECT_EQ(r.type, '!');
}

TEST(ZaberAsciiText, AddressesFlagsAndNumbers) {
  Address a;
  ASSERT_TRUE(ParseAddress("3 2", &a));
  EXPECT_EQ(a.device, 3);
  EXPECT_EQ(a.axis, 2);
  ASSERT_TRUE(ParseAddress("7", &a));
  EXPECT_EQ(a.axis, 1);
  for (const char* bad : {"", "0", "100", "1 0", "1 10", "1 2 3", "x", "-1"}) {
    EXPECT_FALSE(ParseAddress(bad, &a)) << bad;
  }
  EXPECT_TRUE(Unreferenced("WR"));
  EXPECT_TRUE(Unreferenced("WH"));
  EXPECT_FALSE(Unreferenced("--"));
  EXPECT_TRUE(Fault("FS"));
  EXPECT_FALSE(Fault("WS"));
  EXPECT_EQ(FlagMeaning("FS"), "stalled and stopped");
  EXPECT_EQ(FlagMeaning("ZZ"), "flag not in the manual's table");
  EXPECT_TRUE(IsIntegers("1651"));
  EXPECT_TRUE(IsIntegers("-5 12"));
  EXPECT_FALSE(IsIntegers("16=1"));
  EXPECT_FALSE(IsIntegers("-"));
  EXPECT_FALSE(IsIntegers(""));
  EXPECT_NE(RejectionFix("BADDATA").find("limit"), std::string::npos);
}

}  // namespace
}  // namespace irdist::zaber_ascii_text
