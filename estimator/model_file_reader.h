#pragma once
// The model file's strict reader (estimator/model_file.cc, and the parts of model.yaml read in
// files of their own: estimator/defect_map_file.cc). Estimator-internal: yaml-cpp shows here, so
// only .cc files include it.

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "estimator/fit.h"
#include "estimator/model_file_error.h"

namespace irdist::model_file {

// Reads with the key path and line in every error.
class Reader {
 public:
  explicit Reader(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void Fail(const YAML::Node& node, const std::string& key,
                         const std::string& problem) const {
    const int line = node.IsDefined() && node.Mark().line >= 0 ? node.Mark().line + 1 : 0;
    throw ModelFileError(path_, key, line, problem);
  }

  YAML::Node Child(const YAML::Node& parent, const std::string& parent_key,
                   const std::string& name) const {
    const std::string key = parent_key.empty() ? name : parent_key + "." + name;
    if (!parent.IsMap()) Fail(parent, parent_key, "expected a map");
    YAML::Node child = parent[name];
    if (!child.IsDefined() || child.IsNull()) Fail(parent, key, "missing");
    return child;
  }

  template <typename T>
  T Scalar(const YAML::Node& parent, const std::string& parent_key, const std::string& name) const {
    const YAML::Node node = Child(parent, parent_key, name);
    const std::string key = parent_key.empty() ? name : parent_key + "." + name;
    if (!node.IsScalar()) Fail(node, key, "expected a scalar");
    T value{};
    try {
      value = node.as<T>();
    } catch (const YAML::Exception&) {
      Fail(node, key, "cannot read '" + node.Scalar() + "' as a number");
    }
    if constexpr (std::is_floating_point_v<T>) {
      if (!std::isfinite(value)) Fail(node, key, "'" + node.Scalar() + "' is not a finite number");
    }
    return value;
  }

  // A fit statistic: finite, or .inf / .nan where the fit could not say (a singular fit's
  // condition number); it only describes the fit, no estimate uses it.
  double Statistic(const YAML::Node& parent, const std::string& parent_key,
                   const std::string& name) const {
    const YAML::Node node = Child(parent, parent_key, name);
    try {
      return node.as<double>();
    } catch (const YAML::Exception&) {
      Fail(node, parent_key + "." + name, "cannot read '" + node.Scalar() + "' as a number");
    }
  }

  // Every key of the map `node` is in `allowed` (a misspelt key is an error, not a default).
  void Keys(const YAML::Node& node, const std::string& key,
            const std::vector<std::string>& allowed) const {
    if (!node.IsMap()) Fail(node, key, "expected a map");
    for (const auto& entry : node) {
      const std::string name = entry.first.Scalar();
      if (std::find(allowed.begin(), allowed.end(), name) == allowed.end()) {
        std::string valid;
        for (const std::string& a : allowed) valid += (valid.empty() ? "" : ", ") + a;
        Fail(entry.first, key.empty() ? name : key + "." + name,
             "unknown key; valid keys here: " + valid);
      }
    }
  }

  std::vector<double> Doubles(const YAML::Node& parent, const std::string& parent_key,
                              const std::string& name, bool allow_empty) const {
    const std::string key = parent_key.empty() ? name : parent_key + "." + name;
    YAML::Node node = parent[name];
    if (allow_empty && (!node.IsDefined() || node.IsNull())) return {};
    node = Child(parent, parent_key, name);
    if (!node.IsSequence()) Fail(node, key, "expected a sequence of numbers");
    std::vector<double> out;
    for (size_t i = 0; i < node.size(); ++i) {
      double value = 0.0;
      try {
        value = node[i].as<double>();
      } catch (const YAML::Exception&) {
        Fail(node[i], key + "[" + std::to_string(i) + "]", "not a number");
      }
      if (!std::isfinite(value))
        Fail(node[i], key + "[" + std::to_string(i) + "]", "not a finite number");
      out.push_back(value);
    }
    return out;
  }

  void Range(const YAML::Node& parent, const std::string& parent_key, const std::string& name,
             double* lo, double* hi) const {
    const std::vector<double> v = Doubles(parent, parent_key, name, false);
    if (v.size() != 2 || !(v[0] <= v[1]))
      Fail(parent[name], parent_key + "." + name, "expected [min, max] with min <= max");
    *lo = v[0];
    *hi = v[1];
  }

  FitSummary Fit(const YAML::Node& parent, const std::string& parent_key) const {
    const std::string key = parent_key + ".fit";
    const YAML::Node node = Child(parent, parent_key, "fit");
    Keys(node, key, {"termination", "message", "mean_relative_error", "max_relative_error",
                     "condition_number", "samples", "iterations", "gauge_index"});
    FitSummary s;
    const std::string termination = Scalar<std::string>(node, key, "termination");
    bool known = false;
    for (auto t : {FitSummary::Termination::kConverged, FitSummary::Termination::kNoConvergence,
                   FitSummary::Termination::kFailed, FitSummary::Termination::kDegenerate,
                   FitSummary::Termination::kIllConditioned}) {
      if (termination == ToString(t)) {
        s.termination = t;
        known = true;
      }
    }
    if (!known) Fail(node["termination"], key + ".termination", "unknown termination");
    s.message = node["message"] && !node["message"].IsNull()
                    ? Scalar<std::string>(node, key, "message")
                    : std::string();
    s.mean_relative_error = Statistic(node, key, "mean_relative_error");
    s.max_relative_error = Statistic(node, key, "max_relative_error");
    s.condition_number = Statistic(node, key, "condition_number");
    s.samples = Scalar<int>(node, key, "samples");
    s.iterations = Scalar<int>(node, key, "iterations");
    s.gauge_index = Scalar<int>(node, key, "gauge_index");
    return s;
  }

 private:
  std::string path_;
};

}  // namespace irdist::model_file
