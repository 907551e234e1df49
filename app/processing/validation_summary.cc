#include "app/processing/validation_summary.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <tuple>

#include "base/check.h"

namespace irdist {
namespace {

double Median(const std::vector<double>& v) { return Percentile(v, 50.0); }

double MaxOf(const std::vector<double>& v) {
  return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
}

ErrorFigures Figures(const std::vector<const EstimateRow*>& rows) {
  ErrorFigures f;
  std::vector<double> rel, abs_mm, th, th_ge, th_lt;
  for (const EstimateRow* r : rows) {
    if (!r->ok) {
      ++f.failed;
      continue;
    }
    ++f.count;
    const double err_mm = std::abs(r->d_mm - r->true_d_mm);
    abs_mm.push_back(err_mm);
    rel.push_back(100.0 * err_mm / r->true_d_mm);
    const double err_th = std::abs(std::abs(r->theta_deg) - std::abs(r->true_theta_deg));
    th.push_back(err_th);
    (r->true_theta_deg >= 15.0 ? th_ge : th_lt).push_back(err_th);
  }
  f.distance_rel_error_pct_median = Median(rel);
  f.distance_rel_error_pct_p95 = Percentile(rel, 95.0);
  f.distance_rel_error_pct_max = MaxOf(rel);
  f.distance_abs_error_mm_median = Median(abs_mm);
  f.distance_abs_error_mm_max = MaxOf(abs_mm);
  f.theta_abs_error_deg_median = Median(th);
  f.theta_abs_error_deg_max = MaxOf(th);
  f.theta_ge15_count = static_cast<int>(th_ge.size());
  f.theta_ge15_abs_error_deg_median = Median(th_ge);
  f.theta_ge15_abs_error_deg_max = MaxOf(th_ge);
  f.theta_lt15_count = static_cast<int>(th_lt.size());
  f.theta_lt15_abs_error_deg_median = Median(th_lt);
  f.theta_lt15_abs_error_deg_max = MaxOf(th_lt);
  return f;
}

// Poses are identified by their ground truth, rounded to the station's resolution (0.01 mm/deg).
using PoseKey = std::tuple<long, long>;
PoseKey KeyOf(const EstimateRow& r) {
  return {std::lround(r.true_d_mm * 100.0), std::lround(r.true_theta_deg * 100.0)};
}
long CurrentKey(const EstimateRow& r) { return std::lround(r.bias_ma * 10.0); }

double Mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

// The ok rows grouped by pose (ground truth) and current, in order of first appearance.
std::vector<ConditionErrors> ConditionsOf(const std::vector<const EstimateRow*>& rows) {
  std::vector<ConditionErrors> out;
  std::map<std::tuple<long, long, long>, size_t> index;
  for (const EstimateRow* r : rows) {
    if (!r->ok) continue;
    const auto key = std::tuple_cat(KeyOf(*r), std::make_tuple(CurrentKey(*r)));
    auto [it, inserted] = index.emplace(key, out.size());
    if (inserted) {
      ConditionErrors c;
      c.d_mm = r->true_d_mm;
      c.theta_deg = r->true_theta_deg;
      c.bias_ma = r->bias_ma;
      out.push_back(c);
    }
    ConditionErrors& c = out[it->second];
    c.d_error_mm.push_back(r->d_mm - r->true_d_mm);
    c.theta_error_deg.push_back(std::abs(r->theta_deg) - std::abs(r->true_theta_deg));
  }
  return out;
}

// Whether a trusted row is silently wrong: its distance off by more than max(0.3%, 4 standard
// errors) of the truth (ground truth known).
bool SilentlyWrong(const EstimateRow& r) {
  if (!r.Trusted() || !(r.true_d_mm > 0.0)) return false;
  const double error_mm = std::abs(r.d_mm - r.true_d_mm);
  const double se_mm = r.d_std_mm > 0.0 ? r.d_std_mm : 0.0;
  return error_mm > std::max(0.003 * r.true_d_mm, 4.0 * se_mm);
}

// The rows outside a range, with their health and motion assessed and flagged, their flags by
// name, the suspect rows and the silently wrong ones.
void CountFlags(const std::vector<const EstimateRow*>& rows, MethodSummary* m) {
  for (const EstimateRow* r : rows) {
    m->outside_calibrated_range += r->outside_range ? 1 : 0;
    m->health_assessed += r->health != "-" ? 1 : 0;
    m->health_flagged += r->health != "-" && r->health != "ok" ? 1 : 0;
    m->motion_assessed += r->motion != "-" ? 1 : 0;
    m->motion_flagged += r->motion == "moving" ? 1 : 0;
    for (const EstimateFlag& f : r->flags) ++m->flags[f.name];
    m->suspect += r->Trusted() ? 0 : 1;
    m->silently_wrong += SilentlyWrong(*r) ? 1 : 0;
  }
}

MethodSummary SummarizeMethod(const std::string& method, const std::vector<EstimateRow>& rows) {
  MethodSummary m;
  m.method = method;
  std::vector<const EstimateRow*> mine;
  bool has_joint = false;
  for (const EstimateRow& r : rows) {
    if (r.method != method) continue;
    mine.push_back(&r);
    has_joint = has_joint || r.dt_ms == 0.0;
  }
  std::vector<const EstimateRow*> main_rows;
  std::map<double, std::vector<const EstimateRow*>> per_dt;
  for (const EstimateRow* r : mine) {
    if (!has_joint || r->dt_ms == 0.0) main_rows.push_back(r);
    if (r->dt_ms > 0.0) per_dt[r->dt_ms].push_back(r);
  }
  m.all = Figures(main_rows);
  m.conditions = ConditionsOf(main_rows);
  CountFlags(main_rows, &m);

  std::map<PoseKey, std::map<long, std::vector<double>>> by_pose_current;
  for (const EstimateRow* r : main_rows) {
    if (r->ok) by_pose_current[KeyOf(*r)][CurrentKey(*r)].push_back(r->d_mm);
  }
  for (const auto& [pose, by_current] : by_pose_current) {
    if (by_current.size() >= 2) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (const auto& [current, ds] : by_current) {
        lo = std::min(lo, Mean(ds));
        hi = std::max(hi, Mean(ds));
      }
      const double shift = 100.0 * (hi - lo) / (static_cast<double>(std::get<0>(pose)) / 100.0);
      m.current_shift_pct = std::max(m.current_shift_pct.value_or(0.0), shift);
    }
    for (const auto& [current, ds] : by_current) {
      if (ds.size() < 2) continue;
      const double mean = Mean(ds);
      double ss = 0.0;
      for (double d : ds) ss += (d - mean) * (d - mean);
      const double sd = std::sqrt(ss / static_cast<double>(ds.size() - 1));
      m.dispersion_mm = std::max(m.dispersion_mm.value_or(0.0), sd);
    }
  }
  double best = std::numeric_limits<double>::infinity();
  for (const auto& [dt, dt_rows] : per_dt) {
    m.by_dt[dt] = Figures(dt_rows);
    const double med = m.by_dt[dt].distance_rel_error_pct_median;
    if (m.by_dt[dt].count > 0 && med < best) {
      best = med;
      m.best_dt_ms = dt;
    }
  }
  return m;
}

}  // namespace

double Percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  IRDIST_CHECK(p >= 0.0 && p <= 100.0, "percentile ", p, " outside [0, 100]");
  std::sort(values.begin(), values.end());
  const double pos = p / 100.0 * static_cast<double>(values.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, values.size() - 1);
  const double frac = pos - static_cast<double>(lo);
  return values[lo] + frac * (values[hi] - values[lo]);
}

const MethodSummary* ValidationSummary::Find(const std::string& method) const {
  for (const MethodSummary& m : methods) {
    if (m.method == method) return &m;
  }
  return nullptr;
}

ValidationSummary Summarize(const std::vector<EstimateRow>& rows) {
  ValidationSummary s;
  std::vector<std::string> order;
  for (const EstimateRow& r : rows) {
    if (std::find(order.begin(), order.end(), r.method) == order.end()) order.push_back(r.method);
  }
  for (const std::string& method : order) s.methods.push_back(SummarizeMethod(method, rows));
  return s;
}

std::string ValidationSummary::BriefReport() const {
  std::ostringstream out;
  out << std::fixed << std::setprecision(2);
  for (const MethodSummary& m : methods) {
    out << m.method << ": " << m.all.count << " estimates";
    if (m.all.failed) out << " (" << m.all.failed << " failed)";
    out << ", distance error median " << m.all.distance_rel_error_pct_median << "% p95 "
        << m.all.distance_rel_error_pct_p95 << "% max " << m.all.distance_rel_error_pct_max
        << "%, theta error (>=15 deg) median " << m.all.theta_ge15_abs_error_deg_median << " max "
        << m.all.theta_ge15_abs_error_deg_max << " deg";
    if (m.current_shift_pct) out << ", current shift " << *m.current_shift_pct << "%";
    if (m.dispersion_mm) out << ", dispersion " << *m.dispersion_mm << " mm";
    if (m.best_dt_ms) out << ", best dt " << *m.best_dt_ms << " ms";
    if (m.outside_calibrated_range) out << ", " << m.outside_calibrated_range << " outside range";
    if (m.health_flagged) out << ", " << m.health_flagged << " unhealthy (optics)";
    const auto refocused = m.flags.find("refocused");  // measured through with their own blur
    if (refocused != m.flags.end()) out << ", " << refocused->second << " of them refocused";
    if (m.motion_flagged) out << ", " << m.motion_flagged << " moving";
    if (m.suspect) out << ", " << m.suspect << " suspect";
    if (m.silently_wrong) out << ", " << m.silently_wrong << " silently wrong";
    out << "\n";
  }
  return out.str();
}

}  // namespace irdist
