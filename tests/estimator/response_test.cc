// Camera response recovery on frames rendered by the virtual rig's sensor (sim/sensor.cc: the ADC
// value x, black level included, becomes y = x - a x^2 / x_max). The true inverse is derived here
// from that formula, not from the code under test.
#include "estimator/response.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "sim/renderer.h"
#include "sim/rig_physics.h"

namespace irdist {
namespace {

constexpr int kSide = 160;

// The sensor's formula inverted: ADC value x before the nonlinearity, for the normalised gray m.
double TrueAdc(double m, double a, double x_max) {
  const double y = m * x_max;
  if (a == 0.0) return y;
  return x_max * (1.0 - std::sqrt(1.0 - 4.0 * a * y / x_max)) / (2.0 * a);
}

class ResponseTest : public ::testing::Test {
 protected:
  sim::RigPhysics Physics(double nonlinearity) {
    sim::RigPhysics physics =
        sim::LoadRigPhysics(std::string(IRDIST_SOURCE_DIR) + "/recipes/rigs/virtual.yaml");
    physics.sensor.nonlinearity = nonlinearity;
    return physics;
  }

  // Brackets of the calibration recipe's shape (t_r 8 ms, t_n 30..36 ms) at a few poses.
  std::vector<ExposureStack> Brackets(double nonlinearity, int poses = 6) {
    const sim::RigPhysics physics = Physics(nonlinearity);
    const sim::Renderer renderer(physics);
    const cv::Point origin(physics.sensor.width_px / 2 - kSide / 2,
                           physics.sensor.height_px / 2 - kSide / 2);
    const double d_mm[] = {1500.0, 2000.0, 2500.0, 3000.0, 1800.0, 2700.0};
    const double theta_deg[] = {0.0, 20.0, 35.0, 10.0, 30.0, 0.0};
    const double bias_ma[] = {500.0, 475.0, 500.0, 525.0, 550.0, 500.0};
    std::vector<ExposureStack> stacks;
    for (int p = 0; p < poses; ++p) {
      ExposureStack stack;
      for (double t_ms : {8.0, 30.0, 32.0, 34.0, 36.0}) {
        cv::Mat frame(kSide, kSide, CV_16UC1);
        renderer.Render(
            sim::StaticConditions(d_mm[p], theta_deg[p], 0.0, bias_ma[p], t_ms * 1e-3),
            ++frame_index_, sim::PixelFormat::kMono12, origin, frame);
        stack.frames.push_back(frame);
        stack.exposures_us.push_back(t_ms * 1000.0);
      }
      stacks.push_back(stack);
    }
    return stacks;
  }

  // Largest |f(m) - c (x(m) - black)| over [lo, hi] relative to f's rise there, with the scale c
  // fitted by least squares (f's scale is a convention: f(1) = 1).
  static double MaxDeviation(const InverseResponse& f, double a, double lo, double hi) {
    const double x_max = 4095.0, black = 16.0;
    std::vector<double> ms, fs, ts;
    for (int i = 0; i <= 200; ++i) {
      const double m = lo + (hi - lo) * i / 200.0;
      ms.push_back(m);
      fs.push_back(f.Apply(m));
      ts.push_back(TrueAdc(m, a, x_max) - black);
    }
    double num = 0.0, den = 0.0;
    for (size_t i = 0; i < ms.size(); ++i) {
      num += fs[i] * ts[i];
      den += ts[i] * ts[i];
    }
    const double c = num / den;
    double worst = 0.0;
    for (size_t i = 0; i < ms.size(); ++i) worst = std::max(worst, std::abs(fs[i] - c * ts[i]));
    return worst / (f.Apply(hi) - f.Apply(lo));
  }

