// Calibration health: a blob whose blur moved from the calibration's is flagged only when the
// change is both significant (z_limit standard errors) and large enough to matter
// (min_sigma_change of the blur's sigma), with the label and advice estimates.csv carries.
#include "estimator/health.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "base/check.h"
#include "estimator/features.h"
#include "estimator/fit.h"

namespace irdist {
namespace {

// A model whose calibrated blur is 1 + 0.5 u px^2 (u = 1000 / d_mm), a frame's noise 0.04 px^2.
CalibrationModel ModelWithBlur() {
  CalibrationModel model;
  model.blur_calibration.c0_px2 = 1.0;
  model.blur_calibration.c1_px2 = 0.5;
  model.blur_calibration.noise_at_1m_px2 = 0.04;
  model.blur_calibration.noise_exponent = 0.0;
  model.blur_calibration.frames = 40;
  return model;
}

Features FrameWithBlur(double blur_var_px2) {
  Features f;
  f.blob_found = true;
  f.blur_var_px2 = blur_var_px2;
  return f;
}

// The measured blur variance whose sigma (pixel area removed) is (1 + change) x the calibrated.
double BlurWithSigmaChange(double calibrated_px2, double change) {
  return kPixelAreaVarPx2 + (calibrated_px2 - kPixelAreaVarPx2) * (1.0 + change) * (1.0 + change);
}

// n frames whose blur's sigma is (1 + sigma_change) x the calibrated at 2000 mm (1.25 px^2).
std::vector<Features> Frames(int n, double sigma_change) {
  return std::vector<Features>(n, FrameWithBlur(BlurWithSigmaChange(1.25, sigma_change)));
}

HealthCheck Check(const std::vector<Features>& frames, double d_mm = 2000.0) {
  std::vector<const Features*> pointers;
  for (const Features& f : frames) pointers.push_back(&f);
  return CheckHealth(ModelWithBlur(), d_mm, pointers);
}

TEST(HealthTest, BlurSigmaChangeRemovesThePixelArea) {
  EXPECT_NEAR(BlurSigmaChange(BlurWithSigmaChange(1.25, 0.2), 1.25), 0.2, 1e-12);
  EXPECT_NEAR(BlurSigmaChange(1.25, 1.25), 0.0, 1e-12);
  EXPECT_NEAR(BlurSigmaChange(kPixelAreaVarPx2, 1.25), -1.0, 1e-12);  // nothing but the pixel
}

TEST(HealthTest, NotAssessedWithoutACalibratedBlurOrAUsableFrame) {
  CalibrationModel no_blur;
  const Features frame = FrameWithBlur(1.25);
  EXPECT_FALSE(CheckHealth(no_blur, 2000.0, {&frame}).assessed);
  Features saturated = FrameWithBlur(1.25);
  saturated.saturated_pixels = 3;
  Features unmeasured = FrameWithBlur(NAN);
  const HealthCheck h = Check({saturated, unmeasured});
  EXPECT_FALSE(h.assessed);
  EXPECT_STREQ(h.Label(), "-");
  EXPECT_EQ(h.Advice(), "");
  EXPECT_FALSE(Check({FrameWithBlur(1.25)}, 0.0).assessed);  // no distance
}

TEST(HealthTest, TheCalibratedBlurIsOk) {
  const HealthCheck h = Check(Frames(8, 0.0));  // 1 + 0.5 x 0.5
  ASSERT_TRUE(h.assessed);
  EXPECT_EQ(h.frames, 8);
  EXPECT_DOUBLE_EQ(h.calibrated_px2, 1.25);
  EXPECT_NEAR(h.z, 0.0, 1e-9);
  EXPECT_FALSE(h.flagged);
  EXPECT_STREQ(h.Label(), "ok");
}

TEST(HealthTest, ALargerOrSmallerBlurIsFlaggedWithItsAdvice) {
  const HealthCheck larger = Check(Frames(8, 0.2));
  EXPECT_TRUE(larger.flagged);
  EXPECT_NEAR(larger.sigma_change, 0.2, 1e-12);
  // z: (measured - calibrated) / (0.04 / sqrt(8)).
  EXPECT_NEAR(larger.z, (larger.blur_var_px2 - 1.25) / (0.04 / std::sqrt(8.0)), 1e-9);
  EXPECT_STREQ(larger.Label(), "blur_larger");
  EXPECT_NE(larger.Advice().find("+20% from the calibration's"), std::string::npos)
      << larger.Advice();
  const HealthCheck smaller = Check(Frames(8, -0.2));
  EXPECT_TRUE(smaller.flagged);
  EXPECT_STREQ(smaller.Label(), "blur_smaller");
  EXPECT_NE(smaller.Advice().find("-20%"), std::string::npos) << smaller.Advice();
}

// Both conditions: many frames make a 3% change significant, but it is too small to matter; one
// frame leaves a 20% change within 5 standard errors.
TEST(HealthTest, FlaggedOnlyWhenSignificantAndLargeEnough) {
  const HealthCheck small = Check(Frames(400, 0.03));
  EXPECT_GT(std::fabs(small.z), HealthOptions().z_limit);
  EXPECT_FALSE(small.flagged);
  CalibrationModel noisy = ModelWithBlur();
  noisy.blur_calibration.noise_at_1m_px2 = 1.0;
  const Features frame = FrameWithBlur(BlurWithSigmaChange(1.25, 0.2));
  const HealthCheck single = CheckHealth(noisy, 2000.0, {&frame});
  EXPECT_LT(std::fabs(single.z), HealthOptions().z_limit);
  EXPECT_FALSE(single.flagged);
  HealthOptions strict;
  strict.z_limit = 0.1;
  EXPECT_TRUE(CheckHealth(noisy, 2000.0, {&frame}, strict).flagged);
}

// A frame with the blob fit's own blur `own_px2` (standard error `se_px2`), fitted with the
// calibrated blob-fit blur `given_px2`, and a cumulant blur far off both (a lens outside the
// Gaussian family: a halo reads +14% by the cumulants).
Features FrameWithOwnBlur(double own_px2, double se_px2, double given_px2) {
  Features f = FrameWithBlur(BlurWithSigmaChange(given_px2, 0.14));
  f.size_blur_var_px2 = given_px2;
  f.own_blur_var_px2 = own_px2;
  f.own_blur_se_px2 = se_px2;
  return f;
}

// The blob fit's own blur against the blur the fit was given, not the cumulants:
// a lens whose own blur is its calibration's is ok whatever its cumulants say; a focus change of
// the blob-fit blur is flagged with the figure's name.
TEST(HealthTest, JudgesTheBlobFitsOwnBlurAgainstTheCalibratedBlobFitBlur) {
  const std::vector<Features> same(4, FrameWithOwnBlur(0.80, 0.01, 0.80));
  const HealthCheck ok = Check(same);
  ASSERT_TRUE(ok.assessed);
  EXPECT_TRUE(ok.blob_fit);
  EXPECT_FALSE(ok.flagged);
  EXPECT_STREQ(ok.Label(), "ok");
  EXPECT_NEAR(ok.blur_var_px2, 0.80, 1e-12);
  EXPECT_NEAR(ok.blur_se_px2, 0.005, 1e-12);  // 0.01 / sqrt(4)
  // The blob-fit figure needs no distance: each frame's calibrated blur is the one it was given.
  EXPECT_TRUE(Check(same, NAN).assessed);
  const double wider = BlurWithSigmaChange(0.80, 0.30);
  const HealthCheck changed = Check(std::vector<Features>(4, FrameWithOwnBlur(wider, 0.01, 0.80)));
  EXPECT_TRUE(changed.flagged);
  EXPECT_STREQ(changed.Label(), "blur_larger");
  EXPECT_NEAR(changed.sigma_change, 0.30, 1e-9);
  // A change within the bracket's noise is not flagged (z = 0.025 / 0.05 < 5).
  const HealthCheck noisy =
      Check(std::vector<Features>(4, FrameWithOwnBlur(0.825, 0.10, 0.80)));
  EXPECT_TRUE(noisy.blob_fit);
  EXPECT_FALSE(noisy.flagged);
  // A refocused bracket's advice says it was measured through.
  HealthCheck refocused = changed;
  refocused.refocused = true;
  EXPECT_NE(refocused.Advice().find("measured with its own blur"), std::string::npos);
  EXPECT_EQ(changed.Advice().find("measured with its own blur"), std::string::npos);
}

// A frame without the blob fit's own blur (the moments path) keeps the cumulants' figure.
TEST(HealthTest, WithoutTheBlobFitsOwnBlurTheCumulantsJudge) {
  std::vector<Features> frames = Frames(4, 0.0);
  const HealthCheck h = Check(frames);
  EXPECT_TRUE(h.assessed);
  EXPECT_FALSE(h.blob_fit);
}


// The options refuse a bad field with its name, and the check refuses such options.
TEST(HealthOptions, RefusesEachBadFieldByName) {
  std::string why;
  EXPECT_TRUE(HealthOptions().IsValid(&why)) << why;
  HealthOptions z;
  z.z_limit = -1.0;
  EXPECT_FALSE(z.IsValid(&why));
  EXPECT_EQ(why.rfind("z_limit", 0), 0u) << why;
  HealthOptions change;
  change.min_sigma_change = 1.5;
  EXPECT_FALSE(change.IsValid(&why));
  EXPECT_EQ(why.rfind("min_sigma_change", 0), 0u) << why;
  EXPECT_THROW(CheckHealth(ModelWithBlur(), 2000.0, {}, change), CheckError);
}
}  // namespace
}  // namespace irdist
