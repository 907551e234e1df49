#pragma once
// How much a set of frames' blob sizes follow the edge's sub-pixel phase: the part of
// the sizes' distance error that moves with where the disc's edge falls inside a pixel, over
// frames at many distances and centres (a calibration's poses). A model whose pixel response is
// not the camera's reads a sampled edge at one phase larger than at another; the error of a disc
// of radius R centred at (cx, cy) then follows the phases of its four axis-parallel edge points,
// R + cx, R - cx, R + cy, R - cy (mod 1; the edge's error at phase p, e(p) = sum_m a_m cos 2 pi m p
// + b_m sin 2 pi m p, mirrored for the left and lower edges), whose sum is, per harmonic m,
// w_m (a_m cos 2 pi m R + b_m sin 2 pi m R) with w_m = cos 2 pi m cx + cos 2 pi m cy.
// EdgePhaseOf regresses ln(R d) on a quadratic in u = 1000 / d (the smooth part: the size's own
// bias, a distance scale) and these harmonics (m = 1, 2), and reports the harmonic part.

#include <vector>

namespace irdist {

// One frame's fitted size and where its disc lies.
struct EdgePhaseSample {
  double size_var_px2 = 0.0;   // the fitted disc's variance R^2 / 4 (mean of its axes), px^2
  double center_x_px = 0.0;    // the disc's centre, pixel-centre coordinates
  double center_y_px = 0.0;
  double d_mm = 0.0;           // the frame's distance (> 0)
};

struct EdgePhase {
  bool ok = false;  // false with fewer than kMinEdgePhaseSamples usable samples
  // The harmonic part's rms and peak to peak over the samples, as a relative distance error.
  double rms = 0.0;
  double peak_to_peak = 0.0;
  // What rms reads from the sizes' noise alone: the residual sd times sqrt(4 / n) (the four
  // harmonic coefficients' share of n samples).
  double noise_rms = 0.0;
  int samples = 0;
  // The smooth part of ln(R d / 1000 mm), s0 + s1 u + s2 u^2 (u = 1000 / d): what a calibration
  // of the size against the distance takes from these frames, the phase apart.
  double smooth[3] = {0.0, 0.0, 0.0};
  double SmoothAt(double d_mm) const {
    const double u = 1000.0 / d_mm;
    return smooth[0] + smooth[1] * u + smooth[2] * u * u;
  }
};

constexpr int kMinEdgePhaseSamples = 12;

EdgePhase EdgePhaseOf(const std::vector<EdgePhaseSample>& samples);

}  // namespace irdist
