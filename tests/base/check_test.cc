#include "base/check.h"

#include <gtest/gtest.h>

namespace irdist {
namespace {

int Half(int even) {
  IRDIST_CHECK(even % 2 == 0, "Half() wants an even number, got ", even);
  return even / 2;
}

TEST(Check, PassesThroughWhenTheConditionHolds) { EXPECT_EQ(Half(8), 4); }

TEST(Check, ThrowsWithFileLineConditionAndMessage) {
  try {
    Half(3);
    FAIL() << "IRDIST_CHECK did not throw";
  } catch (const CheckError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("check_test.cc:"), std::string::npos) << what;
    EXPECT_NE(what.find("even % 2 == 0"), std::string::npos) << what;
    EXPECT_NE(what.find("got 3"), std::string::npos) << what;
  }
}

TEST(Check, IsAnIrdistError) { EXPECT_THROW(Half(1), Error); }

}  // namespace
}  // namespace irdist
