#include "estimator/model_file_bounds.h"

#include <gtest/gtest.h>

#include <limits>
#include <string>

namespace irdist {
namespace {

// A model with a fitted blur over 1000..3500 mm and a provenance, inside every bound.
CalibrationModel Fitted() {
  CalibrationModel model;
  model.ranges.d_min_mm = 1000.0;
  model.ranges.d_max_mm = 3500.0;
  BlurCalibration& b = model.blur_calibration;
  b.c0_px2 = 0.9;
  b.c1_px2 = 0.2;
  b.noise_at_1m_px2 = 0.01;
  b.noise_exponent = 1.0;
  b.frames = 40;
  ModelProvenance& p = model.provenance;
  p.known = true;
  p.pixel_format = "Mono12p";
  p.bit_depth = 12;
  p.roi_width = 256;
  p.roi_height = 256;
  p.t_ref_ms = 8.0;
  p.t_meas_ms = {30.0, 32.0};
  return model;
}

std::string Keys(const std::vector<ModelBoundFailure>& failures) {
  std::string keys;
  for (const ModelBoundFailure& f : failures) keys += f.key + "; ";
  return keys;
}

TEST(ModelFileBounds, AFittedModelIsInside) { EXPECT_EQ(Keys(CheckModelBounds(Fitted())), ""); }

// Regression: a defocused lens fits fit_offset_u_px2 -0.573 over a blur of about 1 px^2: the blob
// fit's blur stays a positive variance, so it is inside (it was refused outside [-0.5, 0.5]).
TEST(ModelFileBounds, ADefocusedLensOffsetIsInside) {
  CalibrationModel model = Fitted();
  model.blur_calibration.fit_offset_u_px2 = -0.573;
  EXPECT_EQ(Keys(CheckModelBounds(model)), "");
}

// The same offset on a sharp lens's blur (0.3 px^2) makes the fit's blur negative near the
// camera: refused naming the key, the distance and the physics.
TEST(ModelFileBounds, AnOffsetThatMakesTheBlurNegativeIsRefused) {
  CalibrationModel model = Fitted();
  model.blur_calibration.c0_px2 = 0.3;
  model.blur_calibration.c1_px2 = 0.0;
  model.blur_calibration.fit_offset_u_px2 = -0.573;
  const std::vector<ModelBoundFailure> failures = CheckModelBounds(model);
  ASSERT_EQ(failures.size(), 1u) << Keys(failures);
  EXPECT_EQ(failures[0].key, "blur_calibration.fit_offset_u_px2");
  EXPECT_NE(failures[0].message.find("d = 1000 mm"), std::string::npos) << failures[0].message;
  EXPECT_NE(failures[0].message.find("(0, 16] px^2"), std::string::npos) << failures[0].message;
}

// The PSF's anisotropy (an astigmatic lens): 0.3 px^2 on a blur of about 1 px^2 is inside; one
// longer than the optics' blur at the far end (no elliptical PSF has a negative variance) is
// refused naming the key, the distance and why.
TEST(ModelFileBounds, APsfAnisotropyBeyondTheBlurIsRefused) {
  CalibrationModel model = Fitted();
  model.blur_calibration.psf_aniso_c_px2 = 0.15;
  model.blur_calibration.psf_aniso_s_px2 = 0.26;
  EXPECT_EQ(Keys(CheckModelBounds(model)), "");
  model.blur_calibration.psf_aniso_s_px2 = 0.9;
  const std::vector<ModelBoundFailure> failures = CheckModelBounds(model);
  ASSERT_EQ(failures.size(), 1u) << Keys(failures);
  EXPECT_EQ(failures[0].key, "blur_calibration.psf_aniso_c_px2");
  EXPECT_NE(failures[0].message.find("d = 3500 mm"), std::string::npos) << failures[0].message;
  EXPECT_NE(failures[0].message.find("both > 0"), std::string::npos) << failures[0].message;
  model.blur_calibration.psf_aniso_s_px2 = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(Keys(CheckModelBounds(model)).find("psf_aniso_s_px2"), std::string::npos);
}

// Regression: blur_var_px2 [-5, 0, 0] or [1e300, 0, 0] were loaded and used.
TEST(ModelFileBounds, ABlurThatIsNoVarianceIsRefused) {
  for (double c0 : {-5.0, 1e300, 16.5}) {
    SCOPED_TRACE(c0);
    CalibrationModel model = Fitted();
    model.blur_calibration.c0_px2 = c0;
    model.blur_calibration.c1_px2 = 0.0;
    const std::string keys = Keys(CheckModelBounds(model));
    EXPECT_NE(keys.find("blur_calibration.blur_var_px2"), std::string::npos) << keys;
  }
}

TEST(ModelFileBounds, NoiseAndShareOutsideAreRefused) {
  CalibrationModel model = Fitted();
  model.blur_calibration.noise_exponent = 1e300;
  model.blur_calibration.crosstalk_lattice_share = 1.5;
  model.blur_calibration.optics_excess = -3.5;
  EXPECT_EQ(Keys(CheckModelBounds(model)),
            "blur_calibration.noise_exponent; blur_calibration.crosstalk_lattice_share; "
            "blur_calibration.optics_excess; ");
}

// Regression: t_ref_ms 1e300 and t_meas_ms [-30, 0] passed in a provenance.
TEST(ModelFileBounds, ProvenanceExposuresOutsideAreRefused) {
  CalibrationModel model = Fitted();
  model.provenance.t_ref_ms = 1e300;
  EXPECT_EQ(Keys(CheckModelBounds(model)), "provenance.t_ref_ms; provenance.t_meas_ms[0]; "
                                           "provenance.t_meas_ms[1]; ");
  model = Fitted();
  model.provenance.t_meas_ms = {-30.0, 0.0};
  const std::string keys = Keys(CheckModelBounds(model));
  EXPECT_NE(keys.find("provenance.t_meas_ms[0]"), std::string::npos) << keys;
  EXPECT_NE(keys.find("provenance.t_meas_ms[1]"), std::string::npos) << keys;
}

// The provenance's pixel format is a monochrome camera format agreeing with its bit depth.
TEST(ModelFileBounds, APixelFormatThatContradictsTheBitDepthIsRefused) {
  CalibrationModel model = Fitted();
  model.provenance.pixel_format = "Mono16";
  EXPECT_EQ(Keys(CheckModelBounds(model)), "provenance.bit_depth; ");
  model.provenance.pixel_format = "BayerRG8";
  EXPECT_EQ(Keys(CheckModelBounds(model)), "provenance.pixel_format; ");
  model.provenance.pixel_format = "Mono12Packed";
  EXPECT_EQ(Keys(CheckModelBounds(model)), "");
}

// Regression: features.window_side_px 512 on a 256 px ROI was an internal check failure.
TEST(ModelFileBounds, AWindowLargerThanTheRoiIsRefused) {
  CalibrationModel model = Fitted();
  model.features.window_side_px = 512;
  const std::vector<ModelBoundFailure> failures = CheckModelBounds(model);
  ASSERT_EQ(failures.size(), 1u) << Keys(failures);
  EXPECT_EQ(failures[0].key, "features.window_side_px");
  EXPECT_NE(failures[0].message.find("at most 256"), std::string::npos) << failures[0].message;
}

TEST(ModelFileBounds, FitnessOutsideIsRefused) {
  CalibrationModel model = Fitted();
  CalibrationFitness& f = model.fitness;
  f.assessed = true;
  f.poses = 10;
  f.dof = 20;
  f.reduced_chi2 = 1.0;
  f.limit = 1.5;
  f.pose_limit = 20.0;
  f.tail_probability = 1e-3;
  f.size_floor = 0.004;
  f.difference_floor = 0.004;
  f.worst.push_back({{2000.0, 10.0, 0.0, 500.0}, 3.0, 4, 1.0, "size", 0.2});
  EXPECT_EQ(Keys(CheckModelBounds(model)), "");
  f.tail_probability = 0.0;
  f.size_floor = 2.0;
  f.poses_over = 11;
  f.worst[0].pose.pan_deg = 400.0;
  f.worst[0].chi2 = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(Keys(CheckModelBounds(model)),
            "fitness.tail_probability; fitness.size_floor; fitness.poses_over; "
            "fitness.worst_poses[0].pan_deg; fitness.worst_poses[0].chi2; ");
  f.assessed = false;  // not assessed: nothing of it is written or checked
  EXPECT_EQ(Keys(CheckModelBounds(model)), "");
}

}  // namespace
}  // namespace irdist
