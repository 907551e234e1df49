// The live camera's options (app/live/live_camera.h): each bad field refused with its name, and
// the camera refuses such options as a usage error before it opens anything. Opening a camera is
// tested through measure, snap and view (app/live/measure, app/live/view).
#include "app/live/live_camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "app/inputs/errors.h"

namespace irdist {
namespace {

TEST(LiveCameraOptions, DefaultsAreValid) {
  std::string why = "not touched";
  EXPECT_TRUE(LiveCameraOptions().IsValid(&why));
  EXPECT_EQ(why, "");
  LiveCameraOptions placed;
  placed.at = {2000.0, 10.0, 0.0, 500.0};
  placed.time_scale = 5.0;
  EXPECT_TRUE(placed.IsValid(&why)) << why;
}

TEST(LiveCameraOptions, RefusesEachBadFieldByName) {
  std::vector<std::pair<LiveCameraOptions, std::string>> cases;
  LiveCameraOptions o;
  o.rig_spec = "";
  cases.emplace_back(o, "rig_spec");
  for (const double time_scale : {-1.0, 0.001, 2000.0, double(NAN)}) {
    o = LiveCameraOptions();
    o.time_scale = time_scale;
    cases.emplace_back(o, "time_scale");
  }
  for (const std::vector<double>& at : {std::vector<double>{1.0, 2.0, 3.0},
                                        std::vector<double>{2000.0, 0.0, 0.0, -5.0}}) {
    o = LiveCameraOptions();
    o.at = at;
    cases.emplace_back(o, "at");
  }
  o = LiveCameraOptions();
  o.first_exposure_us = 0.0;
  cases.emplace_back(o, "first_exposure_us");
  o = LiveCameraOptions();
  o.longest_exposure_us = 100.0;  // shorter than the first, 8000 us
  cases.emplace_back(o, "longest_exposure_us");
  for (const int buffers : {0, 1001}) {
    o = LiveCameraOptions();
    o.buffer_count = buffers;
    cases.emplace_back(o, "buffer_count");
  }
  for (const auto& [options, field] : cases) {
    std::string why;
    EXPECT_FALSE(options.IsValid(&why)) << field;
    EXPECT_EQ(why.rfind(field, 0), 0u) << why;
  }
}

TEST(LiveCamera, RefusesInvalidOptionsAsAUsageError) {
  LiveCameraOptions options;
  options.buffer_count = 0;
  std::ostringstream err;
  try {
    LiveCamera camera(options, err);
    FAIL() << "opened with 0 buffers";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("buffer_count"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace irdist
