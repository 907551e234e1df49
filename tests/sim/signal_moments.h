#pragma once
// Test helper: the intensity-weighted covariance (px^2) and sum of a signal window (sim/scene.h).

#include "sim/scene.h"

namespace irdist::sim::testing {

struct Covariance {
  double sum = 0.0, xx = 0.0, xy = 0.0, yy = 0.0;
};

inline Covariance CovarianceOf(const SignalWindow& w) {
  double s = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  for (int r = 0; r < w.electrons.rows; ++r) {
    for (int c = 0; c < w.electrons.cols; ++c) {
      const double v = w.electrons(r, c);
      s += v;
      sx += v * c;
      sy += v * r;
      sxx += v * c * c;
      syy += v * r * r;
      sxy += v * c * r;
    }
  }
  const double mx = sx / s, my = sy / s;
  return {s, sxx / s - mx * mx, sxy / s - mx * my, syy / s - my * my};
}

}  // namespace irdist::sim::testing
