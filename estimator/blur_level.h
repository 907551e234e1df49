#pragma once
// The blob fit's blur level from every calibration frame. FitBlurSplit (blob_fit.h) fits the
// blur's split on up to 32 frames, with the curve of their own best blurs (the offset to the
// cumulants' blur); behind sharp optics the size's phase is that sensitive to the curve's level
// (0.01 px^2 off swings it by 0.06-0.16%: docs/estimator.md "Pixel responses outside the
// model"), and 32 noisy frames leave it about 0.02 px^2 off. BlurLevelLine refits the curve on as
// many frames as the calibration has: each frame's own best blur at the split by Newton's method
// on the one-pass cost (refocus.h NewtonOnBlobBlur, about two fits a frame against Brent's 15-20),
// the curve weighted by each frame's standard error, frames beyond 5 robust sd of it left out.

#include <vector>

#include "estimator/blob_fit.h"

namespace irdist {

// The fewest frames whose curve replaces the split's own.
constexpr int kMinBlurLevelFrames = 8;

// The offset's curve offset = o0 + o1 u + o2 u^2 (u = 1000 / d) through weighted points by least
// squares (FitBlurSplit's rounds give every frame the weight 1): a line (o2 = 0), bent into the
// quadratic where the points hold three distances or more and the bend stands out of their own
// scatter about it (an F test at 4 sd), a constant where one distance or none is known (o1 = o2 =
// 0). False (nothing set) without weight.
struct OffsetPoint {
  double u, offset_px2, weight;  // 1000 / d_mm, own best blur less the given, 1 / se^2
};
bool FitOffsetCurve(const std::vector<OffsetPoint>& points, double* o0, double* o1, double* o2);

class BlurLevelLine {
 public:
  explicit BlurLevelLine(const BlurSplit& split) : split_(split) {}
  // The frame's own best blur at the split, searched from its given blur plus the split's curve;
  // false (the frame left out) when the search fails.
  bool Add(const CrosstalkFrame& frame);
  // The split with its offset curve refitted on the frames added; the split's own with fewer than
  // kMinBlurLevelFrames of them.
  BlurSplit Fitted() const;
  int frames() const { return static_cast<int>(points_.size()); }

 private:
  BlurSplit split_;
  std::vector<OffsetPoint> points_;
};

// The split and the blur's level refitted on every calibration frame: a Gauss-Newton step of the
// frames' summed one-pass cost (FitBlurSplit's objective) in the offset's (o0, o1; o2 held) and the
// crosstalk's variance per pass over them, each frame's profile (blob_fit.h ProfileBlobSplit: one
// fit and two model evaluations) at the current split; the kernel's shape stays FitBlurSplit's.
// The variance is kept within [0, the frames' least room beside the optics' floor].
class BlurSplitRefiner {
 public:
  explicit BlurSplitRefiner(const BlurSplit& split) : split_(split) {}
  // The frame's profile at the current split into the sums; false (left out) when it fails.
  bool Add(const CrosstalkFrame& frame);
  // The split after the sums' step; the current one with fewer than kMinBlurLevelFrames frames.
  BlurSplit Stepped() const;
  int frames() const { return frames_; }
  // The frames' mean one-pass cost at the current split.
  double MeanCost() const { return frames_ > 0 ? cost_ / frames_ : 0.0; }

 private:
  BlurSplit split_;
  double cost_ = 0.0;
  double h_[3][3] = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}}, g_[3] = {0.0, 0.0, 0.0};
  double max_crosstalk_px2_ = 1e300;
  int frames_ = 0;
};

// The passes `irdist fit` makes after FitBlurSplit: up to kSplitRefinePasses of BlurSplitRefiner,
// each evaluating the frames' cost at the split it starts from; a step that raises it ends them,
// and the split of the lowest cost evaluated is kept; then BlurLevelLine at it. `for_frames(use)`
// calls use(const CrosstalkFrame&) on each calibration frame (it may load them one at a time).
constexpr int kSplitRefinePasses = 3;
template <typename ForFrames>
BlurSplit RefineBlurSplit(BlurSplit split, ForFrames for_frames) {
  BlurSplit best = split;
  double best_cost = 1e300;
  for (int pass = 0; pass < kSplitRefinePasses; ++pass) {
    BlurSplitRefiner refiner(split);
    for_frames([&](const CrosstalkFrame& f) { refiner.Add(f); });
    if (refiner.frames() < kMinBlurLevelFrames || !(refiner.MeanCost() < best_cost)) break;
    best = split;
    best_cost = refiner.MeanCost();
    split = refiner.Stepped();
  }
  BlurLevelLine level(best);
  for_frames([&](const CrosstalkFrame& f) { level.Add(f); });
  return level.Fitted();
}

}  // namespace irdist
