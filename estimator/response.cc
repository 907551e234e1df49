#include "estimator/response.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <sstream>

namespace irdist {
namespace {

// Rows kept for the residual statistics; beyond this every other row is dropped (the normal
// equations always hold every sample).
constexpr size_t kMaxStoredRows = size_t{1} << 16;

// Knot index k and weight u of M: f(M) = (1 - u) f_k + u f_{k+1}.
void Interpolation(double m, int num_knots, int* k, double* u) {
  const double x = std::clamp(m, 0.0, 1.0) * (num_knots - 1);
  *k = std::min(static_cast<int>(std::floor(x)), num_knots - 2);
  *u = x - *k;
}

std::string Fmt(double value, int precision = 3) {
  std::ostringstream out;
  out.precision(precision);
  out << value;
  return out.str();
}

}  // namespace

bool ResponseOptions::IsValid(std::string* why) const {
  auto fail = [why](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (num_knots < 3 || num_knots > 257) return fail("num_knots must be in [3,257]");
  if (!(smoothness >= 0.0)) return fail("smoothness must be >= 0");
  if (!(saturation_fraction > 0.0 && saturation_fraction <= 1.0))
    return fail("saturation_fraction must be in (0,1]");
  if (!(min_signal_fraction >= 0.0 && min_signal_fraction < 1.0))
    return fail("min_signal_fraction must be in [0,1)");
  if (neighbourhood_px < 8) return fail("neighbourhood_px must be >= 8");
  if (!(min_exposure_ratio > 1.0)) return fail("min_exposure_ratio must be > 1");
  if (!(min_gray_span > 0.0 && min_gray_span <= 1.0)) return fail("min_gray_span must be in (0,1]");
  if (min_samples < 1) return fail("min_samples must be >= 1");
  if (group_size < 1 || group_size > 4096) return fail("group_size must be in [1,4096]");
  return true;
}

std::string ResponseRecovery::BriefReport() const {
  std::ostringstream out;
  out << "camera response: " << curve.m.size() << " knots from " << samples << " samples ("
      << stacks_used << " stacks, " << stacks_skipped << " skipped), gray levels "
      << Fmt(gray_min) << ".." << Fmt(gray_max) << ", exposure ratio up to "
      << Fmt(max_exposure_ratio) << "; linearity error " << Fmt(linearity_error_pct) << " %"
      << ", black level " << Fmt(black_level) << ", rms relative residual "
      << Fmt(rms_relative_residual) << ", condition number " << Fmt(condition_number);
  return out.str();
}

ResponseRecoverer::ResponseRecoverer(int bit_depth, const ResponseOptions& options)
    : bit_depth_(bit_depth), options_(options) {
  std::string why;
  IRDIST_CHECK(options_.IsValid(&why), why);
  IRDIST_CHECK(bit_depth >= 8 && bit_depth <= 16, "bit_depth must be in [8,16], got ", bit_depth);
  const int k = options_.num_knots;
  normal_ = std::vector<double>(static_cast<size_t>(k * k), 0.0);
}

namespace {

// The stack's frames in increasing exposure.
std::vector<size_t> ExposureOrder(const std::vector<double>& exposures_us) {
  std::vector<size_t> order(exposures_us.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return exposures_us[a] < exposures_us[b]; });
  return order;
}

// The instrument that groups the pixels of pair (a, b): their rate M / t in the stack's other
// frames, or, in a stack of two, the mean of the four neighbours in the longer frame b. It carries
// none of frames a's and b's own noise, so the grouped equations stay unbiased (sorting by M_a or
// M_b itself would bias f flat where the scene's gray levels cluster).
double Instrument(const std::vector<cv::Mat>& frames, const std::vector<double>& exposures_us,
                  const std::vector<size_t>& others, size_t b, int gx, int gy) {
  double z = 0.0;
  if (!others.empty()) {
    for (size_t c : others) z += frames[c].at<std::uint16_t>(gy, gx) / exposures_us[c];
    return z;
  }
  int n = 0;
  for (const cv::Point d : {cv::Point(-1, 0), cv::Point(1, 0), cv::Point(0, -1), cv::Point(0, 1)}) {
    const int nx = gx + d.x, ny = gy + d.y;
    if (nx < 0 || ny < 0 || nx >= frames[b].cols || ny >= frames[b].rows) continue;
    z += frames[b].at<std::uint16_t>(ny, nx);
    ++n;
  }
  return n > 0 ? z / n : 0.0;
}

// The region's pixels (y * width + x) in increasing instrument order for pair (a, b).
std::vector<int> InstrumentOrder(const std::vector<cv::Mat>& frames,
                                 const std::vector<double>& exposures_us, size_t a, size_t b,
                                 const cv::Rect& region) {
  std::vector<size_t> others;
  for (size_t c = 0; c < frames.size(); ++c) {
    if (c != a && c != b) others.push_back(c);
  }
  const int width = region.width, height = region.height;
  std::vector<double> instrument(static_cast<size_t>(width * height));
  std::vector<int> pixels(instrument.size());
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      instrument[static_cast<size_t>(y * width + x)] =
          Instrument(frames, exposures_us, others, b, region.x + x, region.y + y);
      pixels[static_cast<size_t>(y * width + x)] = y * width + x;
    }
  }
  std::sort(pixels.begin(), pixels.end(), [&](int p, int q) {
    return instrument[static_cast<size_t>(p)] < instrument[static_cast<size_t>(q)];
  });
  return pixels;
}

}  // namespace

