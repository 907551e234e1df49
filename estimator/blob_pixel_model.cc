#include "estimator/blob_pixel_model.h"

#include <algorithm>
#include <cmath>

#include "estimator/blur_model.h"
#include "estimator/crosstalk_kernel.h"
#include "estimator/normal_table.h"

namespace irdist {
namespace blob_model {
namespace {

// The quantities of one pixel's edge geometry SquareMean and its derivatives share.
struct EdgeGeometry {
  double dx, dy, gx, gy, pgx, pgy, r, n, dist, kappa;
};

// d t / d (x, y, P11, P12, P22) times `slope` at one pixel, for SquareMean's edge offset
// t = dist - shift kappa r: by the chain rule through q = (p - c)^T P (p - c), g = P (p - c),
// n = |g|, dist = (sqrt q - q) / n, the level set's curvature kappa = (n^2 tr P - g^T P g) / n^3
// and the edge's, kappa r (r = sqrt q). slope: the model's derivative along t.
void DiscDerivatives(const double* v, const EdgeGeometry& e, double slope, double shift,
                     double* d) {
  const double n2 = e.n * e.n, inv_n = 1.0 / e.n, inv_n3 = inv_n / n2;
  const double trace = v[2] + v[4];
  const double dq[5] = {-2.0 * e.gx, -2.0 * e.gy, e.dx * e.dx, 2.0 * e.dx * e.dy, e.dy * e.dy};
  const double dgx[5] = {-v[2], -v[3], e.dx, e.dy, 0.0};
  const double dgy[5] = {-v[3], -v[4], 0.0, e.dx, e.dy};
  const double dtrace[5] = {0.0, 0.0, 1.0, 0.0, 1.0};
  const double dgpg_p[5] = {0.0, 0.0, e.gx * e.gx, 2.0 * e.gx * e.gy, e.gy * e.gy};
  const double dq_factor = 0.5 / e.r - 1.0;
  for (int k = 0; k < 5; ++k) {
    const double dn = (e.gx * dgx[k] + e.gy * dgy[k]) * inv_n;
    const double ddist = (dq[k] * dq_factor - e.dist * dn) * inv_n;
    const double dgpg = 2.0 * (e.pgx * dgx[k] + e.pgy * dgy[k]) + dgpg_p[k];
    const double dkappa =
        (2.0 * e.n * dn * trace + n2 * dtrace[k] - dgpg) * inv_n3 - 3.0 * e.kappa * dn * inv_n;
    const double dkappa_edge = e.r * dkappa + e.kappa * dq[k] * 0.5 / e.r;
    d[k] = slope * (ddist - shift * dkappa_edge);
  }
}

// Psi' = Phi and Lambda' = Psi: the first and second integrals of the normal CDF, at one x (Phi
// and phi from the table of estimator/normal_table.h: through erfc and exp they were half of the
// fit's time). With a Gram-Charlier term k (the edge Phi - k phi He3, its line spread
// phi (1 + k He4): a line spread of excess kurtosis 24 k), its integrals k phi He2 and -k x phi
// (d/dx (phi He_n) = -phi He_n+1) join them.
struct EdgeIntegrals {
  EdgeIntegrals(double x, double k) {
    const NormalValues normal = NormalAt(x);
    cdf = normal.cdf;
    const double pdf = normal.pdf;
    psi = x * cdf + pdf;
    lambda = 0.5 * ((x * x + 1.0) * cdf + x * pdf);
    if (k == 0.0) return;
    const double x2 = x * x;
    cdf -= k * pdf * x * (x2 - 3.0);
    psi += k * pdf * (x2 - 1.0);
    lambda -= k * x * pdf;
  }
  double cdf, psi, lambda;
};

// The mean of Phi((t + U) / sd) (with the Gram-Charlier term k) over a square of `side` px, U the
// square's projection on the edge's normal (nx, ny): the sum of two uniforms of widths side |nx|
// and side |ny|, in closed form through Lambda (Psi when the edge runs along a pixel axis); its
// derivative along t into *slope.
double SquareEdge(double t, double nx, double ny, double side, double sd, double k, double* slope) {
  const double a = side * std::max(std::fabs(nx), std::fabs(ny));
  const double b = side * std::min(std::fabs(nx), std::fabs(ny));
  if (b < 1e-4 * side) {  // one uniform of width a (~side)
    const EdgeIntegrals hi((t + 0.5 * a) / sd, k), lo((t - 0.5 * a) / sd, k);
    *slope = (hi.cdf - lo.cdf) / a;
    return sd / a * (hi.psi - lo.psi);
  }
  const EdgeIntegrals e[4] = {
      EdgeIntegrals((t + 0.5 * (a + b)) / sd, k), EdgeIntegrals((t + 0.5 * (a - b)) / sd, k),
      EdgeIntegrals((t - 0.5 * (a - b)) / sd, k), EdgeIntegrals((t - 0.5 * (a + b)) / sd, k)};
  const double c = sd / (a * b);
  *slope = c * (e[0].psi - e[1].psi - e[2].psi + e[3].psi);
  return c * sd * (e[0].lambda - e[1].lambda - e[2].lambda + e[3].lambda);
}

// One edge point's mean over the pixel's square for the PSF's anisotropy along its normal,
// aniso_n = n^T a n (a the traceless part of the PSF's covariance): the edge spreads by the
// variance along its normal, optics_var + aniso_n, and its 50% point moves inward by the curvature
// times the variance along its tangent, optics_var - aniso_n, over 2 (a curved edge's blur reaches
// in along the tangent; an elliptical PSF thus moves the edge by different amounts around the
// disc), plus the square's tangential 1/12 over 2; the curvature widens it to second order.
struct BlurredEdge {
  double value = 0.0, slope = 0.0, shift = 0.0;
};
// The excess kurtosis of a round PSF's tangential spread, from its edge's Gram-Charlier term
// (gc_k = g / 24: a round PSF's every line spread is the same): g where a round PSF can have it,
// from a defocus disc's own -1 (its line spread is a semicircle; the edge's fitted g reads lower,
// -2.1 on a pure disc, where the series stands in for the disc's sharp rim) up to the series' end,
// 4 (an Airy pattern's peaked core and heavy tails, which have no fourth moment: 4 is what the
// window's reach of them reads). With a Gaussian's 2 sd^4 whatever the edge, the fitted ellipse of
// a small disc behind a defocus disc came out rounder; held at a Gaussian's for g > 0 it came out
// flatter behind the Airy lens, theta +0.10 deg at 4.5 px and 30 deg once the blob fit's blur
// followed its frames (docs/estimator.md "The curved edge's widening", "The blob fit's blur
// bends with the cumulants'").
constexpr double kMinTangentialExcess = -1.0;
double TangentialExcess(double gc_k) { return std::max(24.0 * gc_k, kMinTangentialExcess); }
BlurredEdge BlurEdge(double dist, double kappa_edge, double nx, double ny, double side,
                     double optics_var, double aniso_n, double gc_k) {
  const double normal2 = std::max(optics_var + aniso_n, kMinOpticsVarPx2);
  const double tangent2 = std::max(optics_var - aniso_n, kMinOpticsVarPx2);
  const double side2 = side * side;
  BlurredEdge e;
  e.shift = 0.5 * tangent2 + 0.5 * kPixelAreaVarPx2 * side2;
  // The curvature also widens the edge: the tangential offset Y (blur and square) moves it by
  // kappa Y^2 / 2, whose variance kappa^2 var(Y^2) / 4 adds to the edge's (var(Y^2) = (2 + g)
  // sd^4 + sd^2 s^2 / 3 + s^4 (1/80 - 1/144) for a round PSF of sd and excess kurtosis g plus a
  // uniform of width s; g as TangentialExcess reads it).
  const double var_y2 = (2.0 + TangentialExcess(gc_k)) * tangent2 * tangent2 +
                        tangent2 * side2 / 3.0 + side2 * side2 * (1.0 / 80.0 - 1.0 / 144.0);
  const double sd = std::sqrt(normal2 + 0.25 * kappa_edge * kappa_edge * var_y2);
  e.value = SquareEdge(dist - e.shift * kappa_edge, nx, ny, side, sd, gc_k, &e.slope);
  return e;
}

// Adds to d[5] the model's change through the edge normal's turn with v (x, y, P11, P12, P22):
// aniso_n = c (nx^2 - ny^2) + 2 s nx ny moves with n = g / |g|; dvalue_daniso its effect.
void AddNormalTurn(const double* v, double dx, double dy, double nx, double ny, double n,
                   const PixelResponse& r, double dvalue_daniso, double* d) {
  const double dgx[5] = {-v[2], -v[3], dx, dy, 0.0};
  const double dgy[5] = {-v[3], -v[4], 0.0, dx, dy};
  for (int k = 0; k < 5; ++k) {
    const double along = nx * dgx[k] + ny * dgy[k];
    const double dnx = (dgx[k] - nx * along) / n, dny = (dgy[k] - ny * along) / n;
    const double daniso =
        2.0 * r.aniso_c * (nx * dnx - ny * dny) + 2.0 * r.aniso_s * (dnx * ny + nx * dny);
    d[k] += dvalue_daniso * daniso;
  }
}

}  // namespace

// The response for a blur of `blur_var_px2` per axis (pixel area included) of which
// `crosstalk_var_px2` comes after the sampling: the optics' sd, their edge's Gram-Charlier term
// and the crosstalk's kernel.
PixelResponse MakeResponse(double blur_var_px2, double crosstalk_var_px2, double lattice_share,
                           double optics_excess) {
  PixelResponse r;
  r.gc_k = optics_excess / 24.0;
  r.optics_sd =
      std::sqrt(std::max(blur_var_px2 - kPixelAreaVarPx2 - crosstalk_var_px2, kMinOpticsVarPx2));
  r.kernel = {1.0};
  if (!(crosstalk_var_px2 > 1e-6)) return r;
  r.kernel = CrosstalkKernel(crosstalk_var_px2, lattice_share);
  r.reach = static_cast<int>(r.kernel.size() / 2);
  return r;
}

namespace {

// A pixel this near the disc's centre (|dx| + |dy|, px) is taken this far off it along x.
constexpr double kCentreOffsetPx = 1e-3;

// The edge geometry of the point (x, y) for the disc v, but the level set's curvature and P g.
// At the disc's very centre the edge's normal is undefined (g = 0): the point is taken a hair
// off it, where the model is continuous (its value moves by the edge's slope times 1e-3 px).
EdgeGeometry GeometryAt(const double* v, double x, double y) {
  EdgeGeometry e{};
  e.dx = std::fabs(x - v[0]) + std::fabs(y - v[1]) < kCentreOffsetPx ? kCentreOffsetPx : x - v[0];
  e.dy = y - v[1];
  e.gx = v[2] * e.dx + v[3] * e.dy, e.gy = v[3] * e.dx + v[4] * e.dy;  // g = P (p - c)
  const double q = e.dx * e.gx + e.dy * e.gy;
  e.r = std::sqrt(q), e.n = std::hypot(e.gx, e.gy);
  e.dist = (e.r - q) / e.n;
  return e;
}
// The curvature of the level set through the point, and P g, into e.
void AddCurvature(const double* v, EdgeGeometry* e) {
  e->pgx = v[2] * e->gx + v[3] * e->gy, e->pgy = v[3] * e->gx + v[4] * e->gy;  // P g
  const double n2 = e->n * e->n;
  e->kappa = (n2 * (v[2] + v[4]) - (e->gx * e->pgx + e->gy * e->pgy)) / (n2 * e->n);
}

// SquareMean over a square of `side` px centred at (x, y); *near_edge false when it lies far
// from the edge (its value 1 or 0 at once, the derivatives 0).
double SideSquareMean(const double* v, double x, double y, double side, const PixelResponse& r,
                      double* d, bool* near_edge) {
  EdgeGeometry g = GeometryAt(v, x, y);
  const double dist = g.dist;
  const double optics_var = r.optics_sd * r.optics_sd;
  const double aniso = std::hypot(r.aniso_c, r.aniso_s);
  const double margin = 1.25 + 5.0 * std::sqrt(optics_var + aniso);
  std::fill(d, d + 5, 0.0);
  // Only the margin decides: a pixel inside a small, blurred disc is its edge's however near the
  // centre it lies (set to 1 within 0.3 R of the centre, the model stepped by the edge's tail
  // there as the radius moved, 0.006 of the step behind a heavy-tailed edge; docs/estimator.md
  // "A pixel near the disc's centre").
  *near_edge = !(dist > margin || dist < -margin);
  if (!*near_edge) return dist < 0.0 ? 0.0 : 1.0;
  // The curvature of the level set through the pixel, scaled to the disc's edge (the level sets
  // of q are the edge scaled by sqrt q): the edge's own curvature bends the blur's reach.
  AddCurvature(v, &g);
  const double kappa_edge = g.kappa * g.r;
  const double nx = g.gx / g.n, ny = g.gy / g.n, dx = g.dx, dy = g.dy, n = g.n;
  const double aniso_n = r.aniso_c * (nx * nx - ny * ny) + 2.0 * r.aniso_s * nx * ny;
  const BlurredEdge e = BlurEdge(dist, kappa_edge, nx, ny, side, optics_var, aniso_n, r.gc_k);
  DiscDerivatives(v, g, e.slope, e.shift, d);
  if (aniso > 0.0) {
    const double h = 1e-4 * (optics_var + aniso);
    const double up =
        BlurEdge(dist, kappa_edge, nx, ny, side, optics_var, aniso_n + h, r.gc_k).value;
    const double down =
        BlurEdge(dist, kappa_edge, nx, ny, side, optics_var, aniso_n - h, r.gc_k).value;
    AddNormalTurn(v, dx, dy, nx, ny, n, r, (up - down) / (2.0 * h), d);
  }
  return e.value;
}

// The weight of the pixel's four half-squares in SquareMean: 1 behind optics sharper than
// kSubSquaresFullSdPx, 0 beyond kSubSquaresNoneSdPx, linear between (the model stays continuous
// in the blur, which FitBlurSplit and the blob fit's own blur search over).
constexpr double kSubSquaresFullSdPx = 0.15, kSubSquaresNoneSdPx = 0.3;
double SubSquareWeight(double optics_sd) {
  return std::clamp((kSubSquaresNoneSdPx - optics_sd) / (kSubSquaresNoneSdPx - kSubSquaresFullSdPx),
                    0.0, 1.0);
}

// The edge correction's table at offset t (linear between its knots, 0 beyond them) and its
// slope along t.
double CorrectionAt(const std::vector<double>& table, double t, double* slope) {
  *slope = 0.0;
  const double u = (t + kEdgeCorrectionHalfWidthPx) / kEdgeCorrectionStepPx;
  if (!(u >= 0.0) || !(u < kEdgeCorrectionKnots - 1) ||
      table.size() != static_cast<size_t>(kEdgeCorrectionKnots)) {
    return 0.0;
  }
  const auto k = static_cast<size_t>(u);
  const double step = table[k + 1] - table[k];
  *slope = step / kEdgeCorrectionStepPx;
  return table[k] + (u - static_cast<double>(k)) * step;
}

// EdgeOffsetPx's curvature shift, the 50% point's kappa (optics_sd^2 + 1/12) / 2 over kappa, and
// the offset at the geometry g (its curvature added).
double EdgeShift(const PixelResponse& r) {
  return 0.5 * (r.optics_sd * r.optics_sd + kPixelAreaVarPx2);
}
double OffsetOf(const EdgeGeometry& g, double shift) { return g.dist - shift * g.kappa * g.r; }

// The edge correction's share of the pixel at (x, y), its derivatives added to d[5] (none
// computed where the pixel lies beyond the table: most of a fit's window).
double AddEdgeCorrection(const double* v, double x, double y, const PixelResponse& r, double* d) {
  if (!r.edge_correction) return 0.0;
  EdgeGeometry g = GeometryAt(v, x, y);
  AddCurvature(v, &g);
  const double shift = EdgeShift(r);
  double slope = 0.0;
  const double c = CorrectionAt(*r.edge_correction, OffsetOf(g, shift), &slope);
  if (c == 0.0 && slope == 0.0) return 0.0;
  double dc[5];
  DiscDerivatives(v, g, slope, shift, dc);
  for (int k = 0; k < 5; ++k) d[k] += dc[k];
  return c;
}

}  // namespace

double EdgeOffsetPx(const double* v, double x, double y, const PixelResponse& r) {
  EdgeGeometry g = GeometryAt(v, x, y);
  AddCurvature(v, &g);
  return OffsetOf(g, EdgeShift(r));
}

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
// Behind sharp optics the curved edge's sagitta across the square is not a Gaussian widening (a
// sharp disc's pixels were 0.005-0.007 of the amplitude off, its second moment +-0.1% with the
// radius's phase): there the square is the mean of its four half-squares, each a straight edge
// at its own distance (the sagitta's error falls as the side squared: +-0.03%).
double SquareMean(const double* v, double x, double y, const PixelResponse& r, double* d) {
  bool near_edge = false;
  const double whole = SideSquareMean(v, x, y, 1.0, r, d, &near_edge);
  const double w = SubSquareWeight(r.optics_sd);
  if (!near_edge || w == 0.0) return whole + AddEdgeCorrection(v, x, y, r, d);
  double halves = 0.0, sum[5] = {0.0, 0.0, 0.0, 0.0, 0.0}, part[5];
  for (const double oy : {-0.25, 0.25}) {
    for (const double ox : {-0.25, 0.25}) {
      halves += 0.25 * SideSquareMean(v, x + ox, y + oy, 0.5, r, part, &near_edge);
      for (int k = 0; k < 5; ++k) sum[k] += 0.25 * part[k];
    }
  }
  for (int k = 0; k < 5; ++k) d[k] = (1.0 - w) * d[k] + w * sum[k];
  return (1.0 - w) * whole + w * halves + AddEdgeCorrection(v, x, y, r, d);
}

// `in` (rows x cols, row-major) convolved with `kernel` along x (dx = 1) or y, keeping the valid
// part, into `out`: (rows x (cols - 2 reach)) or ((rows - 2 reach) x cols).
void Convolve(const double* in, int rows, int cols, const std::vector<double>& kernel,
              bool along_x, double* out) {
  const int reach = static_cast<int>(kernel.size() / 2);
  const int out_rows = along_x ? rows : rows - 2 * reach;
  const int out_cols = along_x ? cols - 2 * reach : cols;
  // Row by row, each tap added over a contiguous run of the row (the compiler vectorises it):
  // along x the tap's run starts k columns on, along y k rows down.
  for (int row = 0; row < out_rows; ++row) {
    double* o = &out[static_cast<size_t>(row) * out_cols];
    std::fill(o, o + out_cols, 0.0);
    for (size_t k = 0; k < kernel.size(); ++k) {
      const double w = kernel[k];
      const double* first = along_x ? &in[static_cast<size_t>(row) * cols + k]
                                    : &in[(static_cast<size_t>(row) + k) * cols];
      for (int col = 0; col < out_cols; ++col) o[col] += w * first[col];
    }
  }
}

void Spread(const double* in, int rows, int cols, const std::vector<double>& kernel,
            std::vector<double>* across, double* out) {
  const int reach = static_cast<int>(kernel.size() / 2);
  across->resize(static_cast<size_t>(rows) * (cols - 2 * reach));
  Convolve(in, rows, cols, kernel, true, across->data());
  Convolve(across->data(), rows, cols - 2 * reach, kernel, false, out);
}

}  // namespace blob_model
}  // namespace irdist
