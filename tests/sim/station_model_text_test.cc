#include "sim/station_model_text.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

// The station protocol's text as the emulator reads and writes it. Expected values come from
// docs/station-protocol.md: integers of an optional sign and 1-12 characters of decimal digits,
// quantities in 0.01 units (`MOVE 250000,-1050,0` = 2500.00 mm, -10.50 deg, 0), and the table of
// error codes and messages (section 5).

namespace irdist::sim {
namespace {

StationRequest RequestWith(std::vector<std::string> args) {
  StationRequest r;
  r.header = "MOVE";
  r.args = std::move(args);
  return r;
}

TEST(ParseProtocolInt, AcceptsSignedDecimalIntegersOfUpToTwelveCharacters) {
  long long v = 0;
  ASSERT_TRUE(ParseProtocolInt("250000", &v));
  EXPECT_EQ(v, 250000);
  ASSERT_TRUE(ParseProtocolInt("-1050", &v));
  EXPECT_EQ(v, -1050);
  ASSERT_TRUE(ParseProtocolInt("+7", &v));
  EXPECT_EQ(v, 7);
  ASSERT_TRUE(ParseProtocolInt("-99999999999", &v));  // 12 characters with the sign
  EXPECT_EQ(v, -99999999999LL);
  ASSERT_TRUE(ParseProtocolInt("999999999999", &v));
  EXPECT_EQ(v, 999999999999LL);
}

TEST(ParseProtocolInt, RefusesEmptySignOnlyTooLongAndNonDigitText) {
  long long v = 12345;
  for (const char* bad : {"", "-", "+", "1000000000000", "12.5", "1e3", " 12", "12 ", "0x1F",
                          "--3", "1,2", "abc"}) {
    EXPECT_FALSE(ParseProtocolInt(bad, &v)) << "'" << bad << "' was accepted";
  }
  EXPECT_EQ(v, 12345) << "a refused text changed the value";
}

// MOVE takes exactly three integers: too few -109, too many -108, a non-integer -104.
TEST(StationRequest, IntsCountsAndTypesTheParametersWithTheProtocolsCodes) {
  std::vector<long long> out;
  EXPECT_EQ(RequestWith({"250000", "-1050", "0"}).Ints(3, &out), 0);
  EXPECT_EQ(out, (std::vector<long long>{250000, -1050, 0}));
  out.clear();
  EXPECT_EQ(RequestWith({"250000", "-1050"}).Ints(3, &out), -109);
  EXPECT_EQ(RequestWith({"1", "2", "3", "4"}).Ints(3, &out), -108);
  EXPECT_EQ(RequestWith({"1", "2.5", "3"}).Ints(3, &out), -104);
  EXPECT_EQ(RequestWith({}).NoArgs(), 0);
  EXPECT_EQ(RequestWith({"1"}).NoArgs(), -108);
}

// SPEED <axis>,<v>: the axis name in any case, then the integers; an unknown axis is -104.
TEST(StationRequest, AxisAndIntsNamesSlidePanTiltInAnyCase) {
  int axis = -7;
  std::vector<long long> out;
  EXPECT_EQ(RequestWith({"slide", "5000"}).AxisAndInts(1, &axis, &out), 0);
  EXPECT_EQ(axis, 0);
  EXPECT_EQ(out, (std::vector<long long>{5000}));
  out.clear();
  EXPECT_EQ(RequestWith({"Pan", "300"}).AxisAndInts(1, &axis, &out), 0);
  EXPECT_EQ(axis, 1);
  out.clear();
  EXPECT_EQ(RequestWith({"TILT", "-20"}).AxisAndInts(1, &axis, &out), 0);
  EXPECT_EQ(axis, 2);
  EXPECT_EQ(out, (std::vector<long long>{-20}));
  out.clear();
  EXPECT_EQ(RequestWith({"ROLL", "1"}).AxisAndInts(1, &axis, &out), -104);
  EXPECT_EQ(RequestWith({"PAN"}).AxisAndInts(1, &axis, &out), -109);
  EXPECT_EQ(RequestWith({"PAN", "1", "2"}).AxisAndInts(1, &axis, &out), -108);
  EXPECT_EQ(RequestWith({"PAN", "x"}).AxisAndInts(1, &axis, &out), -104);
}

TEST(ErrorFor, EveryCodeOfTheProtocolsTableHasItsMessage) {
  const std::vector<std::pair<int, std::string>> table = {
      {-102, "Syntax error"},         {-104, "Data type error"},
      {-108, "Parameter not allowed"}, {-109, "Missing parameter"},
      {-113, "Undefined header"},     {-221, "Settings conflict"},
      {-222, "Data out of range"},    {-350, "Queue overflow"},
      {201, "Not homed"},             {202, "Emergency stop active"},
      {203, "Checksum mismatch"},     {204, "Homing failed"},
      {205, "Line too long"},         {206, "Link lost"}};
  for (const auto& [code, message] : table) {
    const CommandError e = ErrorFor(code);
    EXPECT_EQ(e.code, code);
    EXPECT_EQ(e.message, message) << code;
  }
  EXPECT_EQ(ErrorFor(299).message, "Execution error");
  EXPECT_EQ(ErrorFor(299).code, 299);
}

TEST(SplitCommas, SplitsAtCommasDroppingSpacesAndKeepsEmptyFields) {
  EXPECT_EQ(SplitCommas("a, b,c"), (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_EQ(SplitCommas(""), std::vector<std::string>{});
  EXPECT_EQ(SplitCommas("SLIDE"), std::vector<std::string>{"SLIDE"});
  EXPECT_EQ(SplitCommas("1,,3"), (std::vector<std::string>{"1", "", "3"}));
  EXPECT_EQ(SplitCommas("1,"), (std::vector<std::string>{"1", ""}));
  EXPECT_EQ(Upper("sour:curr?"), "SOUR:CURR?");
}

// 2500 mm, -10.5 deg and 0 are "250000,-1050,0" (the protocol's own MOVE example); values round
// to the nearest 0.01, halves away from zero.
TEST(Centi, WritesValuesInTheProtocolsHundredthsRoundedToNearest) {
  EXPECT_EQ(CentiList({2500.0, -10.5, 0.0}), "250000,-1050,0");
  EXPECT_EQ(Centi(12.344), 1234);
  EXPECT_EQ(Centi(12.346), 1235);
  EXPECT_EQ(Centi(-0.006), -1);
  EXPECT_EQ(Centi(0.125), 13);  // 12.5 hundredths (exact in binary): away from zero
  EXPECT_EQ(CentiList({}), "");
  EXPECT_EQ(CentiList({1.0}), "100");
}

}  // namespace
}  // namespace irdist::sim
