#include "sim/lens_psf.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "sim/scene.h"
#include "tests/sim/signal_moments.h"

namespace irdist::sim {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

PoseState FaceOn(double slide_mm) {
  PoseState p;
  p.slide_mm = slide_mm;
  p.bias_ma = 500.0;
  return p;
}

using testing::Covariance;
using testing::CovarianceOf;

// The largest difference between two renders' pixels where their windows overlap, over the
// second's peak (a PSF's profile against a Gaussian of the same variance).
double LargestDifferenceOverPeak(const SignalWindow& a, const SignalWindow& gauss) {
  const cv::Rect both = a.rect & gauss.rect;
  const cv::Mat1f a_px = a.electrons(both - a.rect.tl());
  const cv::Mat1f gauss_px = gauss.electrons(both - gauss.rect.tl());
  double peak = 0.0, differs = 0.0;
  for (int r = 0; r < both.height; ++r) {
    for (int c = 0; c < both.width; ++c) {
      peak = std::max(peak, static_cast<double>(gauss_px(r, c)));
      differs = std::max(differs, std::fabs(static_cast<double>(a_px(r, c) - gauss_px(r, c))));
    }
  }
  return differs / peak;
}

RigPhysics Sharp() {
  RigPhysics p;
  p.optics.focus_mm = 0.0;  // no defocus: the PSF alone
  return p;
}

// An astigmatic lens: the face-on disc's image covariance is the disc's (D^2 / 16 per axis), the
// PSF's elliptical covariance (sd 1.05 px along 30 deg, 0.7 across) and the pixel's 1/12, at
// every distance: the anisotropy a constant in pixels, not a share of the disc's size.
TEST(LensPsf, EllipticalPsfAddsItsCovarianceAtEveryDistance) {
  RigPhysics p = Sharp();
  p.optics.psf_sigma_px = 1.05;
  p.optics.psf_sigma_minor_px = 0.7;
  p.optics.psf_angle_deg = 30.0;
  const Scene scene(p);
  const Scene round(Sharp());
  const double a = 30.0 * kDeg, l1 = 1.05 * 1.05, l2 = 0.49;
  const double sxx = l1 * std::cos(a) * std::cos(a) + l2 * std::sin(a) * std::sin(a);
  const double syy = l1 * std::sin(a) * std::sin(a) + l2 * std::cos(a) * std::cos(a);
  const double sxy = (l1 - l2) * std::cos(a) * std::sin(a);
  for (double d : {1500.0, 2250.0, 3000.0}) {
    const double disc = std::pow(scene.Project(FaceOn(d)).major_px, 2) / 16.0;
    const Covariance c = CovarianceOf(scene.RenderSignal(FaceOn(d), 100.0, 0.01));
    EXPECT_NEAR(c.xx, disc + sxx + 1.0 / 12.0, 2e-3) << d;
    EXPECT_NEAR(c.yy, disc + syy + 1.0 / 12.0, 2e-3) << d;
    EXPECT_NEAR(c.xy, sxy, 2e-3) << d;
    // The light is only spread, never lost or made.
    const Covariance r = CovarianceOf(round.RenderSignal(FaceOn(d), 100.0, 0.01));
    EXPECT_NEAR(c.sum / r.sum, 1.0, 1e-5) << d;
  }
}

// A PSF along the rows (angle 0) takes the separable path, one turned by 90 deg the same path
// with x and y swapped, and one turned by 1e-3 deg the sheared one: all three agree with their
// neighbours (the sheared quadrature against the closed form).
TEST(LensPsf, ShearedPathAgreesWithSeparableOne) {
  RigPhysics p = Sharp();
  p.optics.psf_sigma_px = 1.2;
  p.optics.psf_sigma_minor_px = 0.6;
  RigPhysics turned = p;
  turned.optics.psf_angle_deg = 1e-4;
  const SignalWindow a = Scene(p).RenderSignal(FaceOn(2100.0), 100.0, 0.01);
  const SignalWindow b = Scene(turned).RenderSignal(FaceOn(2100.0), 100.0, 0.01);
  ASSERT_EQ(a.rect, b.rect);
  double peak = 0.0, worst = 0.0;
  for (int r = 0; r < a.electrons.rows; ++r) {
    for (int c = 0; c < a.electrons.cols; ++c) {
      peak = std::max(peak, static_cast<double>(a.electrons(r, c)));
      worst = std::max(worst, std::fabs(static_cast<double>(a.electrons(r, c) - b.electrons(r, c))));
    }
  }
  EXPECT_LT(worst, 1e-5 * peak);
}

// The geometric defocus: a uniform disc of diameter c (the thin lens's circle of confusion, here
// 2-4 px between 1.5 and 3 m with the focus at 1 m) convolved with the in-focus PSF. Its variance
// per axis is c^2 / 16 as the Gaussian stand-in's, and the light is kept; but the profile is the
// disc's (flat-topped, a steeper edge): it differs from the Gaussian's.
TEST(LensPsf, DefocusDiscKeepsVarianceButNotTheGaussianProfile) {
  RigPhysics gauss;
  gauss.optics.psf_sigma_px = 0.5;
  gauss.optics.focus_mm = 1000.0;
  RigPhysics disc = gauss;
  disc.optics.defocus_disc = true;
  const Scene g(gauss), s(disc);
  for (double d : {1500.0, 3000.0}) {
    const double coc = s.CircleOfConfusionPx(d);
    EXPECT_GT(coc, 1.9) << d;
    const double var = std::pow(s.Project(FaceOn(d)).major_px, 2) / 16.0 + 0.25 + 1.0 / 12.0 +
                       coc * coc / 16.0;
    const SignalWindow wd = s.RenderSignal(FaceOn(d), 100.0, 0.01);
    const SignalWindow wg = g.RenderSignal(FaceOn(d), 100.0, 0.01);
    const Covariance cd = CovarianceOf(wd), cg = CovarianceOf(wg);
    EXPECT_NEAR(cd.xx, var, 3e-3 * var) << d;
    EXPECT_NEAR(cd.yy, var, 3e-3 * var) << d;
    EXPECT_NEAR(cd.xy, 0.0, 1e-3) << d;
    EXPECT_NEAR(cd.sum / cg.sum, 1.0, 1e-4) << d;
    // (the disc's window reaches its radius farther)
    EXPECT_GT(LargestDifferenceOverPeak(wd, wg), 0.004)
        << d;  // 0.6% of the peak at 1 px radius, more at 2
  }
}

// The quadrature of the uniform disc: weights sum to 1, its second moment is R^2 / 4 per axis.
TEST(LensPsf, DiscQuadratureKeepsAreaAndSecondMoment) {
  for (double radius : {0.3, 1.0, 2.7}) {
    double sum = 0.0, xx = 0.0, yy = 0.0, x = 0.0;
    for (const auto& p : disc_image::DiscQuadrature(radius, 0.25)) {
      sum += p.weight;
      x += p.weight * p.dx;
      xx += p.weight * p.dx * p.dx;
      yy += p.weight * p.dy * p.dy;
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
    EXPECT_NEAR(x, 0.0, 1e-12);
    EXPECT_NEAR(xx, radius * radius / 4.0, 2e-3 * radius * radius);
    EXPECT_NEAR(yy, radius * radius / 4.0, 2e-3 * radius * radius);
  }
}

// The Airy pattern's quadrature (a diffraction-limited lens): the weights sum to 1 and keep the
// centre; the energy inside the first dark ring is the pattern's 83.8% of its 93.8% inside the
// third (Born & Wolf's figures), and the second moment is the cut pattern's, integrated here
// directly from (2 J1(x) / x)^2.
TEST(LensPsf, AiryQuadratureIsTheCutAiryPattern) {
  for (double r0 : {0.5, 1.0, 2.0}) {
    const double reach = kAiryReachZeros * r0;
    double sum = 0.0, x = 0.0, rr = 0.0, inside = 0.0;
    for (const auto& p : disc_image::AiryQuadrature(r0, 0.1 * r0, 0.2)) {
      const double r2 = p.dx * p.dx + p.dy * p.dy;
      sum += p.weight;
      x += p.weight * p.dx;
      rr += p.weight * r2;
      if (r2 <= r0 * r0) inside += p.weight;
      EXPECT_LE(std::sqrt(r2), reach + 1e-9);
    }
    EXPECT_NEAR(sum, 1.0, 1e-12) << r0;
    EXPECT_NEAR(x, 0.0, 1e-12) << r0;
    EXPECT_NEAR(inside, 0.838 / 0.938, 0.02) << r0;
    double energy = 0.0, moment = 0.0;
    const int steps = 20000;
    for (int i = 0; i < steps; ++i) {
      const double r = (i + 0.5) * reach / steps, u = 3.8317 * r / r0;
      const double j = 2.0 * std::cyl_bessel_j(1.0, u) / u;
      energy += j * j * r;
      moment += j * j * r * r * r;
    }
    EXPECT_NEAR(rr, moment / energy, 1e-3 * moment / energy) << r0;
  }
}

// The rig's Airy quadrature (rings and points 1.2 core sd apart) blurred by the core is the
// pattern blurred by it to 0.3% of its peak (a second-order quadrature: each ring's light lumped
// on one radius): against one twenty times finer, the two differ by less than 0.5% of the peak
// anywhere, and one five times finer than the rig's by less than 0.15%.
TEST(LensPsf, TheRigsAiryQuadratureBlurredByTheCoreHasConverged) {
  const double sd = 0.5, r0 = 1.0;
  const auto coarse = disc_image::AiryQuadrature(r0, 1.2 * sd, 1.2 * sd);
  const auto finer = disc_image::AiryQuadrature(r0, 0.24 * sd, 0.24 * sd);
  const auto fine = disc_image::AiryQuadrature(r0, 0.06 * sd, 0.06 * sd);
  auto blurred = [sd](const std::vector<disc_image::DiscPoint>& points, double x, double y) {
    double sum = 0.0;
    for (const auto& p : points) {
      sum += p.weight *
             std::exp(-0.5 * ((x - p.dx) * (x - p.dx) + (y - p.dy) * (y - p.dy)) / (sd * sd));
    }
    return sum / (2.0 * 3.14159265358979323846 * sd * sd);
  };
  const double peak = blurred(fine, 0.0, 0.0);
  double worst = 0.0, worst_finer = 0.0;
  for (double x = -4.0; x <= 4.0; x += 0.13) {
    for (double y = -1.0; y <= 1.0; y += 0.37) {
      worst = std::max(worst, std::fabs(blurred(coarse, x, y) - blurred(fine, x, y)));
      worst_finer = std::max(worst_finer, std::fabs(blurred(finer, x, y) - blurred(fine, x, y)));
    }
  }
  EXPECT_LT(worst, 5e-3 * peak);
  EXPECT_LT(worst_finer, 1.5e-3 * peak);
}

// An Airy lens (first dark ring at 1 px) renders the disc with its light kept and the pattern's
// variance added to the core's, but not as a Gaussian of that variance: its rings reach farther.
TEST(LensPsf, AnAiryLensAddsItsPatternsVarianceButNotAGaussiansProfile) {
  RigPhysics airy = Sharp();
  airy.optics.psf_sigma_px = 0.5;
  airy.optics.airy_first_zero_px = 1.0;
  std::string why;
  ASSERT_TRUE(airy.optics.IsValid(&why)) << why;
  double pattern_var = 0.0;
  for (const auto& p : disc_image::AiryQuadrature(1.0, 0.1, 0.2)) {
    pattern_var += p.weight * p.dx * p.dx;
  }
  RigPhysics gauss = Sharp();
  gauss.optics.psf_sigma_px = std::sqrt(0.25 + pattern_var);
  const Scene a(airy), g(gauss);
  const double d = 2000.0;
  const double var =
      std::pow(a.Project(FaceOn(d)).major_px, 2) / 16.0 + 0.25 + pattern_var + 1.0 / 12.0;
  const SignalWindow wa = a.RenderSignal(FaceOn(d), 100.0, 0.01);
  const SignalWindow wg = g.RenderSignal(FaceOn(d), 100.0, 0.01);
  const Covariance ca = CovarianceOf(wa), cg = CovarianceOf(wg);
  EXPECT_NEAR(ca.xx, var, 3e-3 * var);
  EXPECT_NEAR(ca.yy, var, 3e-3 * var);
  EXPECT_NEAR(ca.sum / cg.sum, 1.0, 1e-4);
  EXPECT_GT(LargestDifferenceOverPeak(wa, wg), 0.004);
  // Bounds: a pattern narrower than the core's quadrature, or with the defocus disc, is refused.
  RigPhysics bad = airy;
  bad.optics.psf_sigma_px = 0.2;
  EXPECT_FALSE(bad.optics.IsValid(&why));
  bad = airy;
  bad.optics.defocus_disc = true;
  EXPECT_FALSE(bad.optics.IsValid(&why));
  bad = airy;
  bad.optics.airy_first_zero_px = 5.0;
  EXPECT_FALSE(bad.optics.IsValid(&why));
}

// Veiling glare: 3% of the light in a halo of sd 8 px. The light is kept, and the covariance is
// the mix of the core's and the halo's (each the disc's + its PSF's + the pixel's).
TEST(LensPsf, HaloSpreadsItsShareOfTheLight) {
  RigPhysics p = Sharp();
  p.optics.halo_share = 0.03;
  p.optics.halo_sigma_px = 8.0;
  const Scene scene(p), plain(Sharp());
  const double d = 2000.0;
  const double disc = std::pow(scene.Project(FaceOn(d)).major_px, 2) / 16.0 + 1.0 / 12.0;
  const Covariance c = CovarianceOf(scene.RenderSignal(FaceOn(d), 100.0, 0.01));
  const Covariance r = CovarianceOf(plain.RenderSignal(FaceOn(d), 100.0, 0.01));
  EXPECT_NEAR(c.sum / r.sum, 1.0, 2e-4);  // the halo's tails beyond 4 sd are cut (6e-5 of 3%)
  const double expected = disc + 0.97 * 0.49 + 0.03 * 64.0;
  EXPECT_NEAR(c.xx, expected, 0.02 * 0.03 * 64.0);
  EXPECT_NEAR(c.yy, expected, 0.02 * 0.03 * 64.0);
}

// A fill factor: each pixel senses only the central 70% of its pitch per side. Its box then adds
// 0.7^2 / 12 px^2 to the image's covariance instead of the whole pixel's 1/12 (a sharper pixel),
// on the separable path and on the sheared one (an astigmatic lens turned by 30 deg), and a flat
// field reads as with the whole pixel (the light is kept: the quantum efficiency is the pixel's).
TEST(LensPsf, PixelApertureNarrowsThePixelsBoxAndKeepsTheLight) {
  for (const double angle_deg : {0.0, 30.0}) {
    RigPhysics whole = Sharp();
    whole.optics.psf_sigma_minor_px = angle_deg == 0.0 ? 0.0 : 0.6;
    whole.optics.psf_angle_deg = angle_deg;
    RigPhysics narrow = whole;
    narrow.sensor.pixel_aperture = 0.7;
    const Scene w(whole), n(narrow);
    for (double d : {1500.0, 3000.0}) {
      const Covariance cw = CovarianceOf(w.RenderSignal(FaceOn(d), 100.0, 0.01));
      const Covariance cn = CovarianceOf(n.RenderSignal(FaceOn(d), 100.0, 0.01));
      EXPECT_NEAR(cn.sum / cw.sum, 1.0, 1e-4) << angle_deg << " deg, " << d;
      EXPECT_NEAR(cw.xx - cn.xx, (1.0 - 0.49) / 12.0, 1e-3) << angle_deg << " deg, " << d;
      EXPECT_NEAR(cw.yy - cn.yy, (1.0 - 0.49) / 12.0, 1e-3) << angle_deg << " deg, " << d;
      EXPECT_NEAR(cw.xy - cn.xy, 0.0, 1e-4) << angle_deg << " deg, " << d;
    }
  }
  // A flat field: the disc's plateau (1.5 m, a 9 px radius) reads the same through both.
  RigPhysics narrow = Sharp();
  narrow.sensor.pixel_aperture = 0.7;
  const SignalWindow a = Scene(Sharp()).RenderSignal(FaceOn(1500.0), 100.0, 0.01);
  const SignalWindow b = Scene(narrow).RenderSignal(FaceOn(1500.0), 100.0, 0.01);
  const cv::Point centre(a.electrons.cols / 2, a.electrons.rows / 2);
  EXPECT_NEAR(b.electrons(centre) / a.electrons(centre), 1.0, 1e-5);
}

// A sharp lens (no blur before the pixels, no defocus): the face-on disc centred on a pixel
// corner is as wide along x as along y (x and y swap by symmetry). The strips are exact across the
// row (closed form) but sample y: without the split at the rows' borders each strip's light fell
// whole into one row and the disc read 2.2% wider along x at 2500 mm (0.5% at 2000, 0.17% at 1500).
// With a pixel aperture the split falls where the sensitive heights begin and end.
TEST(LensPsf, ASharpDiscIsAsWideAlongXAsAlongY) {
  for (const double sigma : {0.0, 0.05, 0.2, -0.7}) {  // -0.7: sharp, a 70% pixel aperture
    RigPhysics p = Sharp();
    p.optics.psf_sigma_px = std::max(sigma, 0.0);
    if (sigma < 0.0) p.sensor.pixel_aperture = -sigma;
    const Scene scene(p);
    for (double d : {1500.0, 2000.0, 2500.0}) {
      const Covariance c = CovarianceOf(scene.RenderSignal(FaceOn(d), 100.0, 0.01));
      EXPECT_NEAR(c.xx / c.yy, 1.0, sigma < 0.0 ? 3e-4 : 1e-4) << "sd " << sigma << " px, " << d;
      EXPECT_NEAR(c.xy / c.yy, 0.0, 1e-6) << "sd " << sigma << " px, " << d;
    }
  }
}

}  // namespace
}  // namespace irdist::sim
