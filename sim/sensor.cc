#include "sim/sensor.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <boost/math/special_functions/bessel.hpp>
#include <opencv2/imgproc.hpp>

namespace irdist::sim {
namespace {

constexpr int kTableBits = 14;
constexpr int kTableSize = 1 << kTableBits;

std::uint64_t SplitMix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

std::uint64_t FrameSeed(std::uint64_t seed, std::uint64_t frame_index, std::uint64_t stream) {
  std::uint64_t state = seed * 0x100000001B3ull ^ (frame_index + 0x51ED270B27ull * stream);
  SplitMix64(state);
  return SplitMix64(state);
}

// SplitMix64 as a standard random bit generator: cheap to seed, one per defect pixel and frame.
struct SplitMixEngine {
  using result_type = std::uint64_t;
  std::uint64_t state;
  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return ~0ull; }
  result_type operator()() { return SplitMix64(state); }
};

template <typename T>
void FillFromTable(cv::Mat& out, const std::vector<std::uint16_t>& table, std::uint64_t state) {
  for (int row = 0; row < out.rows; ++row) {
    T* dst = out.ptr<T>(row);
    int col = 0;
    while (col < out.cols) {
      std::uint64_t bits = SplitMix64(state);
      for (int k = 0; k < 4 && col < out.cols; ++k, ++col) {  // 4 x 14 of the 64 bits
        dst[col] = static_cast<T>(table[bits & (kTableSize - 1)]);
        bits >>= kTableBits;
      }
    }
  }
}

}  // namespace

std::vector<double> CrosstalkKernel(double sigma_px, CrosstalkShape shape) {
  IRDIST_CHECK(std::isfinite(sigma_px) && sigma_px >= 0.0, "crosstalk sigma must be >= 0");
  if (sigma_px == 0.0) return {1.0};
  const double t = sigma_px * sigma_px;
  std::vector<double> w;
  if (shape == CrosstalkShape::kSampledGaussian) {
    for (int n = 0; n <= 4.0 * sigma_px; ++n) w.push_back(std::exp(-0.5 * n * n / t));
  } else {
    for (int n = 0;; ++n) {
      // e^-t I_n(t): the lattice random walk's share n pixels away (exponentially scaled Bessel).
      const double share = std::exp(-t) * boost::math::cyl_bessel_i(n, t);
      if (n > 0 && share < 1e-9) break;
      w.push_back(share);
    }
  }
  double sum = w[0];
  for (size_t n = 1; n < w.size(); ++n) sum += 2.0 * w[n];
  for (double& share : w) share /= sum;
  return w;
}

SignalWindow DiffuseCharge(const SignalWindow& electrons, double sigma_px, CrosstalkShape shape,
                           const cv::Rect& sensor) {
  if (sigma_px == 0.0 || electrons.rect.empty()) return electrons;
  const std::vector<double> half = CrosstalkKernel(sigma_px, shape);
  const int reach = static_cast<int>(half.size()) - 1;
  cv::Mat1d kernel(2 * reach + 1, 1);
  for (int n = -reach; n <= reach; ++n) kernel(n + reach) = half[std::abs(n)];
  // The window with room for the charge to spread, zero outside the original one.
  const cv::Rect grown(electrons.rect.x - reach, electrons.rect.y - reach,
                       electrons.rect.width + 2 * reach, electrons.rect.height + 2 * reach);
  cv::Mat1f padded = cv::Mat1f::zeros(grown.height, grown.width);
  electrons.electrons.copyTo(padded(electrons.rect - grown.tl()));
  cv::Mat1f spread;
  cv::sepFilter2D(padded, spread, CV_32F, kernel, kernel, cv::Point(-1, -1), 0.0,
                  cv::BORDER_CONSTANT);
  SignalWindow out;
  out.rect = grown & sensor;
  out.electrons = spread(out.rect - grown.tl()).clone();
  return out;
}

SignalWindow DiffuseCharge(const SignalWindow& electrons, const SensorOptions& sensor) {
  return DiffuseCharge(electrons, sensor.crosstalk_sigma_px, sensor.crosstalk_shape,
                       cv::Rect(0, 0, sensor.width_px, sensor.height_px));
}

