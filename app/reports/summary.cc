#include "app/reports/summary.h"

#include <fcntl.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include "base/safe_file.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "base/utc_time.h"
#include "base/yaml_fields.h"
#include "station/plan.h"

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

void EmitFigures(YAML::Emitter& out, const ErrorFigures& f) {
  out << YAML::Key << "count" << YAML::Value << f.count;
  out << YAML::Key << "failed" << YAML::Value << f.failed;
  out << YAML::Key << "distance_rel_error_pct" << YAML::Value << YAML::Flow << YAML::BeginMap
      << YAML::Key << "median" << YAML::Value << f.distance_rel_error_pct_median << YAML::Key
      << "p95" << YAML::Value << f.distance_rel_error_pct_p95 << YAML::Key << "max" << YAML::Value
      << f.distance_rel_error_pct_max << YAML::EndMap;
  out << YAML::Key << "distance_abs_error_mm" << YAML::Value << YAML::Flow << YAML::BeginMap
      << YAML::Key << "median" << YAML::Value << f.distance_abs_error_mm_median << YAML::Key
      << "max" << YAML::Value << f.distance_abs_error_mm_max << YAML::EndMap;
  out << YAML::Key << "theta_abs_error_deg" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "median" << YAML::Value << f.theta_abs_error_deg_median;
  out << YAML::Key << "max" << YAML::Value << f.theta_abs_error_deg_max;
  out << YAML::Key << "theta_ge_15" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
      << "count" << YAML::Value << f.theta_ge15_count << YAML::Key << "median" << YAML::Value
      << f.theta_ge15_abs_error_deg_median << YAML::Key << "max" << YAML::Value
      << f.theta_ge15_abs_error_deg_max << YAML::EndMap;
  out << YAML::Key << "theta_lt_15" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
      << "count" << YAML::Value << f.theta_lt15_count << YAML::Key << "median" << YAML::Value
      << f.theta_lt15_abs_error_deg_median << YAML::Key << "max" << YAML::Value
      << f.theta_lt15_abs_error_deg_max << YAML::EndMap;
  out << YAML::EndMap;
}

void EmitOptional(YAML::Emitter& out, const char* key, std::optional<double> value) {
  out << YAML::Key << key << YAML::Value;
  if (value && std::isfinite(*value))
    out << *value;
  else
    out << YAML::Null;
}

std::optional<double> Finite(double value) {
  return std::isfinite(value) ? std::optional<double>(value) : std::nullopt;
}

void EmitCrbPose(YAML::Emitter& out, const CrbPoseRatio& p) {
  out << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "d_mm" << YAML::Value << p.d_mm << YAML::Key << "theta_deg" << YAML::Value
      << p.theta_deg << YAML::Key << "bias_ma" << YAML::Value << p.bias_ma << YAML::Key
      << "repeats" << YAML::Value << p.repeats;
  out << YAML::Key << "distance_sd_mm" << YAML::Value << p.distance_sd_mm << YAML::Key
      << "distance_sd_bound_mm" << YAML::Value << p.distance_sd_bound_mm;
  EmitOptional(out, "ratio", p.distance_sd_mm / p.distance_sd_bound_mm);
  out << YAML::Key << "theta_sd_deg" << YAML::Value << p.theta_sd_deg;
  const bool theta_bounded = p.theta_sd_bound_deg > 0.0;
  EmitOptional(out, "theta_sd_bound_deg",
               theta_bounded ? std::optional<double>(p.theta_sd_bound_deg) : std::nullopt);
  EmitOptional(out, "theta_ratio",
               theta_bounded ? Finite(p.theta_sd_deg / p.theta_sd_bound_deg) : std::nullopt);
  out << YAML::EndMap;
}

// `crb:` of one method: the bound's range over the recipe's conditions, the errors in units of
// the bound, and each repeated condition's dispersion against its bound.
void EmitCrb(YAML::Emitter& out, const CrbFigures& c) {
  out << YAML::Key << "crb" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "source" << YAML::Value << c.source;
  if (c.available) {
    out << YAML::Key << "conditions" << YAML::Value << c.conditions;
    out << YAML::Key << "distance_sd_bound_mm" << YAML::Value << YAML::Flow << YAML::BeginMap
        << YAML::Key << "min" << YAML::Value << c.distance_sd_bound_mm_min << YAML::Key << "max"
        << YAML::Value << c.distance_sd_bound_mm_max << YAML::EndMap;
    EmitOptional(out, "distance_error_over_bound_rms", Finite(c.distance_error_over_bound_rms));
    out << YAML::Key << "theta_ge_15" << YAML::Value << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "count" << YAML::Value << c.theta_ge15_count;
    if (c.theta_ge15_count > 0) {
      out << YAML::Key << "theta_sd_bound_deg_min" << YAML::Value << c.theta_ge15_sd_bound_deg_min
          << YAML::Key << "theta_sd_bound_deg_max" << YAML::Value << c.theta_ge15_sd_bound_deg_max;
      EmitOptional(out, "error_rms_deg", Finite(c.theta_ge15_error_rms_deg));
      EmitOptional(out, "sd_bound_rms_deg", Finite(c.theta_ge15_sd_bound_rms_deg));
      EmitOptional(out, "error_over_bound_rms", Finite(c.theta_ge15_error_over_bound_rms));
      EmitOptional(out, "max_at_bound_deg_median", Finite(c.theta_ge15_max_at_bound_deg_median));
      EmitOptional(out, "max_at_bound_deg_p95", Finite(c.theta_ge15_max_at_bound_deg_p95));
    }
    out << YAML::EndMap;
    EmitOptional(out, "dispersion_ratio_max", c.dispersion_ratio_max);
    EmitOptional(out, "theta_dispersion_ratio_max", c.theta_dispersion_ratio_max);
    out << YAML::Key << "dispersion" << YAML::Value << YAML::BeginSeq;
    for (const CrbPoseRatio& p : c.dispersion) EmitCrbPose(out, p);
    out << YAML::EndSeq;
  }
  out << YAML::EndMap;
}

