// The fit's fitness (fitness.h): pose residuals of every predicted feature against the frames'
// own scatter inside their brackets, a chi-square per pose and overall.
#include "estimator/fitness.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

#include <boost/math/distributions/chi_squared.hpp>

#include "base/bounds.h"
#include "base/check.h"
#include "estimator/fit.h"

namespace irdist {
namespace {

constexpr int kChannels = 4;
const std::array<const char*, kChannels> kChannelNames = {"size", "minor", "dE", "dSigma"};
constexpr std::array<bool, kChannels> kDifference = {false, false, true, true};
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// A pose's variance beyond this many times its distance's median is kept out of that pool.
constexpr double kPoolOutlierRatio = 10.0;

// meas / pred - 1 (NaN when either is not a positive number).
double SizeResidual(double measured, double predicted) {
  return measured > 0.0 && predicted > 0.0 ? measured / predicted - 1.0 : kNaN;
}

// pred / meas - 1 of an I0-free model (the fit's own relative residual); NaN when not fitted.
double DifferenceResidual(const FittedModel* m, const CalibrationModel& model,
                          const CalibrationSample& s, double measured) {
  if (m == nullptr || m->degenerate || !(std::fabs(measured) > 0.0)) return kNaN;
  ModelInputs in;
  in.d_mm = s.d_mm;
  in.theta_deg = s.theta_deg;
  in.bias_ma = s.bias_ma;
  in.dt_ms = s.t_ms - s.t_ref_ms;
  in.df = s.measurement.f00 - s.reference.f00;
  return m->Predict(model.scaling, in) / measured - 1.0;
}

std::array<double, kChannels> ChannelResiduals(const CalibrationModel& model,
                                               const CalibrationSample& s) {
  std::array<double, kChannels> r = {kNaN, kNaN, kNaN, kNaN};
  const GeometricModel& g = model.geometric;
  if (g.fitted()) {
    const double cos_t = std::cos(s.theta_deg * M_PI / 180.0);
    r[0] = SizeResidual(g.FrameMajorVarPx2(s.measurement), g.MajorVarPx2(s.d_mm));  // as read
    r[1] = SizeResidual(s.measurement.moment_minor_var_px2,
                        g.alpha_px2 * 1e6 / (s.d_mm * s.d_mm) * cos_t * cos_t +
                            g.BlurVarPx2(s.d_mm));
  }
  r[2] = DifferenceResidual(model.Find(ModelKind::kFreeE), model, s,
                            s.measurement.e_rel - s.reference.e_rel);
  r[3] = DifferenceResidual(model.Find(ModelKind::kFreeSigma), model, s,
                            s.measurement.sigma - s.reference.sigma);
  return r;
}

struct ChannelStats {
  int n = 0;
  double mean = 0.0;
  double var = kNaN;  // the frames' scatter (n - 1 in the denominator), NaN for n < 2
};

struct PoseData {
  std::array<std::vector<double>, kChannels> residuals;
  std::array<ChannelStats, kChannels> stats;
};

ChannelStats StatsOf(const std::vector<double>& r) {
  ChannelStats c;
  c.n = static_cast<int>(r.size());
  if (c.n == 0) return c;
  for (double x : r) c.mean += x / c.n;
  if (c.n < 2) return c;
  double ss = 0.0;
  for (double x : r) ss += (x - c.mean) * (x - c.mean);
  c.var = ss / (c.n - 1);
  return c;
}

// The pooled scatter of one channel over `members` (indices into `data`), leaving out a pose
// beyond kPoolOutlierRatio times their median; {variance, degrees of freedom}.
std::pair<double, int> Pool(const std::vector<PoseData>& data, const std::vector<int>& members,
                            int channel) {
  std::vector<double> vars;
  for (int p : members) {
    if (std::isfinite(data[p].stats[channel].var)) vars.push_back(data[p].stats[channel].var);
  }
  if (vars.empty()) return {kNaN, 0};
  std::nth_element(vars.begin(), vars.begin() + vars.size() / 2, vars.end());
  const double median = vars[vars.size() / 2];
  double ss = 0.0;
  int dof = 0;
  for (int p : members) {
    const ChannelStats& c = data[p].stats[channel];
    if (!std::isfinite(c.var) || (median > 0.0 && c.var > kPoolOutlierRatio * median)) continue;
    ss += c.var * (c.n - 1);
    dof += c.n - 1;
  }
  return {dof > 0 ? ss / dof : kNaN, dof};
}

// Free parameters the fit spent on these channels: the geometric model's and each fitted I0-free
// model's coefficients (less its gauge) and sigma.
int FittedParameters(const CalibrationModel& model) {
  int parameters = 0;
  if (model.geometric.fitted()) parameters += model.geometric.BlurVariesWithDistance() ? 4 : 2;
  for (ModelKind kind : {ModelKind::kFreeE, ModelKind::kFreeSigma}) {
    const FittedModel* m = model.Find(kind);
    if (m == nullptr || m->degenerate) continue;
    for (double c : m->coefficients) parameters += c != 0.0 ? 1 : 0;
    parameters += 1 - (m->summary.gauge_index >= 0 ? 1 : 0);
  }
  return parameters;
}

double Quantile(int dof, double tail) {
  const boost::math::chi_squared law(dof);
  return boost::math::quantile(boost::math::complement(law, tail));
}

std::vector<PoseData> CollectPoses(const CalibrationModel& model,
                                   const std::vector<CalibrationSample>& samples, size_t poses) {
  std::vector<PoseData> data(poses);
  for (const CalibrationSample& s : samples) {
    if (s.pose < 0 || static_cast<size_t>(s.pose) >= poses) continue;
    if (!s.reference.Usable() || !s.measurement.Usable()) continue;
    const std::array<double, kChannels> r = ChannelResiduals(model, s);
    for (int c = 0; c < kChannels; ++c) {
      if (std::isfinite(r[c])) data[s.pose].residuals[c].push_back(r[c]);
    }
  }
  for (PoseData& d : data) {
    for (int c = 0; c < kChannels; ++c) d.stats[c] = StatsOf(d.residuals[c]);
  }
  return data;
}

// Each pose's pooled variance per channel: its distance's pool, or all poses' when the distance
// has fewer than 3 degrees of freedom.
std::vector<std::array<double, kChannels>> PooledVariances(const std::vector<PoseData>& data,
                                                           const std::vector<FitnessPose>& poses) {
  std::map<double, std::vector<int>> groups;
  std::vector<int> all;
  for (size_t p = 0; p < data.size(); ++p) {
    groups[poses[p].slide_mm].push_back(static_cast<int>(p));
    all.push_back(static_cast<int>(p));
  }
  std::vector<std::array<double, kChannels>> pooled(data.size());
  for (int c = 0; c < kChannels; ++c) {
    const double overall = Pool(data, all, c).first;
    for (const auto& [slide_mm, members] : groups) {
      const std::pair<double, int> group = Pool(data, members, c);
      for (int p : members) pooled[p][c] = group.second >= 3 ? group.first : overall;
    }
  }
  return pooled;
}

PoseFitness JudgePose(const PoseData& d, const std::array<double, kChannels>& pooled,
                      const FitnessOptions& options) {
  PoseFitness f;
  double worst = -1.0;
  for (int c = 0; c < kChannels; ++c) {
    const ChannelStats& s = d.stats[c];
    const double floor = kDifference[c] ? options.difference_floor : options.size_floor;
    const double noise = std::isfinite(pooled[c]) ? pooled[c] : 0.0;
    const double var = noise * (kDifference[c] ? s.n + 1.0 : 1.0) / std::max(1, s.n) + floor * floor;
    if (s.n == 0 || !(var > 0.0)) continue;
    const double term = s.mean * s.mean / var;
    f.chi2 += term;
    ++f.channels;
    if (noise > 0.0 && std::isfinite(s.var)) f.scatter_ratio = std::max(f.scatter_ratio, s.var / noise);
    if (term > worst) {
      worst = term;
      f.worst_channel = kChannelNames[c];
      f.worst_residual_percent = 100.0 * s.mean;
    }
  }
  return f;
}

void Conclude(std::vector<PoseFitness> judged, int parameters, const FitnessOptions& options,
              CalibrationFitness* out) {
  int pose_channels = 0, most_channels = 0;
  for (const PoseFitness& p : judged) {
    out->chi2 += p.chi2;
    pose_channels += p.channels;
    most_channels = std::max(most_channels, p.channels);
  }
  out->dof = pose_channels - parameters;
  if (out->dof < 1 || most_channels == 0) return;
  out->assessed = true;
  out->reduced_chi2 = std::min(out->chi2 / out->dof, bounds::kChiSquare.max);
  out->limit = Quantile(out->dof, options.tail_probability) / out->dof;
  const double pose_tail = options.tail_probability / static_cast<double>(judged.size());
  out->pose_limit = Quantile(most_channels, pose_tail);
  for (const PoseFitness& p : judged) {
    out->poses_over += p.channels > 0 && p.chi2 > Quantile(p.channels, pose_tail) ? 1 : 0;
  }
  out->passed = out->reduced_chi2 <= out->limit && out->poses_over == 0;
  std::stable_sort(judged.begin(), judged.end(),
                   [](const PoseFitness& a, const PoseFitness& b) { return a.chi2 > b.chi2; });
  judged.resize(std::min<size_t>(judged.size(), static_cast<size_t>(options.worst_poses)));
  out->worst = std::move(judged);
  if (!out->passed) out->cause = FitnessCause(*out);
}


}  // namespace

bool FitnessOptions::IsValid(std::string* why) const {
  std::string reason;
  if (!(tail_probability > 0.0 && tail_probability < 1.0)) reason = "tail_probability not in (0, 1)";
  if (!(size_floor >= 0.0 && difference_floor >= 0.0)) reason = "a floor is negative";
  if (worst_poses < 1) reason = "worst_poses < 1";
  if (why != nullptr) *why = reason;
  return reason.empty();
}

CalibrationFitness AssessFitness(const CalibrationModel& model,
                                 const std::vector<CalibrationSample>& samples,
                                 const std::vector<FitnessPose>& poses,
                                 const FitnessOptions& options) {
  std::string why;
  IRDIST_CHECK(options.IsValid(&why), "FitnessOptions: " + why);
  CalibrationFitness out;
  out.tail_probability = options.tail_probability;
  out.size_floor = options.size_floor;
  out.difference_floor = options.difference_floor;
  const std::vector<PoseData> data = CollectPoses(model, samples, poses.size());
  const std::vector<std::array<double, kChannels>> pooled = PooledVariances(data, poses);
  std::vector<PoseFitness> judged;
  for (size_t p = 0; p < data.size(); ++p) {
    PoseFitness f = JudgePose(data[p], pooled[p], options);
    f.pose = poses[p];
    f.chi2 = std::min(f.chi2, bounds::kChiSquare.max);
    f.scatter_ratio = std::min(f.scatter_ratio, bounds::kChiSquare.max);
    f.worst_residual_percent = std::clamp(f.worst_residual_percent, bounds::kResidualPercent.min,
                                          bounds::kResidualPercent.max);
    if (f.channels > 0) judged.push_back(f);
  }
  out.poses = static_cast<int>(judged.size());
  if (judged.size() < 2) return out;
  Conclude(std::move(judged), FittedParameters(model), options, &out);
  return out;
}

}  // namespace irdist
