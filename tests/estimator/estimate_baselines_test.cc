// The baselines the I0-free method is compared with (estimator/estimate_baselines.h).
#include "estimator/estimate_baselines.h"

#include <gtest/gtest.h>

#include "tests/estimator/synthetic.h"

namespace irdist {
namespace {

TEST(Estimate, GeometricBaseline) {
  const testing::SyntheticRig rig;
  CalibrationModel model = rig.ExactModel();
  model.geometric = FitGeometric(rig.Table3());
  const GeometricEstimate g = EstimateGeometric(model, rig.Frame(30.0, 500.0, 2345.0, 10.0, 10.0));
  ASSERT_TRUE(g.valid);
  EXPECT_NEAR(g.d_mm, 2345.0, 1e-6);
  Features none;
  EXPECT_FALSE(EstimateGeometric(model, none).valid);
}

}  // namespace
}  // namespace irdist
