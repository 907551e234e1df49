// The frame grabber's options (app/live/frame_grabber.h): each bad field refused with its name.
// The grabber itself runs against the virtual camera in app/live/track_session.
#include "app/live/frame_grabber.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace irdist {
namespace {

TEST(GrabberOptions, DefaultsAreValid) {
  std::string why = "not touched";
  EXPECT_TRUE(GrabberOptions().IsValid(&why));
  EXPECT_EQ(why, "");
}

TEST(GrabberOptions, RefusesEachBadFieldByName) {
  std::vector<std::pair<GrabberOptions, std::string>> cases;
  for (const double exposure_us : {0.0, -5.0, double(NAN), 2.0e8}) {
    GrabberOptions o;
    o.exposure_us = exposure_us;
    cases.emplace_back(o, "exposure_us");
  }
  for (const int ahead : {0, -1, 17}) {
    GrabberOptions o;
    o.ahead = ahead;
    cases.emplace_back(o, "ahead");
  }
  GrabberOptions timeout;
  timeout.frame_timeout = std::chrono::milliseconds(0);
  cases.emplace_back(timeout, "frame_timeout");
  for (const double tolerance : {0.0, 1.0, double(NAN)}) {
    GrabberOptions o;
    o.exposure_tolerance = tolerance;
    cases.emplace_back(o, "exposure_tolerance");
  }
  for (const auto& [options, field] : cases) {
    std::string why;
    EXPECT_FALSE(options.IsValid(&why)) << field;
    EXPECT_EQ(why.rfind(field, 0), 0u) << why;
  }
}

}  // namespace
}  // namespace irdist