int FormatBits(PixelFormat format) {
  switch (format) {
    case PixelFormat::kMono8:
      return 8;
    case PixelFormat::kMono12:
      return 12;
    case PixelFormat::kMono16:
      return 16;
  }
  return 16;
}

int FormatCvType(PixelFormat format) {
  return format == PixelFormat::kMono8 ? CV_8UC1 : CV_16UC1;
}

Sensor::Sensor(const SensorOptions& options)
    : Sensor(options, 0.5 * options.width_px, 0.5 * options.height_px) {}

Sensor::Sensor(const SensorOptions& options, double near_x_px, double near_y_px)
    : options_(options) {
  std::string why;
  IRDIST_CHECK(options_.IsValid(&why), why);
  DrawFixedPattern();
  if (options_.defects.Count() > 0) {
    defects_ = PlaceDefectPixels(options_.defects, options_.width_px, options_.height_px,
                                 near_x_px, near_y_px);
  }
}

void Sensor::DrawFixedPattern() {
  const SensorOptions& s = options_;
  // Stream 4 of frame "index" ~0: independent of every frame's temporal noise.
  std::mt19937_64 rng(FrameSeed(s.seed, ~0ull, 4));
  std::normal_distribution<float> unit(0.0f, 1.0f);
  if (s.prnu_percent > 0.0) {
    gain_.create(s.height_px, s.width_px);
    const float sd = static_cast<float>(s.prnu_percent / 100.0);
    for (auto& g : gain_) g = std::max(0.0f, 1.0f + sd * unit(rng));
  }
  if (s.dsnu_e > 0.0) {
    offset_e_.create(s.height_px, s.width_px);
    const float sd = static_cast<float>(s.dsnu_e);
    for (auto& o : offset_e_) o = sd * unit(rng);
  }
}

double Sensor::PixelGain(int x, int y) const {
  return gain_.empty() ? 1.0 : static_cast<double>(gain_(y, x));
}

double Sensor::PixelDarkOffsetE(int x, int y) const {
  return offset_e_.empty() ? 0.0 : static_cast<double>(offset_e_(y, x));
}

void Sensor::FillWithDarkOffsets(double dark_e, std::uint64_t frame_index, PixelFormat format,
                                 cv::Point roi_origin, double black_dn, cv::Mat& out) const {
  const SensorOptions& s = options_;
  std::mt19937_64 table_rng(FrameSeed(s.seed, frame_index, 1));
  std::vector<float> dark(kTableSize), read(kTableSize);
  std::poisson_distribution<long> dark_draw(dark_e > 0.0 ? dark_e : 1.0);
  std::normal_distribution<double> read_draw(0.0, s.read_noise_e);
  for (int k = 0; k < kTableSize; ++k) {
    dark[k] = dark_e > 0.0 ? static_cast<float>(dark_draw(table_rng)) : 0.0f;
    read[k] = static_cast<float>(read_draw(table_rng));
  }
  std::uint64_t state = FrameSeed(s.seed, frame_index, 2);
  for (int row = 0; row < out.rows; ++row) {
    const float* offset = offset_e_[row + roi_origin.y] + roi_origin.x;
    for (int col = 0; col < out.cols; ++col) {
      const std::uint64_t k = SplitMix64(state) & (kTableSize - 1);
      const std::uint16_t value = Pack(ToAdc(dark[k], read[k] + offset[col], black_dn), format);
      if (out.depth() == CV_8U) {
        out.at<std::uint8_t>(row, col) = static_cast<std::uint8_t>(value);
      } else {
        out.at<std::uint16_t>(row, col) = value;
      }
    }
  }
}

std::uint16_t Sensor::Pack(int adc, PixelFormat format) const {
  const int shift = FormatBits(format) - options_.adc_bits;
  return static_cast<std::uint16_t>(shift >= 0 ? adc << shift : adc >> -shift);
}

double Sensor::MeanAdc(double signal_electrons, double exposure_s, double black_offset_dn) const {
  const SensorOptions& s = options_;
  const double electrons =
      std::min(s.full_well_e, signal_electrons +
                                  (s.dark_current_e_per_s + s.background_e_per_s) * exposure_s);
  const double max = s.AdcMax();
  double x = s.system_gain_dn_per_e * electrons + s.black_level_dn + black_offset_dn;
  x -= s.nonlinearity * x * x / max;
  return std::clamp(x, 0.0, max);
}

