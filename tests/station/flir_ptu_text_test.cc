// The FLIR PTU's reply text (station/flir_ptu_text.h): what a resetting unit prints is told apart
// from another device's answers.
#include "station/flir_ptu_text.h"

#include <gtest/gtest.h>

namespace irdist::ptu_text {
namespace {

TEST(PtuText, PowerUpTextIsTheBannerOrInitializing) {
  EXPECT_TRUE(IsPowerUpText("Pan-Tilt Controller v3.4.2 (emulated, irdist)"));
  EXPECT_TRUE(IsPowerUpText("Initializing..."));
  EXPECT_TRUE(IsPowerUpText("INITIALIZING"));
  EXPECT_FALSE(IsPowerUpText("* Pan-Tilt Controller v3.4.2"));  // a version answer
  EXPECT_FALSE(IsPowerUpText("PP"));
  EXPECT_FALSE(IsPowerUpText("@01 0 OK IDLE -- 0"));
}

TEST(PtuText, ResetChatterIsPowerUpTextOrEchoedCommands) {
  for (const char* line : {"V", "PP", "PP2000", "TP -40", "PP 1200 TP-40 A", "Initializing..."}) {
    EXPECT_TRUE(IsResetChatter(line)) << line;
  }
  // Another device's answers, and the unit's own replies, are not.
  for (const char* line : {"@01 0 OK IDLE -- 0", "KEITHLEY INSTRUMENTS INC.,MODEL 2400",
                           "* 22", "! Illegal command", "OK IRDIST,1,abc", "PPPP", ""}) {
    EXPECT_FALSE(IsResetChatter(line)) << line;
  }
}

TEST(PtuText, LimitHitRateCommandsAndNumbers) {
  EXPECT_TRUE(IsLimitHit("!P"));
  EXPECT_TRUE(IsLimitHit(" ! T "));
  EXPECT_FALSE(IsLimitHit("! Illegal command"));
  EXPECT_TRUE(IsRateCommand("PS2000"));
  EXPECT_FALSE(IsRateCommand("PP2000"));
  double value = 0;
  ASSERT_TRUE(FirstNumber("Current Pan position is 22.", &value));
  EXPECT_EQ(value, 22.0);
  EXPECT_FALSE(FirstNumber("no number here", &value));
  EXPECT_TRUE(NamesAPanTiltUnit("* pan-tilt controller"));
}

}  // namespace
}  // namespace irdist::ptu_text
