#include "base/utc_time.h"

#include <gtest/gtest.h>

namespace irdist {
namespace {

// 2026-12-02T06:12:03Z is 1796191923 s after the epoch (date -u -d @1796191923).
constexpr std::int64_t kSecondNs = 1000000000;
constexpr std::int64_t kExampleS = 1796191923;

TEST(UtcTime, FormatsIso8601WithMicroseconds) {
  EXPECT_EQ(FormatUtcIso8601(kExampleS * kSecondNs + 123456789), "2026-12-02T06:12:03.123456Z");
  EXPECT_EQ(FormatUtcIso8601(0), "1970-01-01T00:00:00.000000Z");
}

TEST(UtcTime, TruncatesToTheMicrosecondBelowAlsoBefore1970) {
  EXPECT_EQ(FormatUtcIso8601(999), "1970-01-01T00:00:00.000000Z");
  EXPECT_EQ(FormatUtcIso8601(-1), "1969-12-31T23:59:59.999999Z");
  EXPECT_EQ(FormatUtcIso8601(-kSecondNs), "1969-12-31T23:59:59.000000Z");
}

TEST(UtcTime, ParsesWhatItFormats) {
  const std::int64_t ns = kExampleS * kSecondNs + 123456000;
  ASSERT_TRUE(ParseUtcIso8601(FormatUtcIso8601(ns)).has_value());
  EXPECT_EQ(*ParseUtcIso8601(FormatUtcIso8601(ns)), ns);
  EXPECT_EQ(*ParseUtcIso8601("1969-12-31T23:59:59.999999Z"), -1000);
  EXPECT_EQ(*ParseUtcIso8601("2024-02-29T00:00:00.000000Z") % kSecondNs, 0);
}

TEST(UtcTime, RefusesAnyOtherLayoutOrAnImpossibleDate) {
  for (const char* text : {"2026-12-02T06:12:03Z", "2026-12-02T06:12:03.123456",
                           "2026-12-02 06:12:03.123456Z", "2026-12-02T06:12:03.12345Z", "2026-02-30T00:00:00.000000Z",
                           "2026-12-02T24:00:00.000000Z", "+026-12-02T06:12:03.123456Z", ""}) {
    EXPECT_FALSE(ParseUtcIso8601(text).has_value()) << text;
  }
}

TEST(UtcTime, NowIsTheWallClockAndMonotonicNeverGoesBack) {
  const std::int64_t before = UtcNowNs();
  const auto parsed = ParseUtcIso8601(UtcNowIso8601());
  const std::int64_t after = UtcNowNs();
  ASSERT_TRUE(parsed.has_value());
  EXPECT_GE(*parsed, before / 1000 * 1000);
  EXPECT_LE(*parsed, after);
  const std::int64_t m0 = MonotonicNowNs();
  EXPECT_GE(MonotonicNowNs(), m0);
}

}  // namespace
}  // namespace irdist