void EmitMethod(YAML::Emitter& out, const MethodSummary& m, const CrbFigures* crb) {
  out << YAML::Key << "method" << YAML::Value << m.method;
  EmitFigures(out, m.all);
  out << YAML::Key << "current_shift_pct" << YAML::Value;
  if (m.current_shift_pct)
    out << *m.current_shift_pct;
  else
    out << YAML::Null;
  out << YAML::Key << "dispersion_mm" << YAML::Value;
  if (m.dispersion_mm)
    out << *m.dispersion_mm;
  else
    out << YAML::Null;
  out << YAML::Key << "by_dt" << YAML::Value << YAML::BeginMap;
  for (const auto& [dt, f] : m.by_dt) {
    out << YAML::Key << dt << YAML::Value << YAML::BeginMap;
    EmitFigures(out, f);
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  out << YAML::Key << "best_dt_ms" << YAML::Value;
  if (m.best_dt_ms)
    out << *m.best_dt_ms;
  else
    out << YAML::Null;
  out << YAML::Key << "outside_calibrated_range" << YAML::Value << m.outside_calibrated_range;
  if (m.health_assessed > 0) {
    out << YAML::Key << "health" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
        << "assessed" << YAML::Value << m.health_assessed << YAML::Key << "flagged" << YAML::Value
        << m.health_flagged << YAML::EndMap;
  }
  if (m.motion_assessed > 0) {
    out << YAML::Key << "motion" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
        << "assessed" << YAML::Value << m.motion_assessed << YAML::Key << "moving" << YAML::Value
        << m.motion_flagged << YAML::EndMap;
  }
  out << YAML::Key << "suspect" << YAML::Value << m.suspect;
  out << YAML::Key << "silently_wrong" << YAML::Value << m.silently_wrong;
  out << YAML::Key << "flags" << YAML::Value << YAML::Flow << YAML::BeginMap;
  for (const auto& [name, count] : m.flags) out << YAML::Key << name << YAML::Value << count;
  out << YAML::EndMap;
  if (crb) EmitCrb(out, *crb);
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

std::optional<double> ReadBestDtMs(const std::string& summary_yaml_path) {
  const std::string fix =
      "; pass the summary.yaml of an irdist validation (its best_dt_ms a number of ms in (0, " +
      std::to_string(static_cast<long>(kMaxExposureMs)) + "])";
  try {
    // The one reader of input files: a FIFO or a device is refused, never waited on.
    const std::string& path = summary_yaml_path;
    const YAML::Node root = yaml_fields::Parse(yaml_fields::ReadFile(path), path);
    if (!root.IsMap()) yaml_fields::Fail(path, root.Mark(), "not a map of results");
    const YAML::Node best = root["best_dt_ms"];
    if (!best || best.IsNull()) return std::nullopt;
    const double best_dt_ms = yaml_fields::AsNumber(best, path, "best_dt_ms");
    if (!(best_dt_ms > 0.0 && best_dt_ms <= kMaxExposureMs)) {
      yaml_fields::Fail(path, best.Mark(), "best_dt_ms " + best.Scalar() + " is out of range");
    }
    return best_dt_ms;
  } catch (const InputError& e) {
    throw EstimatesFileError(e.what() + fix);
  }
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

void WriteSummaryYaml(const std::string& path, const ValidationSummary& summary,
                      const std::map<std::string, std::string>& context,
                      const std::map<std::string, CrbFigures>& crb) {
  YAML::Emitter out;
  out.SetDoublePrecision(6);
  out << YAML::BeginMap;
  for (const auto& [key, value] : context) out << YAML::Key << key << YAML::Value << value;
  const auto crb_of = [&crb](const MethodSummary& m) -> const CrbFigures* {
    const auto it = crb.find(m.method);
    return it == crb.end() ? nullptr : &it->second;
  };
  if (!summary.methods.empty()) {
    EmitMethod(out, summary.methods.front(), crb_of(summary.methods.front()));
  }
  for (size_t i = 1; i < summary.methods.size(); ++i) {
    out << YAML::Key << summary.methods[i].method << YAML::Value << YAML::BeginMap;
    EmitMethod(out, summary.methods[i], crb_of(summary.methods[i]));
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  std::string why;  // path.tmp created new (never through a planted link), then renamed
  if (!WriteFileAtomically(path, std::string(out.c_str()) + "\n", 0644, &why)) {
    throw EstimatesFileError(path + ": " + why + "; check the folder (and the disk).");
  }
}

}  // namespace irdist
