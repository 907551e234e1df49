#include "estimator/blur_level.h"

#include <algorithm>
#include <cmath>

#include "estimator/blur_model.h"
#include "estimator/refocus.h"

namespace irdist {

namespace {

// How far the search may move a frame's blur from the split's line (FitBlurSplit's rounds move
// each frame's by at most 0.15 px^2 a round).
constexpr double kSearchPx2 = 0.3;
// Frames beyond this many robust sd of the line are left out (a scene fault, a moving stage).
constexpr double kOutlierSd = 5.0;

struct Line {
  double o0 = 0.0, o1 = 0.0;
  bool ok = false;
};

// The weighted least-squares line offset = o0 + o1 u over the points `keep` marks; a constant
// where their u do not spread (no distances known).
template <typename P>
Line WeightedLine(const std::vector<P>& points, const std::vector<bool>& keep) {
  double sw = 0.0, su = 0.0, sr = 0.0, suu = 0.0, sur = 0.0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!keep[i]) continue;
    const P& p = points[i];
    sw += p.weight;
    su += p.weight * p.u;
    sr += p.weight * p.offset_px2;
    suu += p.weight * p.u * p.u;
    sur += p.weight * p.u * p.offset_px2;
  }
  Line line;
  if (!(sw > 0.0)) return line;
  const double det = sw * suu - su * su;
  line.o1 = det > 1e-9 * std::max(sw * suu, 1e-300) ? (sw * sur - su * sr) / det : 0.0;
  line.o0 = (sr - line.o1 * su) / sw;
  line.ok = true;
  return line;
}

}  // namespace

bool BlurLevelLine::Add(const CrosstalkFrame& frame) {
  if (!frame.features.Usable() || !(frame.blur_var_px2 > kPixelAreaVarPx2)) return false;
  const double u = frame.d_mm > 0.0 ? 1000.0 / frame.d_mm : 0.0;
  const Crosstalk crosstalk(split_.crosstalk_var_px2, split_.crosstalk_lattice_share);
  const double start = frame.blur_var_px2 + split_.blur_offset_px2 + split_.blur_offset_u_px2 * u;
  const double floor = kPixelAreaVarPx2 + kMinOpticsVarPx2 + crosstalk.var_px2;
  const double low = std::max(start - kSearchPx2, floor + 1e-3);
  double blur = std::max(start, low + 1e-3);
  BlobBlurProfile at;
  if (!NewtonOnBlobBlur(frame.image, frame.bit_depth, frame.features, crosstalk, low,
                        start + kSearchPx2, &blur, &at) ||
      !(at.se_px2 > 0.0) || !std::isfinite(at.se_px2)) {
    return false;
  }
  points_.push_back({u, blur - frame.blur_var_px2, 1.0 / (at.se_px2 * at.se_px2)});
  return true;
}

BlurSplit BlurLevelLine::Fitted() const {
  if (frames() < kMinBlurLevelFrames) return split_;
  std::vector<bool> keep(points_.size(), true);
  Line line = WeightedLine(points_, keep);
  // The residuals in their standard errors; their robust sd (1.4826 x the median absolute).
  std::vector<double> z(points_.size());
  for (size_t i = 0; i < points_.size(); ++i) {
    const Point& p = points_[i];
    z[i] = std::fabs(p.offset_px2 - line.o0 - line.o1 * p.u) * std::sqrt(p.weight);
  }
  std::vector<double> sorted = z;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double robust_sd = 1.4826 * sorted[sorted.size() / 2];
  for (size_t i = 0; i < points_.size(); ++i) keep[i] = z[i] <= kOutlierSd * robust_sd;
  line = WeightedLine(points_, keep);
  BlurSplit out = split_;
  if (!line.ok) return out;
  out.blur_offset_px2 = line.o0;
  out.blur_offset_u_px2 = line.o1;
  out.level_frames = static_cast<int>(std::count(keep.begin(), keep.end(), true));
  return out;
}

}  // namespace irdist
