#include "estimator/blur_level.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "estimator/blur_model.h"
#include "estimator/refocus.h"

namespace irdist {

namespace {

// How far the search may move a frame's blur from the split's curve (FitBlurSplit's rounds move
// each frame's by at most 0.15 px^2 a round).
constexpr double kSearchPx2 = 0.3;
// Frames beyond this many robust sd of the curve are left out (a scene fault, a moving stage).
constexpr double kOutlierSd = 5.0;
// FitOffsetCurve bends the line where the bend's F statistic passes this (4 sd of one term) on
// at least this many points.
constexpr double kCurveF = 16.0;
constexpr int kMinCurvePoints = 8;

// The weighted least squares of the points' offsets on the first `terms` of (1, u, u^2): the
// coefficients into c (the rest 0) and the weighted sum of squared residuals.
double SolveOffset(const std::vector<OffsetPoint>& points, int terms, Eigen::Vector3d* c) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const OffsetPoint& p : points) {
    const Eigen::Vector3d m(1.0, p.u, p.u * p.u);
    a += p.weight * m * m.transpose();
    b += p.weight * p.offset_px2 * m;
  }
  c->setZero();
  c->head(terms) =
      a.topLeftCorner(terms, terms).completeOrthogonalDecomposition().solve(b.head(terms));
  double sum = 0.0;
  for (const OffsetPoint& p : points) {
    const double r = p.offset_px2 - OffsetCurvePx2((*c)(0), (*c)(1), (*c)(2), p.u);
    sum += p.weight * r * r;
  }
  return sum;
}

}  // namespace

bool FitOffsetCurve(const std::vector<OffsetPoint>& points, double* o0, double* o1, double* o2) {
  std::vector<OffsetPoint> kept;
  std::vector<double> distinct;  // the distances (u within 1e-9 are one), up to three
  for (const OffsetPoint& p : points) {
    if (!(p.weight > 0.0)) continue;
    kept.push_back(p);
    const bool seen = std::any_of(distinct.begin(), distinct.end(),
                                  [&](double u) { return std::fabs(u - p.u) <= 1e-9; });
    if (!seen && distinct.size() < 3) distinct.push_back(p.u);
  }
  if (kept.empty()) return false;
  Eigen::Vector3d c;
  const int line_terms = std::min<int>(2, static_cast<int>(distinct.size()));
  const double line_ss = SolveOffset(kept, line_terms, &c);
  // The curve where its bend stands out of the points' own scatter about it (an F test of one
  // term at kCurveF); a line's residuals alone do not bend it.
  const int n = static_cast<int>(kept.size());
  if (distinct.size() >= 3 && n >= kMinCurvePoints) {
    Eigen::Vector3d curve;
    const double curve_ss = SolveOffset(kept, 3, &curve);
    if (curve_ss > 0.0 && (line_ss - curve_ss) * (n - 3) > kCurveF * curve_ss) c = curve;
  }
  if (!c.allFinite()) return false;
  *o0 = c(0), *o1 = c(1), *o2 = c(2);
  return true;
}

bool BlurLevelLine::Add(const CrosstalkFrame& frame) {
  if (!frame.features.Usable() || !(frame.blur_var_px2 > kPixelAreaVarPx2)) return false;
  const Crosstalk crosstalk = CrosstalkOf(split_);
  const double start = split_.FitBlurAt(frame);
  // Past the crosstalk's kink too (blob_fit.h RoomFor): where the blur is all after the pixels,
  // a search held at the kink loses the frames that ask for less blur (the level reads high).
  const double low = std::max(start - kSearchPx2, kLeastBlurVarPx2 + 1e-3);
  double blur = std::max(start, low + 1e-3);
  BlobBlurProfile at;
  if (!NewtonOnBlobBlur(frame.image, frame.bit_depth, frame.features, crosstalk, low,
                        start + kSearchPx2, &blur, &at) ||
      !(at.se_px2 > 0.0) || !std::isfinite(at.se_px2)) {
    return false;
  }
  points_.push_back(
      {frame.InverseMetres(), blur - frame.blur_var_px2, 1.0 / (at.se_px2 * at.se_px2)});
  return true;
}

