// The geometric model's blur terms in u and tilt term in model.yaml (model_file_geometric.h).
#include "estimator/model_file_geometric.h"

#include <cmath>
#include <string>

namespace irdist::model_file {
namespace {

// Format 4 keys blur_u1_px2 / blur_u2_px2 (both or neither; absent: a fixed blur) and the optional
// blur_u3_px2 beside them.
void ReadBlurTerms(const Reader& rd, const YAML::Node& g, int version, GeometricModel* geo) {
  if (!g["blur_u1_px2"].IsDefined() && !g["blur_u2_px2"].IsDefined() &&
      !g["blur_u3_px2"].IsDefined()) {
    return;
  }
  if (version < 4) {
    rd.Fail(g["blur_u1_px2"], "geometric.blur_u1_px2",
            "is new in format_version 4; this file says " + std::to_string(version));
  }
  const auto finite = [&rd, &g](const char* key) {
    const double value = rd.Scalar<double>(g, "geometric", key);
    if (!std::isfinite(value)) rd.Fail(g[key], std::string("geometric.") + key, "must be finite");
    return value;
  };
  geo->blur_u1_px2 = finite("blur_u1_px2");
  geo->blur_u2_px2 = finite("blur_u2_px2");
  // Optional: files before it have none.
  if (g["blur_u3_px2"].IsDefined()) geo->blur_u3_px2 = finite("blur_u3_px2");
}

// The optional tilt term: both keys or neither, as many values as knots, the knots increasing
// in [0, 90) deg (their values' bound: model_file_bounds.cc).
void ReadTiltTerm(const Reader& rd, const YAML::Node& g, GeometricModel* geo) {
  const bool knots = g["tilt_theta_deg"].IsDefined(), values = g["tilt_var_px2"].IsDefined();
  if (!knots && !values) return;
  geo->tilt_theta_deg = rd.Doubles(g, "geometric", "tilt_theta_deg", false);
  geo->tilt_var_px2 = rd.Doubles(g, "geometric", "tilt_var_px2", false);
  const std::vector<double>& t = geo->tilt_theta_deg;
  if (t.empty() || geo->tilt_var_px2.size() != t.size()) {
    rd.Fail(g["tilt_var_px2"], "geometric.tilt_var_px2",
            "needs one value per knot of tilt_theta_deg (" + std::to_string(t.size()) +
                "); re-run irdist fit, or delete both keys for no tilt term");
  }
  for (size_t i = 0; i < t.size(); ++i) {
    if (t[i] >= 0.0 && t[i] < 90.0 && (i == 0 || t[i] > t[i - 1])) continue;
    rd.Fail(g["tilt_theta_deg"][i], "geometric.tilt_theta_deg[" + std::to_string(i) + "]",
            "the knots are angles in [0, 90) deg, increasing; re-run irdist fit");
  }
}

}  // namespace

void EmitGeometricTerms(YAML::Emitter& out, const GeometricModel& g) {
  if (g.BlurVariesWithDistance()) {
    out << YAML::Key << "blur_u1_px2" << YAML::Value << g.blur_u1_px2;
    out << YAML::Key << "blur_u2_px2" << YAML::Value << g.blur_u2_px2;
    if (g.blur_u3_px2 != 0.0) out << YAML::Key << "blur_u3_px2" << YAML::Value << g.blur_u3_px2;
  }
  if (g.tilt_theta_deg.empty()) return;
  out << YAML::Key << "tilt_theta_deg" << YAML::Value << YAML::Flow << g.tilt_theta_deg;
  out << YAML::Key << "tilt_var_px2" << YAML::Value << YAML::Flow << g.tilt_var_px2;
}

void ReadGeometricTerms(const Reader& rd, const YAML::Node& g, int version, GeometricModel* geo) {
  ReadBlurTerms(rd, g, version, geo);
  ReadTiltTerm(rd, g, geo);
}

}  // namespace irdist::model_file
