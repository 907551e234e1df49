#include "sim/sensor.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

namespace irdist::sim {
namespace {

// A uniform exposure of `electrons` per pixel over a region (drawn exactly, pixel by pixel).
SignalWindow Uniform(cv::Rect rect, double electrons) {
  SignalWindow w;
  w.rect = rect;
  w.electrons = cv::Mat1f(rect.size(), static_cast<float>(electrons));
  return w;
}

// Mean, and temporal variance from the difference of two frames (EMVA 1288), of a region.
void MeanVar(const cv::Mat& a, const cv::Mat& b, cv::Rect region, double* mean, double* var) {
  cv::Mat fa, fb;
  a(region).convertTo(fa, CV_64F);
  b(region).convertTo(fb, CV_64F);
  *mean = 0.5 * (cv::mean(fa)[0] + cv::mean(fb)[0]);
  cv::Scalar m, s;
  cv::meanStdDev(fa - fb, m, s);
  *var = 0.5 * s[0] * s[0];
}

// Least-squares slope of y on x.
double Slope(const std::vector<double>& x, const std::vector<double>& y) {
  double mx = 0, my = 0;
  for (size_t i = 0; i < x.size(); ++i) mx += x[i], my += y[i];
  mx /= x.size(), my /= y.size();
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < x.size(); ++i) sxy += (x[i] - mx) * (y[i] - my), sxx += (x[i] - mx) * (x[i] - mx);
  return sxy / sxx;
}

TEST(Sensor, DefaultsAreValid) {
  std::string why;
  EXPECT_TRUE(SensorOptions{}.IsValid(&why)) << why;
}

// The photon-transfer line: temporal variance against mean (dark subtracted) has slope K, for
// the exactly drawn pixels (the emitter's window) and the table-drawn rest of the frame alike.
TEST(Sensor, PhotonTransferSlopeIsSystemGain) {
  SensorOptions o;
  o.background_e_per_s = 2.0e5;  // a flat field
  const Sensor sensor(o);
  const cv::Rect exact(500, 400, 200, 150);
  const cv::Rect table(0, 0, 400, 300);
  std::vector<double> mean_exact, var_exact, mean_table, var_table;
  double dark_mean = 0, dark_var = 0;
  {
    SensorOptions dark = o;
    dark.background_e_per_s = 0.0;
    const Sensor dark_sensor(dark);
    const cv::Mat a = dark_sensor.Expose(Uniform(exact, 0.0), 0.001, 1, PixelFormat::kMono12);
    const cv::Mat b = dark_sensor.Expose(Uniform(exact, 0.0), 0.001, 2, PixelFormat::kMono12);
    MeanVar(a, b, exact, &dark_mean, &dark_var);
  }
  std::uint64_t frame = 10;
  for (double t : {0.002, 0.005, 0.010, 0.015, 0.020, 0.030, 0.040}) {
    const SignalWindow window = Uniform(exact, 0.0);
    const cv::Mat a = sensor.Expose(window, t, frame++, PixelFormat::kMono12);
    const cv::Mat b = sensor.Expose(window, t, frame++, PixelFormat::kMono12);
    double m, v;
    MeanVar(a, b, exact, &m, &v);
    mean_exact.push_back(m - dark_mean);
    var_exact.push_back(v - dark_var);
    MeanVar(a, b, table, &m, &v);
    mean_table.push_back(m - dark_mean);
    var_table.push_back(v - dark_var);
  }
  EXPECT_NEAR(Slope(mean_exact, var_exact), o.system_gain_dn_per_e, 0.05 * o.system_gain_dn_per_e);
  EXPECT_NEAR(Slope(mean_table, var_table), o.system_gain_dn_per_e, 0.05 * o.system_gain_dn_per_e);
  // Dark noise: K^2 sigma_r^2 + 1/12 (quantisation) + K^2 * dark electrons.
  const double k = o.system_gain_dn_per_e;
  const double expected_dark =
      k * k * (o.read_noise_e * o.read_noise_e + o.dark_current_e_per_s * 0.001) + 1.0 / 12.0;
  EXPECT_NEAR(dark_var, expected_dark, 0.1 * expected_dark);
  EXPECT_NEAR(dark_mean, o.black_level_dn, 0.2);
}

TEST(Sensor, FramesAreReproducibleFromSeedAndIndex) {
  const Sensor sensor{SensorOptions{}};
  const SignalWindow w = Uniform(cv::Rect(600, 500, 20, 20), 3000.0);
  const cv::Mat a = sensor.Expose(w, 0.01, 7, PixelFormat::kMono12);
  const cv::Mat b = sensor.Expose(w, 0.01, 7, PixelFormat::kMono12);
  const cv::Mat c = sensor.Expose(w, 0.01, 8, PixelFormat::kMono12);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_L1), 0.0);
  EXPECT_GT(cv::norm(a, c, cv::NORM_L1), 0.0);
  SensorOptions other;
  other.seed = 2;
  const cv::Mat d = Sensor(other).Expose(w, 0.01, 7, PixelFormat::kMono12);
  EXPECT_GT(cv::norm(a, d, cv::NORM_L1), 0.0);
}

