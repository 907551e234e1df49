// measure --track's session: the exposure it tracks at and its refusal. The grabber's accounting of
// every frame is tested in tests/app/live/frame_grabber_test.cc, the track line's JSON, the
// bracket's check against the track and the latency quantiles in track_output_test.cc; the live
// command in tests/integration/measure_track_test.cc.
#include "app/live/track_session.h"

#include <gtest/gtest.h>

#include "app/inputs/errors.h"

namespace irdist {
namespace {

TEST(TrackExposureMs, TheModelsReferenceByDefaultAndOutsideTheCalibrationRefused) {
  CalibrationModel model;
  model.provenance.t_ref_ms = 8.0;
  model.ranges.t_ref_min_ms = model.ranges.t_ref_max_ms = 8.0;
  model.ranges.t_min_ms = 30.0;
  model.ranges.t_max_ms = 36.0;
  MeasureArgs args;
  args.model = "model.yaml";
  EXPECT_DOUBLE_EQ(TrackExposureMs(args, model), 8.0);
  args.exposure_ms = 33.0;
  EXPECT_DOUBLE_EQ(TrackExposureMs(args, model), 33.0);
  args.exposure_ms = 20.0;
  EXPECT_THROW(TrackExposureMs(args, model), UsageError);
}

}  // namespace
}  // namespace irdist