int Sensor::ToAdc(double electrons, double read_noise_e, double black_dn) const {
  const SensorOptions& s = options_;
  electrons = std::min(electrons, s.full_well_e);
  const double max = s.AdcMax();
  double x = s.system_gain_dn_per_e * (electrons + read_noise_e) + black_dn;
  x -= s.nonlinearity * x * x / max;
  return static_cast<int>(std::clamp(std::floor(x + 0.5), 0.0, max));
}

void Sensor::Expose(const SignalWindow& signal, double exposure_s, std::uint64_t frame_index,
                    PixelFormat format, cv::Point roi_origin, cv::Mat& out,
                    double black_offset_dn) const {
  IRDIST_CHECK(out.type() == FormatCvType(format), "output image type does not match format");
  IRDIST_CHECK(exposure_s >= 0.0);
  const SensorOptions& s = options_;
  const double black_dn = s.black_level_dn + black_offset_dn;
  const double dark_e = (s.dark_current_e_per_s + s.background_e_per_s) * exposure_s;

  const cv::Rect roi(roi_origin, out.size());
  if (!gain_.empty() || !offset_e_.empty()) {  // the maps cover the sensor only
    IRDIST_CHECK((roi & cv::Rect(0, 0, s.width_px, s.height_px)) == roi,
                 "region outside the sensor");
  }
  if (!offset_e_.empty()) {
    FillWithDarkOffsets(dark_e, frame_index, format, roi_origin, black_dn, out);
  } else {
    FillBackground(dark_e, frame_index, format, black_dn, out);
  }
  const SignalWindow collected = CollectedCharge(signal);
  const cv::Rect window = collected.rect & roi;
  if (!window.empty()) {
    ExposeWindow(collected, window, dark_e, frame_index, format, roi, black_dn, out);
  }
  ExposeDefects(collected, exposure_s, dark_e, frame_index, format, roi, black_dn, out);
}

void Sensor::ExposeDefects(const SignalWindow& collected, double exposure_s, double dark_e,
                           std::uint64_t frame_index, PixelFormat format, cv::Rect roi,
                           double black_dn, cv::Mat& out) const {
  const SensorOptions& s = options_;
  for (size_t k = 0; k < defects_.size(); ++k) {
    const DefectPixel& d = defects_[k];
    if (!roi.contains(cv::Point(d.x_px, d.y_px))) continue;
    std::uint16_t value = 0;
    if (d.kind == DefectPixel::Kind::kStuck) {
      value = Pack(static_cast<int>(std::clamp(d.value, 0.0, static_cast<double>(s.AdcMax()))),
                   format);
    } else {
      // What the pixel collects (light, dark) plus its own dark charge, from its own stream.
      double mean = dark_e + d.value * exposure_s;
      if (collected.rect.contains(cv::Point(d.x_px, d.y_px))) {
        mean += collected.electrons(d.y_px - collected.rect.y, d.x_px - collected.rect.x);
      }
      SplitMixEngine rng{FrameSeed(s.seed ^ (0xDEFEC7ull * (k + 1)), frame_index, 5)};
      double electrons = 0.0;
      if (mean > 1e7) {
        electrons = std::normal_distribution<double>(mean, std::sqrt(mean))(rng);
      } else if (mean > 0.0) {
        electrons = static_cast<double>(std::poisson_distribution<long>(mean)(rng));
      }
      const double read_e = std::normal_distribution<double>(0.0, s.read_noise_e)(rng) +
                            PixelDarkOffsetE(d.x_px, d.y_px);
      value = Pack(ToAdc(electrons, read_e, black_dn), format);
    }
    if (out.depth() == CV_8U) {
      out.at<std::uint8_t>(d.y_px - roi.y, d.x_px - roi.x) = static_cast<std::uint8_t>(value);
    } else {
      out.at<std::uint16_t>(d.y_px - roi.y, d.x_px - roi.x) = value;
    }
  }
}

