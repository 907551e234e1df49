#include "estimator/theta_start.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "base/check.h"

namespace irdist {
namespace {

constexpr double kDeg = M_PI / 180.0;

// A sharp rig: the disc's variance 30 px^2 at 1 m (alpha), a fixed blur of 1 px^2 (beta).
CalibrationModel SharpRig() {
  CalibrationModel model;
  model.geometric.alpha_px2 = 30.0;
  model.geometric.beta_px2 = 1.0;
  return model;
}

// One frame of a disc tilted by theta_deg at d_mm: the uniform disc's variance alpha u^2 along
// its major axis, times cos^2(theta) along its minor axis, plus the blur on both.
Features Frame(const CalibrationModel& model, double d_mm, double theta_deg, double angle_deg,
               double signal, double blur_px2) {
  const double u = 1000.0 / d_mm;
  const double disc = model.geometric.alpha_px2 * u * u;
  const double c = std::cos(theta_deg * kDeg);
  Features f;
  f.blob_found = true;
  f.moment_major_var_px2 = disc + blur_px2;
  f.moment_minor_var_px2 = disc * c * c + blur_px2;
  f.ellipse_moments.valid = true;
  f.ellipse_moments.angle_deg = angle_deg;
  f.background = 0.01;
  f.roi_area_px = 1000;
  f.f00 = f.background * f.roi_area_px + signal;
  f.theta0_deg = -1.0;  // a value no geometry gives: shows when the features' own theta is used
  return f;
}

double Combined(const CalibrationModel& model, const std::vector<Features>& frames,
                const Features& fallback, const ThetaStartOptions& options) {
  std::vector<const Features*> pointers;
  for (const Features& f : frames) pointers.push_back(&f);
  return Theta0Combined(model, pointers.data(), static_cast<int>(pointers.size()), fallback,
                        options);
}

TEST(ThetaStartOptions, OneSourceAtMost) {
  ThetaStartOptions options;
  std::string why;
  EXPECT_TRUE(options.IsValid(&why));
  EXPECT_TRUE(why.empty());
  options.from_features = true;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("both"), std::string::npos) << why;
  const CalibrationModel model = SharpRig();
  const Features f = Frame(model, 2000.0, 30.0, 0.0, 5.0, 1.0);
  try {
    Theta0Combined(model, nullptr, 0, f, options);
    FAIL() << "both sources set must be refused";
  } catch (const CheckError& e) {
    EXPECT_NE(std::string(e.what()).find("from_features and bracket_moments"), std::string::npos)
        << e.what();
  }
}

// A bracket of one disc at 40 deg, its frames of different brightness: the blur removed, the
// axis ratio is cos(40 deg) whatever the exposure.
TEST(Theta0Combined, BracketOfOneTiltGivesThatTilt) {
  const CalibrationModel model = SharpRig();
  const std::vector<Features> frames = {Frame(model, 2000.0, 40.0, 25.0, 2.0, 1.0),
                                        Frame(model, 2000.0, 40.0, 25.0, 9.0, 1.0)};
  const Features fallback = Frame(model, 2000.0, 10.0, 25.0, 2.0, 1.0);
  EXPECT_NEAR(Combined(model, frames, fallback, ThetaStartOptions()), 40.0, 1e-9);
  // The same frame with the major axis's direction given as its opposite (angle + 180 deg).
  const std::vector<Features> turned = {Frame(model, 2000.0, 40.0, 25.0, 2.0, 1.0),
                                        Frame(model, 2000.0, 40.0, 205.0, 9.0, 1.0)};
  EXPECT_NEAR(Combined(model, turned, fallback, ThetaStartOptions()), 40.0, 1e-9);
}

// The frames' moment matrices are averaged, weighted by their signal, before the axes are found:
// two equal ellipses crossed at 90 deg with equal signal average to a circle (theta 0); with
// signals 3:1 the mean matrix is diag((3 l1 + l2) / 4, (l1 + 3 l2) / 4).
TEST(Theta0Combined, MomentMatricesAreAveragedBySignal) {
  const CalibrationModel model = SharpRig();
  const Features fallback = Frame(model, 2000.0, 10.0, 0.0, 2.0, 1.0);
  const std::vector<Features> crossed = {Frame(model, 2000.0, 50.0, 0.0, 4.0, 1.0),
                                         Frame(model, 2000.0, 50.0, 90.0, 4.0, 1.0)};
  EXPECT_NEAR(Combined(model, crossed, fallback, ThetaStartOptions()), 0.0, 1e-6);

  const std::vector<Features> weighted = {Frame(model, 2000.0, 50.0, 0.0, 6.0, 1.0),
                                          Frame(model, 2000.0, 50.0, 90.0, 2.0, 1.0)};
  const double l1 = weighted[0].moment_major_var_px2, l2 = weighted[0].moment_minor_var_px2;
  const double major = (3.0 * l1 + l2) / 4.0 - 1.0, minor = (l1 + 3.0 * l2) / 4.0 - 1.0;
  EXPECT_NEAR(Combined(model, weighted, fallback, ThetaStartOptions()),
              std::acos(std::sqrt(minor / major)) / kDeg, 1e-9);
}

// With a blur that varies with distance, the blur removed is b(u) at the geometric distance the
// major axis implies: 0.5 + 0.4 u + 0.8 u^2 = 0.9 px^2 at 2 m.
TEST(Theta0Combined, RemovesTheBlurAtTheGeometricDistance) {
  CalibrationModel model = SharpRig();
  model.geometric.beta_px2 = 0.5;
  model.geometric.blur_u1_px2 = 0.4;
  model.geometric.blur_u2_px2 = 0.8;
  const std::vector<Features> frames = {Frame(model, 2000.0, 35.0, 10.0, 3.0, 0.9)};
  EXPECT_NEAR(Combined(model, frames, frames[0], ThetaStartOptions()), 35.0, 1e-9);
}

// No frame with moments (no blob, no signal above the background): theta from the fallback
// frame alone, with the blob fit's own blur where it is known rather than the model's.
TEST(Theta0Combined, FallsBackToOneFrameWithItsOwnBlur) {
  const CalibrationModel model = SharpRig();
  Features no_blob = Frame(model, 2000.0, 40.0, 0.0, 3.0, 1.0);
  no_blob.blob_found = false;
  Features dark = Frame(model, 2000.0, 40.0, 0.0, 0.0, 1.0);
  Features fallback = Frame(model, 2000.0, 25.0, 0.0, 3.0, 0.3);
  fallback.size_blur_var_px2 = 0.3;
  EXPECT_NEAR(Combined(model, {no_blob, dark}, fallback, ThetaStartOptions()), 25.0, 1e-9);
  // bracket_moments off: the fallback frame, whatever the bracket holds.
  ThetaStartOptions one_frame;
  one_frame.bracket_moments = false;
  const std::vector<Features> bracket = {Frame(model, 2000.0, 40.0, 0.0, 3.0, 1.0)};
  EXPECT_NEAR(Combined(model, bracket, fallback, one_frame), 25.0, 1e-9);
}

// The features' own theta0 where asked for, where the model has no geometric fit, and where the
// blob is not larger than the blur.
TEST(Theta0Combined, FeaturesThetaWhereTheMomentsCannotSay) {
  const CalibrationModel model = SharpRig();
  Features fallback = Frame(model, 2000.0, 25.0, 0.0, 3.0, 1.0);
  fallback.theta0_deg = 17.0;
  const std::vector<Features> bracket = {Frame(model, 2000.0, 40.0, 0.0, 3.0, 1.0)};
  ThetaStartOptions from_features;
  from_features.from_features = true;
  from_features.bracket_moments = false;
  EXPECT_EQ(Combined(model, bracket, fallback, from_features), 17.0);
  EXPECT_EQ(Combined(CalibrationModel(), bracket, fallback, ThetaStartOptions()), 17.0);
  Features blur_only = fallback;
  blur_only.moment_major_var_px2 = blur_only.moment_minor_var_px2 = 0.8;  // below beta = 1
  EXPECT_EQ(Combined(model, {}, blur_only, ThetaStartOptions()), 17.0);
}

// A fitted theta correction (cos^2 = 0.1 + 0.8 x, degree 1) is applied to the combined ratio x
// unless the options turn it off.
TEST(Theta0Combined, AppliesTheCalibratedCorrectionWhenAsked) {
  CalibrationModel model = SharpRig();
  model.theta_correction.degree = 1;
  model.theta_correction.coefficients = {0.1, 0.8, 0.0};
  model.theta_correction.d_min_mm = 1000.0;
  model.theta_correction.d_max_mm = 3000.0;
  const std::vector<Features> bracket = {Frame(model, 2000.0, 40.0, 0.0, 3.0, 1.0)};
  const double c = std::cos(40.0 * kDeg);
  EXPECT_NEAR(Combined(model, bracket, bracket[0], ThetaStartOptions()),
              std::acos(std::sqrt(0.1 + 0.8 * c * c)) / kDeg, 1e-9);
  ThetaStartOptions plain;
  plain.correction = false;
  EXPECT_NEAR(Combined(model, bracket, bracket[0], plain), 40.0, 1e-9);
}

}  // namespace
}  // namespace irdist