std::optional<cv::Rect> ResponseRecoverer::BlobRegion(const std::vector<cv::Mat>& frames,
                                                      const std::vector<double>& exposures_us,
                                                      const FeatureOptions& features,
                                                      double* background) const {
  // The blob, in the longest exposure.
  const size_t longest =
      std::max_element(exposures_us.begin(), exposures_us.end()) - exposures_us.begin();
  FeatureOptions locate = features;
  locate.inverse_response = InverseResponse();
  locate.response_scope = ResponseScope::kERelOnly;
  locate.window_side_px = std::min({locate.window_side_px, frames.front().rows,
                                    frames.front().cols});
  const Features blob = ComputeFeatures(frames[longest], bit_depth_, locate);
  if (!blob.blob_found) return std::nullopt;
  *background = blob.background;
  const int side = options_.neighbourhood_px;
  return cv::Rect(static_cast<int>(std::lround(blob.centroid_px.x - 0.5 * (side - 1))),
                  static_cast<int>(std::lround(blob.centroid_px.y - 0.5 * (side - 1))), side,
                  side) &
         cv::Rect(0, 0, frames.front().cols, frames.front().rows);
}

std::int64_t ResponseRecoverer::AddStack(const std::vector<cv::Mat>& frames,
                                         const std::vector<double>& exposures_us,
                                         const FeatureOptions& features) {
  IRDIST_CHECK(frames.size() == exposures_us.size(), "one exposure per frame: ", frames.size(),
               " frames, ", exposures_us.size(), " exposures");
  for (size_t i = 0; i < frames.size(); ++i) {
    IRDIST_CHECK(frames[i].type() == CV_16UC1, "AddStack needs CV_16UC1 frames");
    IRDIST_CHECK(frames[i].size() == frames.front().size(), "frames of a stack differ in size");
    IRDIST_CHECK(exposures_us[i] > 0.0, "exposures must be > 0, got ", exposures_us[i]);
  }
  if (frames.size() < 2) {
    ++stacks_skipped_;
    return 0;
  }
  double background = 0.0;
  const std::optional<cv::Rect> region = BlobRegion(frames, exposures_us, features, &background);
  if (!region) {
    ++stacks_skipped_;
    return 0;
  }
  std::int64_t added = 0;
  const std::vector<size_t> order = ExposureOrder(exposures_us);
  for (size_t i = 0; i < order.size(); ++i) {
    for (size_t j = i + 1; j < order.size(); ++j) {
      const size_t a = order[i], b = order[j];
      if (!(exposures_us[b] * 1e-3 > exposures_us[a] * 1e-3 * (1.0 + 1e-6))) continue;
      ++pairs_seen_;
      added += AddPair(frames, exposures_us, a, b, *region, background);
    }
  }
  if (added > 0) {
    ++stacks_used_;
  } else {
    ++stacks_skipped_;
  }
  return added;
}