SignalWindow Sensor::CollectedCharge(const SignalWindow& signal) const {
  const SensorOptions& s = options_;
  SignalWindow photo = signal;
  if (!gain_.empty() && !signal.rect.empty()) {  // PRNU: where the photon is absorbed
    cv::Mat1f gained;  // a new buffer: `signal` (whose data photo shares) stays as it is
    cv::multiply(signal.electrons, gain_(signal.rect), gained);
    photo.electrons = gained;
  }
  return DiffuseCharge(photo, s);
}

void Sensor::FillBackground(double dark_e, std::uint64_t frame_index, PixelFormat format,
                            double black_dn, cv::Mat& out) const {
  const SensorOptions& s = options_;
  // The background's distribution, as 16384 exact draws for this frame.
  std::mt19937_64 table_rng(FrameSeed(s.seed, frame_index, 1));
  std::vector<std::uint16_t> table(kTableSize);
  {
    std::poisson_distribution<long> dark(dark_e > 0.0 ? dark_e : 1.0);
    std::normal_distribution<double> read(0.0, s.read_noise_e);
    for (auto& value : table) {
      const double electrons = dark_e > 0.0 ? static_cast<double>(dark(table_rng)) : 0.0;
      value = Pack(ToAdc(electrons, read(table_rng), black_dn), format);
    }
  }

  const std::uint64_t fill_state = FrameSeed(s.seed, frame_index, 2);
  if (out.depth() == CV_8U) {
    FillFromTable<std::uint8_t>(out, table, fill_state);
  } else {
    FillFromTable<std::uint16_t>(out, table, fill_state);
  }
}

void Sensor::ExposeWindow(const SignalWindow& signal, cv::Rect window, double dark_e,
                          std::uint64_t frame_index, PixelFormat format, cv::Rect roi,
                          double black_dn, cv::Mat& out) const {
  const SensorOptions& s = options_;
  // Exact draws inside the emitter's window (`signal`: the collected charge, PRNU and crosstalk
  // applied), each pixel with its own DSNU offset.
  std::mt19937_64 rng(FrameSeed(s.seed, frame_index, 3));
  std::normal_distribution<double> read(0.0, s.read_noise_e);
  for (int row = window.y; row < window.y + window.height; ++row) {
    const float* src = signal.electrons[row - signal.rect.y];
    for (int col = window.x; col < window.x + window.width; ++col) {
      const double mean = src[col - signal.rect.x] + dark_e;
      double electrons = 0.0;
      if (mean > 1e7) {
        electrons = std::normal_distribution<double>(mean, std::sqrt(mean))(rng);
      } else if (mean > 0.0) {
        electrons = static_cast<double>(std::poisson_distribution<long>(mean)(rng));
      }
      const double read_e = read(rng) + PixelDarkOffsetE(col, row);
      const std::uint16_t value = Pack(ToAdc(electrons, read_e, black_dn), format);
      if (out.depth() == CV_8U) {
        out.at<std::uint8_t>(row - roi.y, col - roi.x) = static_cast<std::uint8_t>(value);
      } else {
        out.at<std::uint16_t>(row - roi.y, col - roi.x) = value;
      }
    }
  }
}

cv::Mat Sensor::Expose(const SignalWindow& signal, double exposure_s, std::uint64_t frame_index,
                       PixelFormat format) const {
  cv::Mat out(options_.height_px, options_.width_px, FormatCvType(format));
  Expose(signal, exposure_s, frame_index, format, cv::Point(0, 0), out);
  return out;
}

void ApplyResponseCurve(double gamma, PixelFormat format, cv::Mat& image) {
  if (gamma == 1.0 || image.empty()) return;
  const int full_scale = (1 << FormatBits(format)) - 1;
  std::vector<std::uint16_t> table(static_cast<std::size_t>(full_scale) + 1);
  for (int v = 0; v <= full_scale; ++v) {
    table[static_cast<std::size_t>(v)] = static_cast<std::uint16_t>(
        std::lround(full_scale * std::pow(static_cast<double>(v) / full_scale, gamma)));
  }
  if (image.depth() == CV_8U) {
    image.forEach<std::uint8_t>([&table](std::uint8_t& v, const int*) {
      v = static_cast<std::uint8_t>(table[v]);
    });
  } else {
    image.forEach<std::uint16_t>([&table, full_scale](std::uint16_t& v, const int*) {
      v = table[std::min<int>(v, full_scale)];
    });
  }
}

}  // namespace irdist::sim