TEST(Sensor, SaturatesAtAdcMaximumAndFormatsShift) {
  const SensorOptions o;
  const Sensor sensor(o);
  const cv::Rect r(100, 100, 10, 10);
  const cv::Mat bright = sensor.Expose(Uniform(r, 1e6), 0.01, 1, PixelFormat::kMono12);
  double lo, hi;
  cv::minMaxLoc(bright(r), &lo, &hi);
  EXPECT_EQ(lo, o.AdcMax());
  const cv::Mat m8 = sensor.Expose(Uniform(r, 1e6), 0.01, 1, PixelFormat::kMono8);
  const cv::Mat m16 = sensor.Expose(Uniform(r, 1e6), 0.01, 1, PixelFormat::kMono16);
  EXPECT_EQ(m8.type(), CV_8UC1);
  EXPECT_EQ(m8.at<std::uint8_t>(105, 105), 255);
  EXPECT_EQ(m16.at<std::uint16_t>(105, 105), 4095 << 4);
  // Mono8 drops the ADC's 4 low bits, Mono16 adds 4: same frame, same noise draws.
  const cv::Mat m12 = sensor.Expose(Uniform(r, 2000.0), 0.01, 3, PixelFormat::kMono12);
  const cv::Mat m8b = sensor.Expose(Uniform(r, 2000.0), 0.01, 3, PixelFormat::kMono8);
  EXPECT_EQ(m8b.at<std::uint8_t>(103, 104), m12.at<std::uint16_t>(103, 104) >> 4);
}

TEST(Sensor, NonlinearityCompressesHighSignals) {
  SensorOptions o;
  o.nonlinearity = 0.1;
  const Sensor curved(o);
  const Sensor linear{SensorOptions{}};
  EXPECT_NEAR(curved.MeanAdc(0, 0), linear.MeanAdc(0, 0), 0.01);
  EXPECT_LT(curved.MeanAdc(8000, 0), linear.MeanAdc(8000, 0) - 50);
}

// A small sensor (the fixed-pattern tests average many frames).
SensorOptions Small() {
  SensorOptions o;
  o.width_px = 320;
  o.height_px = 256;
  return o;
}

// EMVA 1288 spatial nonuniformity of a region: the spatial variance of the average of `frames`
// frames, less the temporal variance's share that survives the average, in ADC counts^2.
double SpatialVarianceDn2(const Sensor& sensor, const SignalWindow& w, cv::Rect region, int frames) {
  cv::Mat1d sum = cv::Mat1d::zeros(region.size());
  double temporal_var = 0.0;
  cv::Mat previous;
  for (int n = 0; n < frames; ++n) {
    const cv::Mat frame = sensor.Expose(w, 0.001, 100 + n, PixelFormat::kMono12);
    cv::Mat f;
    frame(region).convertTo(f, CV_64F);
    sum += f;
    if (n % 2 == 1) {
      double mean = 0.0, var = 0.0;
      MeanVar(previous, frame, region, &mean, &var);
      temporal_var += var / (frames / 2);
    }
    previous = frame;
  }
  cv::Scalar m, sd;
  cv::meanStdDev(sum / frames, m, sd);
  return sd[0] * sd[0] - temporal_var / frames;
}

