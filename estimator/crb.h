#pragma once
// Cramer-Rao bound (CRB) on the IRED's distance d and orientation theta from the pixels of a set
// of frames that share the unknowns p = (ln I0, theta, blob x, blob y, d). Each pixel's value is
// Gaussian with the EMVA 1288 temporal noise of its expected signal (shot noise of the signal and
// dark electrons, read noise, quantisation), so the Fisher information is
//   F_ij = sum over frames and pixels of (d mu / d p_i)(d mu / d p_j) / var(mu),
// mu the expected signal electrons of the pixel (the variance's own dependence on p is left out:
// its share is 1/(2 mu) of the mean's for a Poisson pixel, negligible for blobs of thousands of
// electrons). The bound on d is the (d, d) element of F's inverse: every other unknown free.
//
// This file knows nothing of where mu and its derivatives come from: the caller renders them
// (app/processing/crb.h does it with the virtual rig's physics) and passes one FrameSensitivity per frame.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace irdist {

// The unknowns, in the order of FrameSensitivity::derivatives.
enum CrbParam : int { kCrbLnI0 = 0, kCrbTheta, kCrbX, kCrbY, kCrbD, kNumCrbParams };

// EMVA 1288 temporal noise of one frame, in electrons.
struct PixelNoise {
  double read_noise_e = 0.0;          // read noise sd (e-)
  double dark_e = 0.0;                // dark and background electrons per pixel in the frame
  double system_gain_dn_per_e = 0.0;  // K; quantisation adds 1 / (12 K^2) e-^2 (0: none)
  // The variance (e-^2) of a pixel whose expected signal is signal_e.
  double VarianceE2(double signal_e) const;
  bool IsValid(std::string* why) const;
};

// One frame: its expected signal electrons per pixel and their derivatives with respect to each
// unknown (theta per RADIAN, x and y per pixel, d per mm, ln I0 dimensionless), all the same size.
struct FrameSensitivity {
  cv::Mat1d expected_e;
  cv::Mat1d derivatives[kNumCrbParams];
  PixelNoise noise;
};

struct CrbResult {
  bool valid = false;
  double d_sd_mm = 0.0;              // bound (standard deviation) on d, all other unknowns free
  double theta_sd_deg = 0.0;         // bound on theta; < 0 when theta is not identifiable to first
                                     // order (theta = 0: the image is even in theta)
  double d_sd_known_theta_mm = 0.0;  // bound on d with theta known
  double signal_e = 0.0;             // total signal electrons over the frames
  double peak_e = 0.0;               // brightest pixel's expected electrons
  std::string BriefReport() const;
};

// The Fisher information of the unknowns over a set of frames.
class FisherInformation {
 public:
  FisherInformation();
  void AddFrame(const FrameSensitivity& frame);
  double At(int i, int j) const { return fisher_(i, j); }
  // The bound's variance of `param` with every unknown in `free_params` estimated jointly (the
  // others known); NaN when the information of the free set is singular.
  double BoundVariance(int param, const std::vector<int>& free_params) const;

 private:
  cv::Matx<double, kNumCrbParams, kNumCrbParams> fisher_;
};

// The CRB of the frames: d and theta with every unknown free, and d with theta known. With
// theta_identifiable false (theta = 0, where the derivative in theta vanishes), theta is held
// known for both and theta_sd_deg is -1. valid = false when the information is singular.
CrbResult ComputeFrameCrb(const std::vector<FrameSensitivity>& frames, bool theta_identifiable);

}  // namespace irdist
