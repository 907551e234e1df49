// The features' options and names (estimator/feature_options.cc): every name round-trips through
// its parser, the inverse response's curve and checks, the options' checks naming the field, the
// paper's options and a frame linearised through a curve.
#include <gtest/gtest.h>

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

#include "base/check.h"
#include "estimator/features.h"

namespace irdist {
namespace {

TEST(FeatureOptions, EveryNameRoundTripsThroughItsParser) {
  for (RoiPolicy p : {RoiPolicy::kFixedWindow, RoiPolicy::kThreshold}) {
    RoiPolicy read = p == RoiPolicy::kThreshold ? RoiPolicy::kFixedWindow : RoiPolicy::kThreshold;
    EXPECT_TRUE(ParseRoiPolicy(ToString(p), &read));
    EXPECT_EQ(read, p);
  }
  for (MomentMethod m : {MomentMethod::kThreshold, MomentMethod::kAperture}) {
    MomentMethod read =
        m == MomentMethod::kAperture ? MomentMethod::kThreshold : MomentMethod::kAperture;
    EXPECT_TRUE(ParseMomentMethod(ToString(m), &read));
    EXPECT_EQ(read, m);
  }
  for (EllipseMethod e :
       {EllipseMethod::kMoments, EllipseMethod::kContour, EllipseMethod::kModelFit}) {
    EllipseMethod read =
        e == EllipseMethod::kMoments ? EllipseMethod::kContour : EllipseMethod::kMoments;
    EXPECT_TRUE(ParseEllipseMethod(ToString(e), &read));
    EXPECT_EQ(read, e);
  }
  for (ResponseScope s : {ResponseScope::kERelOnly, ResponseScope::kAllPixels}) {
    ResponseScope read =
        s == ResponseScope::kERelOnly ? ResponseScope::kAllPixels : ResponseScope::kERelOnly;
    EXPECT_TRUE(ParseResponseScope(ToString(s), &read));
    EXPECT_EQ(read, s);
  }
  EXPECT_EQ(std::string(ToString(EllipseMethod::kModelFit)), "model_fit");
  RoiPolicy untouched = RoiPolicy::kThreshold;
  EXPECT_FALSE(ParseRoiPolicy("Threshold", &untouched));  // names are exact
  EXPECT_EQ(untouched, RoiPolicy::kThreshold);
  MomentMethod moment = MomentMethod::kAperture;
  EXPECT_FALSE(ParseMomentMethod("", &moment));
  ResponseScope scope = ResponseScope::kERelOnly;
  EXPECT_FALSE(ParseResponseScope("all", &scope));
  EllipseMethod ellipse = EllipseMethod::kMoments;
  EXPECT_FALSE(ParseEllipseMethod("fit", &ellipse));
}

TEST(InverseResponse, InterpolatesBetweenItsKnotsAndHoldsBeyond) {
  InverseResponse identity;
  EXPECT_TRUE(identity.IsIdentity());
  EXPECT_DOUBLE_EQ(identity.Apply(0.3), 0.3);
  InverseResponse curve;
  curve.m = {0.0, 0.5, 1.0};
  curve.f = {0.0, 0.25, 1.0};
  EXPECT_DOUBLE_EQ(curve.Apply(0.25), 0.125);
  EXPECT_DOUBLE_EQ(curve.Apply(0.75), 0.625);
  curve.m = {0.2, 0.8};
  curve.f = {0.1, 0.7};
  EXPECT_DOUBLE_EQ(curve.Apply(0.0), 0.1);  // held at the first knot
  EXPECT_DOUBLE_EQ(curve.Apply(1.0), 0.7);  // and at the last
}

TEST(InverseResponse, RefusesABadCurveWithTheReason) {
  std::string why;
  InverseResponse c;
  c.m = {0.0, 1.0};
  c.f = {0.0};
  EXPECT_FALSE(c.IsValid(&why));
  EXPECT_NE(why.find("differ in length"), std::string::npos) << why;
  c.m = {0.5};
  EXPECT_FALSE(c.IsValid(&why));
  EXPECT_NE(why.find("two knots"), std::string::npos) << why;
  c.m = {0.0, 1.5};
  c.f = {0.0, 1.0};
  EXPECT_FALSE(c.IsValid(&why));
  EXPECT_NE(why.find("[0,1]"), std::string::npos) << why;
  c.m = {0.5, 0.5};
  EXPECT_FALSE(c.IsValid(&why));
  EXPECT_NE(why.find("increase strictly"), std::string::npos) << why;
  c.m = {0.0, 1.0};
  c.f = {1.0, 0.0};
  EXPECT_FALSE(c.IsValid(&why));
  EXPECT_NE(why.find("monotone"), std::string::npos) << why;
}

TEST(FeatureOptions, RefusesEachBadFieldByName) {
  std::string why;
  EXPECT_TRUE(FeatureOptions().IsValid(&why)) << why;
  FeatureOptions o;
  o.window_side_px = 4;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why.rfind("window_side_px", 0), 0u) << why;
  o = FeatureOptions();
  o.threshold_fraction = 1.0;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why.rfind("threshold_fraction", 0), 0u) << why;
  o = FeatureOptions();
  o.detection_downsample = 17;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why.rfind("detection_downsample", 0), 0u) << why;
  o = FeatureOptions();
  o.response_scope = ResponseScope::kAllPixels;
  o.inverse_response.m = {0.0, 1.0};
  o.inverse_response.f = {0.5, 0.5};  // flat: nothing to scale every pixel by
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("all_pixels"), std::string::npos) << why;
}

TEST(FeatureOptions, ThePapersOptionsAreAFixedWindowOfTheWholeSignal) {
  const FeatureOptions paper = PaperFeatureOptions();
  EXPECT_EQ(paper.roi_policy, RoiPolicy::kFixedWindow);
  EXPECT_EQ(paper.window_side_px, 64);
  EXPECT_FALSE(paper.subtract_background);
  EXPECT_TRUE(paper.IsValid(nullptr));
}

// A frame through the curve f(g) = g^2 on 8 bits: each level to 16 bits; stray high bits to full.
TEST(LineariseFrame, MapsEachLevelThroughTheCurve) {
  InverseResponse square;
  for (int k = 0; k <= 10; ++k) {
    square.m.push_back(k / 10.0);
    square.f.push_back((k / 10.0) * (k / 10.0));
  }
  cv::Mat frame(1, 4, CV_16UC1);
  frame.at<std::uint16_t>(0, 0) = 0;
  frame.at<std::uint16_t>(0, 1) = 255;
  frame.at<std::uint16_t>(0, 2) = 4000;  // above 8 bits
  frame.at<std::uint16_t>(0, 3) = 128;   // 0.50196: f = 0.25 + 0.0196 * 0.11 on the 0.5-0.6 knot
  const cv::Mat out = LineariseFrame(frame, 8, square);
  EXPECT_EQ(out.at<std::uint16_t>(0, 0), 0);
  EXPECT_EQ(out.at<std::uint16_t>(0, 1), 65535);
  EXPECT_EQ(out.at<std::uint16_t>(0, 2), 65535);
  EXPECT_EQ(out.at<std::uint16_t>(0, 3), 16525);                          // 65535 x 0.252157
  EXPECT_THROW(LineariseFrame(frame, 8, InverseResponse()), CheckError);  // the identity
}

}  // namespace
}  // namespace irdist
