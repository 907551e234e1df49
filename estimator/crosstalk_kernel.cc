#include "estimator/crosstalk_kernel.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <vector>

#include <boost/math/special_functions/bessel.hpp>

namespace irdist {
namespace {

// The sampled, normalised Gaussian of sd `sd` over |n| <= reach, and its variance.
double SampledGaussian(double sd, int reach, std::vector<double>* kernel) {
  kernel->assign(2 * reach + 1, 0.0);
  double sum = 0.0, var = 0.0;
  for (int n = -reach; n <= reach; ++n) {
    const double w = std::exp(-0.5 * n * n / (sd * sd));
    (*kernel)[n + reach] = w;
    sum += w;
    var += w * n * n;
  }
  for (double& w : *kernel) w /= sum;
  return var / sum;
}

// The sampled, normalised Gaussian whose variance on the grid is `var` (its sd found by
// bisection: at small variances the sampled Gaussian's variance falls below sd^2).
std::vector<double> SampledGaussianOfVariance(double var) {
  if (!(var > 1e-6)) return {1.0};
  double low = 0.05, high = 3.0;
  for (int i = 0; i < 50; ++i) {
    const double sd = 0.5 * (low + high);
    std::vector<double> k;
    (SampledGaussian(sd, static_cast<int>(std::ceil(4.0 * sd)) + 1, &k) < var ? low : high) = sd;
  }
  std::vector<double> kernel;
  SampledGaussian(high, static_cast<int>(std::ceil(4.0 * high)) + 1, &kernel);
  return kernel;
}

// The lattice random walk of variance t: charge hopping between neighbouring pixels, e^-t I_n(t)
// n pixels away (the modified Bessel function, Boost), to 1e-9.
std::vector<double> LatticeWalk(double t) {
  if (!(t > 1e-6)) return {1.0};
  std::vector<double> half;
  for (int n = 0; n == 0 || half.back() > 1e-9; ++n) {
    half.push_back(std::exp(-t) * boost::math::cyl_bessel_i(n, t));
  }
  std::vector<double> kernel(2 * half.size() - 1);
  const int reach = static_cast<int>(half.size()) - 1;
  double sum = 0.0;
  for (int n = -reach; n <= reach; ++n) sum += kernel[n + reach] = half[std::abs(n)];
  for (double& w : kernel) w /= sum;
  return kernel;
}

}  // namespace

// Outer taps below this are dropped: such a tap moves a pixel by 1e-7 of the blob's amplitude,
// 0.007 DN at a 16-bit full scale (every tap of the grown grid and of the six planes the fit
// spreads costs time: the virtual rig's 0.0015 px^2 had two taps of 1e-9 each side).
constexpr double kKernelTailTap = 1e-7;
const std::vector<double>& CrosstalkKernel(double crosstalk_var_px2, double lattice_share) {
  thread_local double last_var = -1.0, last_share = -1.0;
  thread_local std::vector<double> kernel;
  if (crosstalk_var_px2 == last_var && lattice_share == last_share) return kernel;
  const double share = std::clamp(lattice_share, 0.0, 1.0);
  const std::vector<double> g = SampledGaussianOfVariance((1.0 - share) * crosstalk_var_px2);
  const std::vector<double> l = LatticeWalk(share * crosstalk_var_px2);
  kernel.assign(g.size() + l.size() - 1, 0.0);
  for (size_t i = 0; i < g.size(); ++i) {
    for (size_t j = 0; j < l.size(); ++j) kernel[i + j] += g[i] * l[j];
  }
  while (kernel.size() > 1 && kernel.front() < kKernelTailTap && kernel.back() < kKernelTailTap) {
    kernel.erase(kernel.begin());
    kernel.pop_back();
  }
  double sum = 0.0;
  for (double w : kernel) sum += w;
  for (double& w : kernel) w /= sum;
  last_var = crosstalk_var_px2, last_share = lattice_share;
  return kernel;
}

}  // namespace irdist
