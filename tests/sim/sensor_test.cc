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

}  // namespace
}  // namespace irdist::sim
