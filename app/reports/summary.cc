#include "app/reports/summary.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <optional>
#include <string>

#include "base/safe_file.h"
#include "base/yaml_fields.h"
#include "station/plan.h"

namespace irdist {
namespace {

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
