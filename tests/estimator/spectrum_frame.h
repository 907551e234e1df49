#pragma once
// A 16-bit calibration frame of the independent disc renderer (tests/estimator/disc_spectrum.h)
// with its features, for the blob fit's calibration tests (FitBlurSplit, BlurLevelLine): 48 x 48
// px, 30000 DN of disc over 1000 DN of background, a 40 px feature window; the blur left to the
// caller.

#include "estimator/blob_fit.h"
#include "estimator/features.h"
#include "tests/estimator/disc_spectrum.h"

namespace irdist::testing {

inline CrosstalkFrame SpectrumFrame16(const DiscBlob& blob) {
  CrosstalkFrame frame;
  frame.image = DiscFrame16(RenderDiscSpectrum(blob, 48), 30000.0, 1000.0);
  frame.bit_depth = 16;
  FeatureOptions options;
  options.window_side_px = 40;
  frame.features = ComputeFeatures(frame.image, 16, options);
  return frame;
}

}  // namespace irdist::testing
