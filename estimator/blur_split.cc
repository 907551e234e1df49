// FitBlurSplit (blob_fit.h): the split of the calibrated blur between the optics and the
// inter-pixel crosstalk, the crosstalk kernel's shape and the blob fit's own blur, from
// calibration frames, by coordinate descent on the blob fit's first-pass cost.
#include <algorithm>
#include <boost/math/tools/minima.hpp>
#include <cmath>
#include <limits>
#include <vector>

#include "estimator/blob_fit.h"
#include "estimator/blur_level.h"

namespace irdist {

namespace {

// FitBlurSplit's rounds of coordinate descent (the split and the blur trade along a valley).
constexpr int kSplitRounds = 8;

}  // namespace

namespace {

// How far one round's search moves each frame's blur from the last round's curve (the cumulants
// err by a few 0.01 px^2 on a Gaussian lens; the rounds add up, so a halo's 0.3 px^2 is reached).
constexpr double kMaxBlurOffsetPx2 = 0.15;

}  // namespace

namespace {

// The frames' summed first-pass cost with `crosstalk`; +inf when a frame's fit fails (no split
// may win by losing frames).
double SplitCost(const std::vector<const CrosstalkFrame*>& frames, const Crosstalk& crosstalk,
                 int* pixels = nullptr) {
  double sum = 0.0;
  for (const CrosstalkFrame* f : frames) {
    const BlobFitResult fit =
        FitBlobPasses(f->image, f->bit_depth, f->features, f->blur_var_px2, crosstalk, 1);
    if (!fit.ok) return std::numeric_limits<double>::infinity();
    sum += fit.read_weighted_chi2 * fit.pixels;
    if (pixels) *pixels += fit.pixels;
  }
  return sum;
}

// The frames as SplitCost takes them.
std::vector<const CrosstalkFrame*> PointersTo(const std::vector<CrosstalkFrame>& frames) {
  std::vector<const CrosstalkFrame*> out;
  for (const CrosstalkFrame& f : frames) out.push_back(&f);
  return out;
}

// Brent's minimisation (Boost) of f over [low, high] to 2^-9 of the range.
template <typename F>
double Minimise(F f, double low, double high) {
  if (!(high > low)) return low;
  boost::uintmax_t iterations = 30;
  return boost::math::tools::brent_find_minima(f, low, high, 9, iterations).first;
}

// The optics' excess kurtosis at the split's variance and shape: Brent's over its range, kept
// where it lowers the frames' cost by more than kExcessEvidence of its per-pixel scale (the
// deviance of one parameter at 95%) and by kExcessMaterial of the cost itself, else a Gaussian's
// 0. A lens the Gaussian edge fits keeps it: behind optics sharper than the pixel the edge's
// shape has no say (the cost is flat in it), and where a lattice walk's tails or the blur's
// level could stand in for it, noise-free frames would otherwise let it wander.
constexpr double kExcessEvidence = 3.84, kExcessMaterial = 0.01;
double FitOpticsExcess(const std::vector<const CrosstalkFrame*>& frames, double var, double share) {
  int pixels = 0;
  const double gaussian = SplitCost(frames, {var, share, 0.0}, &pixels);
  const auto cost_at = [&](double x) { return SplitCost(frames, Crosstalk(var, share, x)); };
  const double excess = Minimise(cost_at, kMinOpticsExcess, kMaxOpticsExcess);
  const double gain = gaussian - SplitCost(frames, {var, share, excess});
  const double evidence = kExcessEvidence * gaussian / std::max(pixels, 1);
  return gain > std::max(evidence, kExcessMaterial * gaussian) ? excess : 0.0;
}

}  // namespace

namespace {

// The offset's curve o0 + o1 u + o2 u^2 (u = 1000 / d; blur_level.h FitOffsetCurve) through each
// frame's own best blur at `crosstalk` (Brent on the frame's one-pass cost) less its given blur.
void FitBlurOffset(const std::vector<const CrosstalkFrame*>& given,
                   const std::vector<CrosstalkFrame>& shifted, const Crosstalk& crosstalk,
                   double* o0, double* o1, double* o2) {
  std::vector<OffsetPoint> points;
  for (size_t i = 0; i < shifted.size(); ++i) {
    CrosstalkFrame trial = shifted[i];
    const std::vector<const CrosstalkFrame*> one = {&trial};
    const double room = CrosstalkRoomPx2(shifted[i].blur_var_px2) - crosstalk.var_px2;
    const double low = -std::min(kMaxBlurOffsetPx2, std::max(room, 0.0));
    const double o = Minimise(
        [&](double x) {
          trial.blur_var_px2 = shifted[i].blur_var_px2 + x;
          return SplitCost(one, crosstalk);
        },
        low, kMaxBlurOffsetPx2);
    points.push_back(
        {given[i]->InverseMetres(), shifted[i].blur_var_px2 + o - given[i]->blur_var_px2, 1.0});
  }
  FitOffsetCurve(points, o0, o1, o2);
}

}  // namespace

namespace {

// One round's searches at the frames' blur: the optics' edge where it is not a Gaussian's (from
// the third round on, once the kernel's shape is found: a lattice walk's tails and the edge
// trade), the crosstalk's variance at its kernel's shape and that edge, then the shape at the
// variance (the first two rounds).
void SplitRound(const std::vector<const CrosstalkFrame*>& now, double max_var, int round,
                Crosstalk* best) {
  if (round >= 2 && best->optics_excess != 0.0) {
    best->optics_excess = FitOpticsExcess(now, best->var_px2, best->lattice_share);
  }
  const double share = best->lattice_share, excess = best->optics_excess;
  const auto at_var = [&](double c) { return SplitCost(now, Crosstalk(c, share, excess)); };
  best->var_px2 = Minimise(at_var, 0.0, max_var);
  const double var = best->var_px2;
  const auto at_share = [&](double l) { return SplitCost(now, Crosstalk(var, l, excess)); };
  if (round < 2) best->lattice_share = Minimise(at_share, 0.0, 1.0);
}

// The first two rounds (the kernel's shape found) from a Gaussian optics' edge, or from the
// optics' own edge fitted first with all of the blur theirs, whichever the frames' cost prefers:
// an Airy pattern's tails otherwise send the variance down a lattice walk's valley (1.4 px^2 for
// none), where the optics are at their floor and their edge has no say. A lens that starts
// Gaussian stays Gaussian (the later rounds refine a non-Gaussian edge only): on noise-free
// frames the edge's shape would otherwise stand in for the blur's level or a lattice walk's
// tails wherever that lowers the cost by a hair.
Crosstalk FirstRounds(const std::vector<const CrosstalkFrame*>& now, double max_var) {
  Crosstalk gaussian;
  for (const int round : {0, 1}) SplitRound(now, max_var, round, &gaussian);
  Crosstalk shaped;
  shaped.optics_excess = FitOpticsExcess(now, 0.0, 0.0);
  if (shaped.optics_excess == 0.0) return gaussian;
  for (const int round : {0, 1}) SplitRound(now, max_var, round, &shaped);
  return SplitCost(now, shaped) < SplitCost(now, gaussian) ? shaped : gaussian;
}

// Where the crosstalk's variance has reached the room the frames' least blur leaves it (its kink,
// blob_fit.h RoomFor: beyond, the fit clamps it and the cost is flat in it), a sensor whose blur
// is all after the pixels is tried: every frame's blur on the kink (the optics at their floor),
// the variance Brent's over the room to kMaxBlurOffsetPx2 past it, kept where the frames' cost is
// lower than the split's; the next offset's curve takes the frames' blur up with it. Such a sensor
// lies on the kink, and where the cumulants' blur is short of its truth the variance and the
// frames' level held each other there (the virtual rig's all-after sensor: 0.964 px^2 for 1).
constexpr double kAtTheKink = 4e-3;  // Brent's tolerance (2^-9 of the range) with a margin
void AlongTheKink(const std::vector<CrosstalkFrame>& shifted, double max_var, Crosstalk* best) {
  std::vector<CrosstalkFrame> trial = shifted;
  const std::vector<const CrosstalkFrame*> at = PointersTo(trial);
  const Crosstalk c = *best;
  const auto cost_at = [&](double x) {
    for (CrosstalkFrame& f : trial) f.blur_var_px2 = kLeastBlurVarPx2 + x;
    return SplitCost(at, Crosstalk(x, c.lattice_share, c.optics_excess));
  };
  const double var = Minimise(cost_at, max_var, max_var + kMaxBlurOffsetPx2);
  if (cost_at(var) < SplitCost(PointersTo(shifted), c)) best->var_px2 = var;
}

}  // namespace

std::vector<CrosstalkFrame> SplitFramesOf(const std::vector<CrosstalkFrame>& frames) {
  std::vector<CrosstalkFrame> out;
  const std::size_t stride = std::max<std::size_t>(1, frames.size() / kBlurSplitFrames);
  for (std::size_t i = 0; i < frames.size() && out.size() < kBlurSplitFrames; i += stride) {
    out.push_back(frames[i]);
  }
  return out;
}

BlurSplit FitBlurSplit(const std::vector<CrosstalkFrame>& frames) {
  BlurSplit split;
  std::vector<const CrosstalkFrame*> usable;
  for (const CrosstalkFrame& f : frames) {
    if (f.features.Usable() && f.blur_var_px2 > kPixelAreaVarPx2 + 0.05) usable.push_back(&f);
  }
  split.frames = static_cast<int>(usable.size());
  if (usable.empty()) return split;
  // Coordinate descent (SplitRound): the crosstalk's variance at its kernel's shape (a sampled
  // Gaussian first) and the optics' edge, then the shape at the variance (two rounds); from the
  // second round on, the optics' edge at the split, and each frame's own best blur at the split
  // gives the offset's curve, and the next round fits the variance at it (the split and the blur
  // trade along a valley: kSplitRounds). The optics keep kMinOpticsVarPx2.
  std::vector<CrosstalkFrame> shifted;
  for (const CrosstalkFrame* f : usable) shifted.push_back(*f);
  const std::vector<const CrosstalkFrame*> now = PointersTo(shifted);
  Crosstalk best;
  double o0 = 0.0, o1 = 0.0, o2 = 0.0;
  for (int round = 0; round < kSplitRounds; ++round) {
    double min_blur = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < shifted.size(); ++i) {
      shifted[i].blur_var_px2 = usable[i]->BlurWithOffset(o0, o1, o2);
      min_blur = std::min(min_blur, shifted[i].blur_var_px2);
    }
    const double max_var = std::max(CrosstalkRoomPx2(min_blur), 0.0);
    if (round == 0) {
      best = FirstRounds(now, max_var);  // rounds 0 and 1
    } else if (round >= 2) {
      SplitRound(now, max_var, round, &best);
    }
    if (best.var_px2 > (1.0 - kAtTheKink) * max_var) AlongTheKink(shifted, max_var, &best);
    if (round >= 1 && round + 1 < kSplitRounds) FitBlurOffset(usable, shifted, best, &o0, &o1, &o2);
  }
  if (SplitCost(now, best) <= SplitCost(now, {})) {
    split.crosstalk_var_px2 = best.var_px2;
    split.crosstalk_lattice_share = best.lattice_share;
    split.optics_excess = best.optics_excess;
  } else {
    best = {};
  }
  // The offset's curve at the split kept: what each frame's own blur is there (the blob fit's own
  // blur, estimator/refocus.h, searches the same cost at the same split).
  for (size_t i = 0; i < shifted.size(); ++i) {
    shifted[i].blur_var_px2 = usable[i]->BlurWithOffset(o0, o1, o2);
  }
  FitBlurOffset(usable, shifted, best, &o0, &o1, &o2);
  split.blur_offset_px2 = o0;
  split.blur_offset_u_px2 = o1;
  split.blur_offset_u2_px2 = o2;
  return split;
}

}  // namespace irdist