// DSNU: the dark frames' spatial sd, over the averaged frames, is dsnu_e x K, in the exactly drawn
// window and in the table-drawn rest alike; with DSNU off it is zero.
TEST(Sensor, DarkSignalNonuniformityMatchesDsnu) {
  SensorOptions o = Small();
  o.dsnu_e = 3.0;
  const Sensor sensor(o);
  const cv::Rect exact(150, 100, 120, 100), table(0, 0, 140, 90);
  const SignalWindow dark = Uniform(exact, 0.0);
  const double k = o.system_gain_dn_per_e;
  EXPECT_NEAR(std::sqrt(SpatialVarianceDn2(sensor, dark, exact, 32)) / k, 3.0, 0.15);
  EXPECT_NEAR(std::sqrt(SpatialVarianceDn2(sensor, dark, table, 32)) / k, 3.0, 0.15);
  const Sensor clean{Small()};
  EXPECT_LT(std::abs(SpatialVarianceDn2(clean, dark, exact, 32)) / (k * k), 0.3);
}

// PRNU: under a uniform exposure, the spatial sd of the averaged signal is prnu_percent of it.
TEST(Sensor, PhotoResponseNonuniformityMatchesPrnu) {
  SensorOptions o = Small();
  o.prnu_percent = 1.0;
  const Sensor sensor(o);
  const cv::Rect exact(150, 100, 120, 100);
  const double signal_e = 5000.0, k = o.system_gain_dn_per_e;
  const double sd_e = std::sqrt(SpatialVarianceDn2(sensor, Uniform(exact, signal_e), exact, 32)) / k;
  EXPECT_NEAR(100.0 * sd_e / signal_e, 1.0, 0.05);
  const Sensor clean{Small()};
  const double clean_sd_e =
      std::sqrt(std::max(0.0, SpatialVarianceDn2(clean, Uniform(exact, signal_e), exact, 32))) / k;
  EXPECT_LT(100.0 * clean_sd_e / signal_e, 0.1);
}

// The pattern belongs to the camera: the same seed gives the same maps (any frame, any run), another
// seed another pattern; the pixel map reads back the documented spread.
TEST(Sensor, FixedPatternIsFixedPerCamera) {
  SensorOptions o;
  o.prnu_percent = 0.5;
  o.dsnu_e = 2.0;
  const Sensor a(o), b(o);
  SensorOptions other = o;
  other.seed = 2;
  const Sensor c(other);
  EXPECT_EQ(a.PixelGain(10, 20), b.PixelGain(10, 20));
  EXPECT_EQ(a.PixelDarkOffsetE(700, 300), b.PixelDarkOffsetE(700, 300));
  EXPECT_NE(a.PixelGain(10, 20), c.PixelGain(10, 20));
  EXPECT_NE(a.PixelDarkOffsetE(700, 300), c.PixelDarkOffsetE(700, 300));
  double sum = 0.0, sum2 = 0.0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    const double g = a.PixelGain(i % o.width_px, i / o.width_px) - 1.0;
    sum += g, sum2 += g * g;
  }
  EXPECT_NEAR(std::sqrt(sum2 / n - (sum / n) * (sum / n)), 0.005, 0.0002);
  EXPECT_EQ(Sensor(SensorOptions{}).PixelGain(5, 5), 1.0);
  EXPECT_EQ(Sensor(SensorOptions{}).PixelDarkOffsetE(5, 5), 0.0);
}

}  // namespace
}  // namespace irdist::sim