std::int64_t ResponseRecoverer::AddPair(const std::vector<cv::Mat>& frames,
                                        const std::vector<double>& exposures_us, size_t a,
                                        size_t b, const cv::Rect& region, double background) {
  const double t_a = exposures_us[a] * 1e-3, t_b = exposures_us[b] * 1e-3;
  const std::vector<int> pixels = InstrumentOrder(frames, exposures_us, a, b, region);
  const double max_gray = static_cast<double>((1 << bit_depth_) - 1);
  const int knots = options_.num_knots;
  std::vector<double> row(static_cast<size_t>(2 * knots));
  // Groups of group_size consecutive pixels in instrument order; one equation per group:
  // sum_p f(M_a,p) / t_a - f(M_b,p) / t_b = 0.
  const int g = options_.group_size;
  std::int64_t added = 0;
  for (size_t first = 0; first + static_cast<size_t>(g) <= pixels.size();
       first += static_cast<size_t>(g)) {
    std::fill(row.begin(), row.end(), 0.0);
    double sum_a = 0.0, sum_b = 0.0;
    bool saturated = false;
    for (size_t q = first; q < first + static_cast<size_t>(g); ++q) {
      const int p = pixels[q];
      const int gx = region.x + p % region.width, gy = region.y + p / region.width;
      const double m_a = frames[a].at<std::uint16_t>(gy, gx) / max_gray;
      const double m_b = frames[b].at<std::uint16_t>(gy, gx) / max_gray;
      if (std::max(m_a, m_b) >= options_.saturation_fraction) saturated = true;
      sum_a += m_a;
      sum_b += m_b;
      int k_a, k_b;
      double u_a, u_b;
      Interpolation(m_a, knots, &k_a, &u_a);
      Interpolation(m_b, knots, &k_b, &u_b);
      row[static_cast<size_t>(k_a)] += 1.0 - u_a;
      row[static_cast<size_t>(k_a + 1)] += u_a;
      row[static_cast<size_t>(knots + k_b)] += 1.0 - u_b;
      row[static_cast<size_t>(knots + k_b + 1)] += u_b;
    }
    if (saturated) {
      excluded_saturated_ += g;
    } else if (sum_a / g - background < options_.min_signal_fraction) {
      excluded_dark_ += g;
    } else {
      AddEquation(row, t_a, t_b, sum_a, sum_b);
      added += g;
    }
  }
  return added;
}

void ResponseRecoverer::AddEquation(const std::vector<double>& row, double t_a, double t_b,
                                    double sum_a, double sum_b) {
  const int knots = options_.num_knots;
  const int g = options_.group_size;
  // Weight: 1 / sqrt of the row's shot-noise-like variance, sum (M_a / t_a^2 + M_b / t_b^2).
  const double w = 1.0 / std::sqrt(sum_a / (t_a * t_a) + sum_b / (t_b * t_b));
  for (int p = 0; p < knots; ++p) {
    const double vp =
        w * (row[static_cast<size_t>(p)] / t_a - row[static_cast<size_t>(knots + p)] / t_b);
    if (vp == 0.0) continue;
    for (int q = 0; q < knots; ++q) {
      const double vq =
          w * (row[static_cast<size_t>(q)] / t_a - row[static_cast<size_t>(knots + q)] / t_b);
      normal_[static_cast<size_t>(p * knots + q)] += vp * vq;
    }
  }
  gray_min_ = std::min(gray_min_, sum_a / g);
  gray_max_ = std::max(gray_max_, sum_b / g);
  max_ratio_ = std::max(max_ratio_, t_b / t_a);
  if (groups_ % stride_ == 0) KeepRow(row, t_a, t_b);
  ++groups_;
  samples_ += g;
}

void ResponseRecoverer::KeepRow(const std::vector<double>& row, double t_a, double t_b) {
  Group kept_row;
  kept_row.t_a = static_cast<float>(t_a);
  kept_row.t_b = static_cast<float>(t_b);
  kept_row.weights.assign(row.begin(), row.end());
  rows_.push_back(std::move(kept_row));
  if (rows_.size() >= kMaxStoredRows) {
    // Keep every other row and halve the rate from now on.
    size_t kept = 0;
    for (size_t r = 0; r < rows_.size(); r += 2) rows_[kept++] = std::move(rows_[r]);
    rows_.resize(kept);
    stride_ *= 2;
  }
}

void ResponseRecoverer::CheckDetermined() const {
  const ResponseOptions& o = options_;
  if (samples_ < o.min_samples) {
    std::ostringstream why;
    why << "camera response: only " << samples_ << " sample equations (at least " << o.min_samples
        << " needed) from " << stacks_used_ << " stacks (" << stacks_skipped_
        << " skipped: fewer than two frames or no blob); " << pairs_seen_
        << " exposure pairs, samples excluded: " << excluded_saturated_ << " saturated (>= "
        << o.saturation_fraction << " of full scale), " << excluded_dark_
        << " near black (shorter exposure < " << o.min_signal_fraction
        << " of full scale above the background). Fix: ";
    if (pairs_seen_ == 0) {
      why << "record brackets with at least two different exposures per pose (t_r and t_n).";
    } else if (excluded_saturated_ > 0) {
      why << "shorten the exposures or lower the IRED current so the blob does not saturate.";
    } else {
      why << "raise the IRED current or lengthen the exposures so the blob stands above black.";
    }
    throw ResponseError(why.str());
  }
  if (max_ratio_ < o.min_exposure_ratio) {
    throw ResponseError("camera response: the largest exposure ratio of the brackets is " +
                        Fmt(max_ratio_) + ", at least " + Fmt(o.min_exposure_ratio) +
                        " is needed to see the curve's shape. Fix: widen the bracket (a shorter "
                        "t_r or a longer t_n).");
  }
  if (gray_max_ - gray_min_ < o.min_gray_span) {
    throw ResponseError("camera response: the samples span gray levels " + Fmt(gray_min_) +
                        ".." + Fmt(gray_max_) + " of full scale, at least " +
                        Fmt(o.min_gray_span) +
                        " wide is needed. Fix: a brighter IRED current or a wider bracket (longer "
                        "t_n), without saturating.");
  }
}