BlurSplit BlurLevelLine::Fitted() const {
  if (frames() < kMinBlurLevelFrames) return split_;
  double o0 = 0.0, o1 = 0.0, o2 = 0.0;
  if (!FitOffsetCurve(points_, &o0, &o1, &o2)) return split_;
  // The residuals in their standard errors; their robust sd (1.4826 x the median absolute).
  std::vector<double> z(points_.size());
  for (size_t i = 0; i < points_.size(); ++i) {
    const OffsetPoint& p = points_[i];
    z[i] = std::fabs(p.offset_px2 - OffsetCurvePx2(o0, o1, o2, p.u)) * std::sqrt(p.weight);
  }
  std::vector<double> sorted = z;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double robust_sd = 1.4826 * sorted[sorted.size() / 2];
  std::vector<OffsetPoint> kept;
  for (size_t i = 0; i < points_.size(); ++i) {
    if (z[i] <= kOutlierSd * robust_sd) kept.push_back(points_[i]);
  }
  BlurSplit out = split_;
  if (!FitOffsetCurve(kept, &out.blur_offset_px2, &out.blur_offset_u_px2,
                      &out.blur_offset_u2_px2)) {
    return out;
  }
  out.level_frames = static_cast<int>(kept.size());
  return out;
}

bool BlurSplitRefiner::Add(const CrosstalkFrame& frame) {
  if (!frame.features.Usable() || !(frame.blur_var_px2 > kPixelAreaVarPx2)) return false;
  const double u = frame.InverseMetres();
  const double blur = split_.FitBlurAt(frame);
  const BlobSplitProfile p =
      ProfileBlobSplit(frame.image, frame.bit_depth, frame.features, blur, CrosstalkOf(split_));
  if (!p.ok) return false;
  // The frame's (blur, crosstalk) = (given + o0 + o1 u, c): its profile carried to (o0, o1, c).
  const double a[2][3] = {{1.0, u, 0.0}, {0.0, 0.0, 1.0}};
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 2; ++k) {
      g_[i] += a[k][i] * p.gradient[k];
      for (int j = 0; j < 3; ++j) {
        for (int l = 0; l < 2; ++l) h_[i][j] += a[k][i] * p.curvature[k][l] * a[l][j];
      }
    }
  }
  max_crosstalk_px2_ = std::min(max_crosstalk_px2_, CrosstalkRoomPx2(blur));
  cost_ += p.cost;
  ++frames_;
  return true;
}

BlurSplit BlurSplitRefiner::Stepped() const {
  if (frames_ < kMinBlurLevelFrames) return split_;
  Eigen::Matrix3d h;
  Eigen::Vector3d g;
  for (int i = 0; i < 3; ++i) {
    g(i) = g_[i];
    for (int j = 0; j < 3; ++j) h(i, j) = h_[i][j];
  }
  // The least-norm step (no slope where the frames share one distance), then the variance held
  // within its range and the line re-solved at it (the curve's bend held).
  Eigen::Vector3d step = h.completeOrthogonalDecomposition().solve(-g);
  const double c =
      std::clamp(split_.crosstalk_var_px2 + step(2), 0.0, std::max(max_crosstalk_px2_, 0.0));
  step(2) = c - split_.crosstalk_var_px2;
  const Eigen::Vector2d line = h.topLeftCorner<2, 2>().completeOrthogonalDecomposition().solve(
      -g.head<2>() - h.topRightCorner<2, 1>() * step(2));
  if (!line.allFinite() || !std::isfinite(c)) return split_;
  BlurSplit out = split_;
  out.blur_offset_px2 += line(0);
  out.blur_offset_u_px2 += line(1);
  out.crosstalk_var_px2 = c;
  out.level_frames = frames_;
  return out;
}

}  // namespace irdist