namespace irdist::sim {
namespace {

// A single pixel holding `electrons` at (x, y).
SignalWindow Point(int x, int y, double electrons) {
  SignalWindow w;
  w.rect = cv::Rect(x, y, 1, 1);
  w.electrons = cv::Mat1f(1, 1, static_cast<float>(electrons));
  return w;
}

// Crosstalk spreads a point's charge by the lattice diffusion kernel: nothing is lost, the
// spread is separable, and its variance along each axis is sigma^2 (what a Gaussian blur of that
// sigma after the pixels adds to a blob's second moment).
TEST(Sensor, CrosstalkConservesChargeAndSpreadsAPointBySigma) {
  const cv::Rect sensor(0, 0, 1280, 1024);
  for (double sigma : {0.3, 0.6, 1.0, 2.0}) {
    const SignalWindow w =
        DiffuseCharge(Point(600, 500, 1000.0), sigma, CrosstalkShape::kLatticeWalk, sensor);
    double sum = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
    for (int r = 0; r < w.electrons.rows; ++r) {
      for (int c = 0; c < w.electrons.cols; ++c) {
        const double v = w.electrons(r, c), x = w.rect.x + c - 600.0, y = w.rect.y + r - 500.0;
        sum += v, sx += v * x, sy += v * y, sxx += v * x * x, syy += v * y * y, sxy += v * x * y;
      }
    }
    EXPECT_NEAR(sum, 1000.0, 1e-3) << sigma;
    EXPECT_NEAR(sx / sum, 0.0, 1e-6) << sigma;
    EXPECT_NEAR(sxx / sum, sigma * sigma, 1e-4 * sigma * sigma) << sigma;
    EXPECT_NEAR(syy / sum, sigma * sigma, 1e-4 * sigma * sigma) << sigma;
    EXPECT_NEAR(sxy / sum, 0.0, 1e-6) << sigma;
    // Separable: the corner share is the product of the axis shares.
    const std::vector<double> k = CrosstalkKernel(sigma, CrosstalkShape::kLatticeWalk);
    const cv::Point at = cv::Point(601, 501) - w.rect.tl();
    EXPECT_NEAR(w.electrons(at) / 1000.0, k[1] * k[1], 1e-6) << sigma;
  }
  // At the sensor's edge the charge that diffuses off it is lost, and the window stays on it.
  const SignalWindow edge =
      DiffuseCharge(Point(0, 0, 1000.0), 1.0, CrosstalkShape::kLatticeWalk, sensor);
  EXPECT_EQ(edge.rect & sensor, edge.rect);
  EXPECT_LT(cv::sum(edge.electrons)[0], 1000.0 * 0.75);
  EXPECT_EQ(CrosstalkKernel(0.0, CrosstalkShape::kLatticeWalk), std::vector<double>{1.0});
  EXPECT_EQ(CrosstalkKernel(0.0, CrosstalkShape::kSampledGaussian), std::vector<double>{1.0});
}

// The sampled Gaussian (a crosstalk outside the lattice walk's family, for the estimator's tests):
// e^(-n^2 / 2 sigma^2) on the pixels, cut at 4 sd, its light kept; at sigma 1 its centre weight is
// 1 / sqrt(2 pi), the walk's e^-1 I_0(1) = 0.466.
TEST(Sensor, SampledGaussianCrosstalkIsTheGaussianOnThePixels) {
  for (double sigma : {0.6, 1.0, 1.7}) {
    const std::vector<double> k = CrosstalkKernel(sigma, CrosstalkShape::kSampledGaussian);
    ASSERT_EQ(static_cast<int>(k.size()), static_cast<int>(std::floor(4.0 * sigma)) + 1) << sigma;
    double sum = k[0], var = 0.0;
    for (std::size_t n = 1; n < k.size(); ++n) {
      sum += 2.0 * k[n];
      var += 2.0 * k[n] * static_cast<double>(n * n);
      EXPECT_NEAR(k[n] / k[0], std::exp(-0.5 * n * n / (sigma * sigma)), 1e-12) << sigma;
    }
    EXPECT_NEAR(sum, 1.0, 1e-12) << sigma;
    // From 1 px on, sigma^2 within the cut's 0.2%; at 0.6 px the grid's sampling takes 2% off.
    if (sigma >= 1.0) {
      EXPECT_NEAR(var, sigma * sigma, 2e-3 * sigma * sigma) << sigma;
    }
  }
  EXPECT_NEAR(CrosstalkKernel(1.0, CrosstalkShape::kSampledGaussian)[0], 0.398942, 2e-5);
  EXPECT_NEAR(CrosstalkKernel(1.0, CrosstalkShape::kLatticeWalk)[0], 0.465760, 2e-5);
  const SignalWindow spread = DiffuseCharge(Point(640, 512, 1000.0), 1.0,
                                            CrosstalkShape::kSampledGaussian,
                                            cv::Rect(0, 0, 1280, 1024));
  EXPECT_NEAR(spread.electrons(cv::Point(640, 512) - spread.rect.tl()) / 1000.0,
              0.398942 * 0.398942, 1e-4);
}

// Exposed through the sensor, crosstalk moves the mean and keeps the counts Poisson: a lit pixel
// loses its neighbours' share and the frames' temporal variance still follows K x mean.
TEST(Sensor, CrosstalkActsOnTheCountedChargeBeforeTheNoise) {
  SensorOptions o;
  o.crosstalk_sigma_px = 0.6;
  o.dark_current_e_per_s = 0.0;
  const Sensor sensor(o);
  const SignalWindow point = Point(640, 512, 8000.0);
  const std::vector<double> k = CrosstalkKernel(0.6, CrosstalkShape::kLatticeWalk);
  const double k_gain = o.system_gain_dn_per_e;
  double centre = 0, neighbour = 0, centre2 = 0;
  const int frames = 400;
  for (int f = 0; f < frames; ++f) {
    const cv::Mat img = sensor.Expose(point, 0.01, 1000 + f, PixelFormat::kMono12);
    const double c = img.at<std::uint16_t>(512, 640) - o.black_level_dn;
    centre += c, centre2 += c * c;
    neighbour += img.at<std::uint16_t>(512, 641) - o.black_level_dn;
  }
  centre /= frames, neighbour /= frames;
  const double var = centre2 / frames - centre * centre;
  EXPECT_NEAR(centre / k_gain, 8000.0 * k[0] * k[0], 0.01 * 8000.0 * k[0] * k[0]);
  EXPECT_NEAR(neighbour / k_gain, 8000.0 * k[0] * k[1], 0.03 * 8000.0 * k[0] * k[1]);
  // Poisson after diffusion: var = K^2 (mean electrons + read^2) + 1/12, within sampling (~7%).
  const double expected = k_gain * centre + k_gain * k_gain * o.read_noise_e * o.read_noise_e + 1.0 / 12;
  EXPECT_NEAR(var, expected, 0.2 * expected);
}

// The camera's LUT / gamma fault: FS (v / FS)^gamma on every pixel, nothing at gamma 1.
TEST(Sensor, ResponseCurveBendsTheGrayLevels) {
  cv::Mat image(1, 3, CV_16UC1);
  image.at<std::uint16_t>(0, 0) = 0;
  image.at<std::uint16_t>(0, 1) = 1024;
  image.at<std::uint16_t>(0, 2) = 4095;
  cv::Mat same = image.clone();
  ApplyResponseCurve(1.0, PixelFormat::kMono12, same);
  EXPECT_EQ(cv::countNonZero(same != image), 0);
  ApplyResponseCurve(0.45, PixelFormat::kMono12, image);
  EXPECT_EQ(image.at<std::uint16_t>(0, 0), 0);
  EXPECT_EQ(image.at<std::uint16_t>(0, 1), std::lround(4095 * std::pow(1024.0 / 4095, 0.45)));
  EXPECT_EQ(image.at<std::uint16_t>(0, 2), 4095);
  cv::Mat mono8(1, 1, CV_8UC1, cv::Scalar(64));
  ApplyResponseCurve(0.5, PixelFormat::kMono8, mono8);
  EXPECT_EQ(mono8.at<std::uint8_t>(0, 0), std::lround(255 * std::sqrt(64.0 / 255)));
}

}  // namespace
}  // namespace irdist::sim