int ResponseRecoverer::PinnedKnot() const {
  // The scale: f at the knot with the most data (largest diagonal of the data's normal matrix) in
  // the upper half of the sampled gray levels (far from black, where f ~ 0) is held at 1 while
  // solving; holding a knot the data do not reach (f(1)) would let the homogeneous rows shrink f
  // inside the data towards 0. Then f is rescaled to f(1) = 1.
  const int k = options_.num_knots;
  const double mid = 0.5 * (gray_min_ + gray_max_);
  int pin = std::clamp(static_cast<int>(std::lround(gray_max_ * (k - 1))), 1, k - 1);
  double pin_weight = -1.0;
  for (int i = 1; i < k; ++i) {
    const double m = static_cast<double>(i) / (k - 1);
    const double weight = normal_[static_cast<size_t>(i * k + i)];
    if (m >= mid && m <= gray_max_ && weight > pin_weight) {
      pin = i;
      pin_weight = weight;
    }
  }
  return pin;
}

namespace {

// The data's normal matrix plus the second-difference penalty, scaled by its mean diagonal.
Eigen::MatrixXd SmoothedNormal(const std::vector<double>& data, int k, double smoothness) {
  Eigen::MatrixXd normal = Eigen::Map<const Eigen::MatrixXd>(data.data(), k, k);
  const double lambda = smoothness * normal.trace() / k;
  for (int r = 0; r + 2 < k; ++r) {
    const int index[3] = {r, r + 1, r + 2};
    const double value[3] = {1.0, -2.0, 1.0};
    for (int p = 0; p < 3; ++p) {
      for (int q = 0; q < 3; ++q) normal(index[p], index[q]) += lambda * value[p] * value[q];
    }
  }
  return normal;
}

// f at every knot with f(pin) = 1: the normal equations of the other knots; `condition` gets the
// square root of their eigenvalue ratio. Throws ResponseError when they are singular.
std::vector<double> SolvePinned(const Eigen::MatrixXd& normal, int pin, const std::string& grays,
                                double* condition) {
  const int k = static_cast<int>(normal.rows());
  std::vector<int> free_knots;
  for (int i = 0; i < k; ++i) {
    if (i != pin) free_knots.push_back(i);
  }
  const int n = k - 1;
  Eigen::MatrixXd n_xx(n, n);
  Eigen::VectorXd rhs(n);
  for (int r = 0; r < n; ++r) {
    rhs(r) = -normal(free_knots[static_cast<size_t>(r)], pin);
    for (int c = 0; c < n; ++c)
      n_xx(r, c) = normal(free_knots[static_cast<size_t>(r)], free_knots[static_cast<size_t>(c)]);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(n_xx);
  const double ev_min = eigen.eigenvalues().minCoeff(), ev_max = eigen.eigenvalues().maxCoeff();
  if (!(ev_min > ev_max * 1e-15)) {
    throw ResponseError("camera response: the least-squares problem is singular (gray levels " +
                        grays + "). Fix: raise smoothness or sample more gray levels (a brighter "
                        "current or a wider bracket).");
  }
  const Eigen::VectorXd x = eigen.eigenvectors() *
                            ((eigen.eigenvectors().transpose() * rhs).array() /
                             eigen.eigenvalues().array())
                                .matrix();
  std::vector<double> values(static_cast<size_t>(k), 1.0);
  for (int r = 0; r < n; ++r) values[static_cast<size_t>(free_knots[static_cast<size_t>(r)])] = x(r);
  *condition = std::sqrt(ev_max / ev_min);
  return values;
}

// The curve on evenly spaced knots, f(1) = 1. Throws ResponseError unless it rises throughout.
InverseResponse IncreasingCurve(const std::vector<double>& values) {
  if (!(values.back() > 0.0)) {
    throw ResponseError("camera response: the recovered curve does not rise towards full scale "
                        "(f(1) <= 0). Fix: sample more gray levels (a brighter current or a wider "
                        "bracket) or raise smoothness.");
  }
  const size_t k = values.size();
  InverseResponse curve;
  curve.m.resize(k);
  curve.f.resize(k);
  for (size_t i = 0; i < k; ++i) {
    curve.m[i] = static_cast<double>(i) / (k - 1);
    curve.f[i] = values[i] / values.back();
  }
  curve.f.back() = 1.0;
  curve.m.back() = 1.0;
  for (size_t i = 1; i < k; ++i) {
    if (!(curve.f[i] > curve.f[i - 1])) {
      throw ResponseError("camera response: the recovered curve is not increasing between gray "
                          "levels " + Fmt(curve.m[i - 1]) + " and " + Fmt(curve.m[i]) +
                          " (the data there are too few or too noisy). Fix: raise smoothness, use "
                          "fewer knots, or record more poses with a wider bracket.");
    }
  }
  return curve;
}

// Where f crosses 0 (f is increasing); 0 when it does not.
double BlackLevel(const InverseResponse& f) {
  for (size_t i = 1; i < f.f.size(); ++i) {
    const double f0 = f.f[i - 1], f1 = f.f[i];
    if (f0 <= 0.0 && f1 > 0.0) return f.m[i - 1] + (f.m[i] - f.m[i - 1]) * (-f0) / (f1 - f0);
  }
  return 0.0;
}

// Largest deviation from the chord over [lo, hi], % of the rise: f is piecewise linear, so it
// lies on a knot or an end.
double LinearityErrorPct(const InverseResponse& f, double lo, double hi) {
  const double f_lo = f.Apply(lo), f_hi = f.Apply(hi);
  double worst = 0.0;
  for (size_t i = 0; i < f.m.size(); ++i) {
    const double m = f.m[i];
    if (m <= lo || m >= hi) continue;
    const double chord = f_lo + (f_hi - f_lo) * (m - lo) / (hi - lo);
    worst = std::max(worst, std::abs(f.f[i] - chord));
  }
  return f_hi > f_lo ? 100.0 * worst / (f_hi - f_lo) : 0.0;
}

}  // namespace

double ResponseRecoverer::RmsRelativeResidual(const InverseResponse& curve) const {
  // Residuals relative to the mean of the two radiance estimates.
  const int k = options_.num_knots;
  double sum_sq = 0.0;
  for (const Group& g : rows_) {
    double ra = 0.0, rb = 0.0;
    for (int i = 0; i < k; ++i) {
      ra += g.weights[static_cast<size_t>(i)] * curve.f[static_cast<size_t>(i)];
      rb += g.weights[static_cast<size_t>(k + i)] * curve.f[static_cast<size_t>(i)];
    }
    ra /= g.t_a;
    rb /= g.t_b;
    const double mean = 0.5 * (ra + rb);
    if (mean > 0.0) sum_sq += ((ra - rb) / mean) * ((ra - rb) / mean);
  }
  return rows_.empty() ? 0.0 : std::sqrt(sum_sq / rows_.size());
}

ResponseRecovery ResponseRecoverer::Solve() const {
  CheckDetermined();
  const int k = options_.num_knots;
  ResponseRecovery result;
  const std::vector<double> values =
      SolvePinned(SmoothedNormal(normal_, k, options_.smoothness), PinnedKnot(),
                  Fmt(gray_min_) + ".." + Fmt(gray_max_), &result.condition_number);
  result.curve = IncreasingCurve(values);
  result.samples = samples_;
  result.stacks_used = stacks_used_;
  result.stacks_skipped = stacks_skipped_;
  result.gray_min = gray_min_;
  result.gray_max = gray_max_;
  result.max_exposure_ratio = max_ratio_;
  result.rms_relative_residual = RmsRelativeResidual(result.curve);
  result.black_level = BlackLevel(result.curve);
  result.linearity_error_pct = LinearityErrorPct(result.curve, gray_min_, gray_max_);
  return result;
}

ResponseRecovery RecoverInverseResponse(const std::vector<ExposureStack>& stacks, int bit_depth,
                                        const ResponseOptions& options) {
  ResponseRecoverer recoverer(bit_depth, options);
  for (const ExposureStack& stack : stacks) recoverer.AddStack(stack.frames, stack.exposures_us);
  return recoverer.Solve();
}

}  // namespace irdist
