#pragma once
// The blob fit's pixel model (estimator/blob_fit.cc; estimator-internal): the mean of a
// uniformly bright elliptical disc over one pixel, blurred by the optics before the pixels
// sample it (a Gaussian, with the PSF's anisotropy along the edge's normal), each pixel's square
// integrated in closed form, and its derivatives in the disc's centre and matrix; the crosstalk
// after the sampling as a separable kernel on the pixel grid.

#include <memory>
#include <vector>

#include "estimator/blur_model.h"  // the edge correction's table

namespace irdist {
namespace blob_model {

// How a pixel responds to the blurred disc: the optical blur's sd before the pixels
// sample the image, each pixel's square integrating it, then the inter-pixel crosstalk after the
// sampling, a separable kernel on the pixel grid. A model that folds the pixel's square and the
// crosstalk into one Gaussian before the sampling (the earlier fit) takes a sharp image's
// sampled edge for a smooth one: the fitted size then swings with the edge's sub-pixel phase.
// Integrated and spread in this order, the model's pixels are the camera's, whatever the mix.
struct PixelResponse {
  double optics_sd = 0.0;
  // The optics' PSF anisotropy (px^2, psf_anisotropy.h): an edge of normal n is blurred by the
  // variance n^T S n = optics_sd^2 + aniso_c (nx^2 - ny^2) + 2 aniso_s nx ny.
  double aniso_c = 0.0, aniso_s = 0.0;
  // The optics' edge beyond a Gaussian's: the Gram-Charlier term of its line spread's excess
  // kurtosis, gc_k = excess / 24 (the edge Phi(x) - gc_k phi(x) He3(x)); 0 = a Gaussian.
  double gc_k = 0.0;
  std::vector<double> kernel;   // crosstalk, 1-D (applied along x, then y), odd, sums to 1
  int reach = 0;                // the kernel's half width
  // The edge's correction learned from the calibration's residuals (estimator/edge_correction.h):
  // kEdgeCorrectionKnots values of the pixel's mean at its EdgeOffsetPx, added before the
  // crosstalk; null: none.
  std::shared_ptr<const std::vector<double>> edge_correction;
};

// The signed offset t (px, > 0 inside) of the pixel centre (x, y) from the disc's edge as the
// optics round it, for the disc v (x, y, P11, P12, P22): the first-order distance to the edge less
// the curvature's shift of the 50% point, kappa (optics_sd^2 + 1/12) / 2; the edge correction's
// argument (SquareMean adds the table at it, with its derivatives).
double EdgeOffsetPx(const double* v, double x, double y, const PixelResponse& r);

// The response for a blur of `blur_var_px2` per axis (pixel area included) of which
// `crosstalk_var_px2` comes after the sampling: the optics' sd and the crosstalk's kernel; the
// optics' line spread of excess kurtosis `optics_excess` (0: a Gaussian).
PixelResponse MakeResponse(double blur_var_px2, double crosstalk_var_px2, double lattice_share,
                           double optics_excess = 0.0);

// The disc's mean over the pixel at (x, y) before crosstalk, and its derivatives into d[5]: the
// optical edge integrated over the pixel's square as a straight edge (SquareEdge) at the signed
// distance to the disc's edge, blurred and shifted as BlurEdge says (the PSF's variance along the
// edge's normal and tangent: an elliptical PSF's differ around the disc). The derivatives
// (analytic, the chain rule through q = (p - c)^T P (p - c), g = P (p - c), the first-order
// distance and the curvature; DiscDerivatives; an elliptical PSF's turn with the normal by a
// central difference in n^T a n) leave out the turn of the edge's normal across the square and
// the widening's change: a few % of the slope, which moves the fit's path, not its solution on an
// exact model. A pixel whose square lies far from the edge (5 sd, Phi(-5) = 3e-7, plus the
// square's half diagonal and 0.5 px for the first-order distance) is 1 or 0 at once.
double SquareMean(const double* v, double x, double y, const PixelResponse& r, double* d);

// `in` (rows x cols, row-major) convolved with `kernel` along x (dx = 1) or y, keeping the valid
// part, into `out`: (rows x (cols - 2 reach)) or ((rows - 2 reach) x cols).
void Convolve(const double* in, int rows, int cols, const std::vector<double>& kernel,
              bool along_x, double* out);

// `in` (rows x cols, row-major: a window grown by the kernel's reach on every side) spread by
// `kernel` along x, into `*across`, then along y, into `out` ((rows - 2 reach) x (cols - 2
// reach)): the crosstalk on the window.
void Spread(const double* in, int rows, int cols, const std::vector<double>& kernel,
            std::vector<double>* across, double* out);

}  // namespace blob_model
}  // namespace irdist
