#include "sim/lens_psf.h"

#include <cmath>

#include <gtest/gtest.h>

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
    const cv::Rect both = wd.rect & wg.rect;  // the disc's window reaches its radius farther
    const cv::Mat1f disc_px = wd.electrons(both - wd.rect.tl());
    const cv::Mat1f gauss_px = wg.electrons(both - wg.rect.tl());
    double peak = 0.0, differs = 0.0;
    for (int r = 0; r < both.height; ++r) {
      for (int c = 0; c < both.width; ++c) {
        peak = std::max(peak, static_cast<double>(gauss_px(r, c)));
        differs =
            std::max(differs, std::fabs(static_cast<double>(disc_px(r, c) - gauss_px(r, c))));
      }
    }
    EXPECT_GT(differs, 0.004 * peak) << d;  // 0.6% of the peak at 1 px radius, more at 2
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
