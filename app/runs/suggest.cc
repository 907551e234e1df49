#include "app/runs/suggest.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "station/plan.h"

namespace irdist {
namespace {

// Straight line peak = offset + slope * t through one end's probes (least squares).
struct Line {
  double offset = 0.0;  // fraction of full scale at t = 0 (background and offset)
  double slope = 0.0;   // fraction of full scale per ms
  double bias_ma = 0.0;
};

Line FitEnd(const std::vector<ProbeFrame>& probes, bool nearest) {
  double n = 0, st = 0, sp = 0, stt = 0, stp = 0, bias = 0;
  double t_min = 1e300, t_max = -1e300;
  for (const ProbeFrame& p : probes) {
    if (p.nearest != nearest) continue;
    const double signal = p.peak - p.background;
    n += 1;
    st += p.exposure_ms;
    sp += signal;
    stt += p.exposure_ms * p.exposure_ms;
    stp += p.exposure_ms * signal;
    bias += p.bias_ma;
    t_min = std::min(t_min, p.exposure_ms);
    t_max = std::max(t_max, p.exposure_ms);
  }
  IRDIST_CHECK(n >= 2 && t_max > t_min, "the ", nearest ? "nearest" : "farthest",
               " end needs probes at two or more exposures");
  Line line;
  line.slope = (n * stp - st * sp) / (n * stt - st * st);
  line.offset = (sp - line.slope * st) / n;
  line.bias_ma = bias / n;
  return line;
}

double Background(const std::vector<ProbeFrame>& probes, bool nearest) {
  double sum = 0.0;
  int n = 0;
  for (const ProbeFrame& p : probes) {
    if (p.nearest == nearest) {
      sum += p.background;
      ++n;
    }
  }
  return n ? sum / n : 0.0;
}

}  // namespace

bool SuggestOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (!(max_peak_fraction > 0.0 && max_peak_fraction < 1.0)) {
    return fail("max_peak_fraction must lie in (0, 1)");
  }
  if (!(min_signal_fraction > 0.0 && min_signal_fraction < max_peak_fraction)) {
    return fail("min_signal_fraction must lie in (0, max_peak_fraction)");
  }
  if (!(min_t_ref_ms > 0.0)) return fail("min_t_ref_ms must be positive");
  if (!(t_step_ms > 0.0)) return fail("t_step_ms must be positive");
  if (t_meas_count < 1) return fail("t_meas_count must be at least 1");
  if (best_dt_ms && !(*best_dt_ms > 0.0 && *best_dt_ms <= kMaxExposureMs)) {
    return fail("best_dt_ms must lie in (0, 100000] ms");
  }
  return true;
}

Suggestion SuggestExposures(const std::vector<ProbeFrame>& probes, const SuggestOptions& options) {
  std::string why;
  IRDIST_CHECK(options.IsValid(&why), why);
  const Line near = FitEnd(probes, true);
  const Line far = FitEnd(probes, false);
  IRDIST_CHECK(near.slope > 0.0 && far.slope > 0.0,
               "probe peaks do not grow with exposure: is the IRED on and in view?");
  const double near_bg = Background(probes, true);

  Suggestion s;
  s.bias_ma = near.bias_ma;
  // Longest measurement exposure: the brightest pixel stays below max_peak_fraction.
  const double t_longest_max = (options.max_peak_fraction - near_bg - near.offset) / near.slope;
  // Shortest reference exposure: the faintest blob still rises min_signal_fraction above background.
  const double t_ref_min =
      std::max(options.min_t_ref_ms, (options.min_signal_fraction - far.offset) / far.slope);
  s.t_ref_ms = std::ceil(t_ref_min * 2.0) / 2.0;  // 0.5 ms grid
  const double span = options.t_step_ms * (options.t_meas_count - 1);
  double t_last = std::floor(t_longest_max * 2.0) / 2.0;
  std::ostringstream reason;
  reason << std::fixed << std::setprecision(1);
  if (options.best_dt_ms) {
    // Centre the measurement exposures on the best exposure difference of the last validation.
    const double centred_last = s.t_ref_ms + *options.best_dt_ms + span / 2.0;
    if (centred_last <= t_last) {
      t_last = centred_last;
      reason << "t_n centred on the best dt " << *options.best_dt_ms
             << " ms of the latest validation; ";
    } else {
      reason << "the best dt " << *options.best_dt_ms << " ms of the latest validation would "
             << "saturate the nearest pose, so t_n ends at the longest safe exposure; ";
    }
  } else {
    reason << "t_n end at the longest exposure that keeps the nearest pose below "
           << 100.0 * options.max_peak_fraction << "% of full scale (largest dt, best SNR); ";
  }
  const double t_first = t_last - span;
  s.feasible = t_first > s.t_ref_ms;
  if (!s.feasible) {
    reason << "infeasible: the working range spans more than the sensor's dynamic range ("
           << "longest safe exposure " << t_longest_max << " ms, shortest useful reference "
           << t_ref_min << " ms); narrow the recipe's distance or angle range, or open the aperture "
           << "and lower the current";
    s.reason = reason.str();
    return s;
  }
  for (int k = 0; k < options.t_meas_count; ++k) s.t_meas_ms.push_back(t_first + k * options.t_step_ms);
  s.nearest_peak_at_longest = near_bg + near.offset + near.slope * t_last;
  s.farthest_signal_at_ref = far.offset + far.slope * s.t_ref_ms;
  reason << "t_r is the shortest exposure giving the faintest pose "
         << 100.0 * options.min_signal_fraction << "% of full scale above background";
  s.reason = reason.str();
  return s;
}

std::string Suggestion::BriefReport() const {
  std::ostringstream out;
  out << std::fixed << std::setprecision(1);
  if (!feasible) return "no feasible exposures: " + reason;
  out << "t_ref_ms: " << t_ref_ms << "\nt_meas_ms: [";
  for (size_t i = 0; i < t_meas_ms.size(); ++i) out << (i ? ", " : "") << t_meas_ms[i];
  out << "]\nbias_ma: " << bias_ma << "\n# nearest pose peaks at " << 100.0 * nearest_peak_at_longest
      << "% of full scale at the longest t_n; farthest pose rises "
      << 100.0 * farthest_signal_at_ref << "% above background at t_r\n# " << reason << "\n";
  return out.str();
}

}  // namespace irdist
