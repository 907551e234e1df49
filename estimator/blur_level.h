#pragma once
// The blob fit's blur level from every calibration frame. FitBlurSplit (blob_fit.h) fits the
// blur's split on up to 32 frames, with the line of their own best blurs (the offset to the
// cumulants' blur); behind sharp optics the size's phase is that sensitive to the line's level
// (0.01 px^2 off swings it by 0.06-0.16%: docs/estimator.md "Pixel responses outside the
// model"), and 32 noisy frames leave it about 0.02 px^2 off. BlurLevelLine refits the line on as
// many frames as the calibration has: each frame's own best blur at the split by Newton's method
// on the one-pass cost (refocus.h NewtonOnBlobBlur, about two fits a frame against Brent's 15-20),
// the line weighted by each frame's standard error, frames beyond 5 robust sd of it left out.

#include <vector>

#include "estimator/blob_fit.h"

namespace irdist {

// The fewest frames whose line replaces the split's own.
constexpr int kMinBlurLevelFrames = 8;

class BlurLevelLine {
 public:
  explicit BlurLevelLine(const BlurSplit& split) : split_(split) {}
  // The frame's own best blur at the split, searched from its given blur plus the split's line;
  // false (the frame left out) when the search fails.
  bool Add(const CrosstalkFrame& frame);
  // The split with its offset line refitted on the frames added; the split's own with fewer than
  // kMinBlurLevelFrames of them.
  BlurSplit Fitted() const;
  int frames() const { return static_cast<int>(points_.size()); }

 private:
  struct Point {
    double u, offset_px2, weight;  // 1000 / d_mm, own best blur less the given, 1 / se^2
  };
  BlurSplit split_;
  std::vector<Point> points_;
};

}  // namespace irdist