  std::uint64_t frame_index_ = 0;
};

TEST_F(ResponseTest, DefaultOptionsAreValid) {
  std::string why;
  EXPECT_TRUE(ResponseOptions().IsValid(&why)) << why;
  ResponseOptions bad;
  bad.num_knots = 2;
  EXPECT_FALSE(bad.IsValid(&why));
  bad = ResponseOptions();
  bad.min_exposure_ratio = 1.0;
  EXPECT_FALSE(bad.IsValid(&why));
}

// The tolerance: 0.25 % of f's rise over the sampled gray levels. A straight line (a linear
// camera's curve) misses the a = 0.1 sensor's inverse by ~1.3 % there, so the bound is 5x tighter
// than "no correction".
TEST_F(ResponseTest, RecoversTheNonlinearSensorsInverse) {
  const double a = 0.1;
  const ResponseRecovery r = RecoverInverseResponse(Brackets(a), 12);
  SCOPED_TRACE(r.BriefReport());
  std::string why;
  ASSERT_TRUE(r.curve.IsValid(&why)) << why;
  EXPECT_DOUBLE_EQ(r.curve.Apply(1.0), 1.0);
  EXPECT_GT(r.gray_max - r.gray_min, 0.4);
  EXPECT_EQ(r.stacks_used, 6);
  const double deviation = MaxDeviation(r.curve, a, r.gray_min, r.gray_max);
  EXPECT_LT(deviation, 0.0025);
  // The same measure for a straight line (what a linear assumption gives) fails the bound.
  InverseResponse line;
  line.m = {0.0, 1.0};
  line.f = {0.0, 1.0};
  EXPECT_GT(MaxDeviation(line, a, r.gray_min, r.gray_max), 0.01);
  // The black level comes out of the data: 16 DN before the nonlinearity.
  EXPECT_NEAR(r.black_level, (16.0 - a * 16.0 * 16.0 / 4095.0) / 4095.0, 0.003);
  EXPECT_GT(r.linearity_error_pct, 1.0);
  EXPECT_LT(r.rms_relative_residual, 0.2);
  EXPECT_GT(r.condition_number, 1.0);
}

TEST_F(ResponseTest, LinearCameraGivesAStraightLine) {
  const ResponseRecovery r = RecoverInverseResponse(Brackets(0.0), 12);
  SCOPED_TRACE(r.BriefReport());
  EXPECT_LT(MaxDeviation(r.curve, 0.0, r.gray_min, r.gray_max), 0.0025);
  EXPECT_LT(r.linearity_error_pct, 0.3);
  EXPECT_NEAR(r.black_level, 16.0 / 4095.0, 0.003);
}

TEST_F(ResponseTest, OneExposureOnlyIsATypedError) {
  std::vector<ExposureStack> stacks = Brackets(0.1, 2);
  for (ExposureStack& s : stacks) {
    for (size_t i = 0; i < s.exposures_us.size(); ++i) s.exposures_us[i] = 35000.0;
  }
  try {
    RecoverInverseResponse(stacks, 12);
    FAIL() << "no error";
  } catch (const ResponseError& e) {
    EXPECT_NE(std::string(e.what()).find("two different exposures"), std::string::npos)
        << e.what();
  }
  // A single frame per stack too.
  for (ExposureStack& s : stacks) {
    s.frames.resize(1);
    s.exposures_us.resize(1);
  }
  EXPECT_THROW(RecoverInverseResponse(stacks, 12), ResponseError);
}

TEST_F(ResponseTest, SaturatedStackIsATypedError) {
  std::vector<ExposureStack> stacks = Brackets(0.0, 1);
  for (cv::Mat& frame : stacks.front().frames) {
    // Every pixel above black + 8 DN clipped at full scale: nothing usable remains.
    frame.setTo(4095, frame > 24);
  }
  try {
    RecoverInverseResponse(stacks, 12);
    FAIL() << "no error";
  } catch (const ResponseError& e) {
    EXPECT_NE(std::string(e.what()).find("saturate"), std::string::npos) << e.what();
  }
}

TEST_F(ResponseTest, NarrowBracketIsATypedError) {
  std::vector<ExposureStack> stacks = Brackets(0.1, 3);
  for (ExposureStack& s : stacks) {
    s.frames.erase(s.frames.begin());  // drop t_r: 30..36 ms only, ratio 1.2
    s.exposures_us.erase(s.exposures_us.begin());
  }
  try {
    RecoverInverseResponse(stacks, 12);
    FAIL() << "no error";
  } catch (const ResponseError& e) {
    EXPECT_NE(std::string(e.what()).find("widen the bracket"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace irdist
