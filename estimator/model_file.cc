#include "estimator/model_file.h"

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <limits>
#include <sstream>

namespace irdist {
namespace {

std::string Message(const std::string& path, const std::string& key, int line,
                    const std::string& problem) {
  std::ostringstream out;
  out << "model file " << path;
  if (line > 0) out << ":" << line;
  if (!key.empty()) out << ": key '" << key << "'";
  out << ": " << problem << ". Re-run the calibration (irdist fit) to write a valid model file.";
  return out.str();
}

void EmitDouble(YAML::Emitter& out, const char* key, double value) {
  out << YAML::Key << key << YAML::Value << value;
}

void EmitFit(YAML::Emitter& out, const FitSummary& s) {
  out << YAML::Key << "fit" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "termination" << YAML::Value << ToString(s.termination);
  out << YAML::Key << "message" << YAML::Value << s.message;
  EmitDouble(out, "mean_relative_error", s.mean_relative_error);
  EmitDouble(out, "max_relative_error", s.max_relative_error);
  EmitDouble(out, "condition_number", s.condition_number);
  out << YAML::Key << "samples" << YAML::Value << s.samples;
  out << YAML::Key << "iterations" << YAML::Value << s.iterations;
  out << YAML::Key << "gauge_index" << YAML::Value << s.gauge_index;
  out << YAML::EndMap;
}

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
    try {
      return node.as<T>();
    } catch (const YAML::Exception&) {
      Fail(node, key, "cannot read '" + node.Scalar() + "' as a number");
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
      try {
        out.push_back(node[i].as<double>());
      } catch (const YAML::Exception&) {
        Fail(node[i], key + "[" + std::to_string(i) + "]", "not a number");
      }
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
    FitSummary s;
    const std::string termination = Scalar<std::string>(node, key, "termination");
    bool known = false;
    for (auto t : {FitSummary::Termination::kConverged, FitSummary::Termination::kNoConvergence,
                   FitSummary::Termination::kFailed}) {
      if (termination == ToString(t)) {
        s.termination = t;
        known = true;
      }
    }
    if (!known) Fail(node["termination"], key + ".termination", "unknown termination");
    s.message = node["message"] ? node["message"].as<std::string>() : std::string();
    s.mean_relative_error = Scalar<double>(node, key, "mean_relative_error");
    s.max_relative_error = Scalar<double>(node, key, "max_relative_error");
    s.condition_number = Scalar<double>(node, key, "condition_number");
    s.samples = Scalar<int>(node, key, "samples");
    s.iterations = Scalar<int>(node, key, "iterations");
    s.gauge_index = Scalar<int>(node, key, "gauge_index");
    return s;
  }

 private:
  std::string path_;
};

// Format 4: the geometric blur's terms in u = 1000 / d (absent: a fixed blur).
void EmitGeometricBlur(YAML::Emitter& out, const GeometricModel& g) {
  if (!g.BlurVariesWithDistance()) return;
  EmitDouble(out, "blur_u1_px2", g.blur_u1_px2);
  EmitDouble(out, "blur_u2_px2", g.blur_u2_px2);
}

// Format 4 keys blur_u1_px2 / blur_u2_px2 (both or neither; absent: a fixed blur).
void ReadGeometricBlur(const Reader& rd, const YAML::Node& g, int version, GeometricModel* geo) {
  if (!g["blur_u1_px2"].IsDefined() && !g["blur_u2_px2"].IsDefined()) return;
  if (version < 4) {
    rd.Fail(g["blur_u1_px2"], "geometric.blur_u1_px2",
            "is new in format_version 4; this file says " + std::to_string(version));
  }
  geo->blur_u1_px2 = rd.Scalar<double>(g, "geometric", "blur_u1_px2");
  geo->blur_u2_px2 = rd.Scalar<double>(g, "geometric", "blur_u2_px2");
  if (!std::isfinite(geo->blur_u1_px2) || !std::isfinite(geo->blur_u2_px2)) {
    rd.Fail(g["blur_u1_px2"], "geometric.blur_u1_px2", "must be finite");
  }
}

// Format 4: the calibrated blur of the health check (health.h); absent: no health check.
void EmitBlurCalibration(YAML::Emitter& out, const BlurCalibration& b) {
  if (!b.fitted()) return;
  out << YAML::Key << "blur_calibration" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "blur_var_px2" << YAML::Value << YAML::Flow << YAML::BeginSeq << b.c0_px2
      << b.c1_px2 << b.c2_px2 << YAML::EndSeq;
  EmitDouble(out, "noise_at_1m_px2", b.noise_at_1m_px2);
  EmitDouble(out, "noise_exponent", b.noise_exponent);
  out << YAML::Key << "frames" << YAML::Value << b.frames;
  out << YAML::EndMap;
}

void ReadBlurCalibration(const Reader& rd, const YAML::Node& root, int version,
                         BlurCalibration* b) {
  const YAML::Node node = root["blur_calibration"];
  if (!node.IsDefined() || node.IsNull()) return;
  if (version < 4) {
    rd.Fail(node, "blur_calibration",
            "is new in format_version 4; this file says " + std::to_string(version));
  }
  const std::vector<double> c = rd.Doubles(node, "blur_calibration", "blur_var_px2", false);
  if (c.size() != 3) rd.Fail(node["blur_var_px2"], "blur_calibration.blur_var_px2", "expected 3 numbers");
  b->c0_px2 = c[0];
  b->c1_px2 = c[1];
  b->c2_px2 = c[2];
  b->noise_at_1m_px2 = rd.Scalar<double>(node, "blur_calibration", "noise_at_1m_px2");
  b->noise_exponent = rd.Scalar<double>(node, "blur_calibration", "noise_exponent");
  b->frames = rd.Scalar<int>(node, "blur_calibration", "frames");
  if (!(b->noise_at_1m_px2 > 0.0) || !std::isfinite(b->noise_exponent)) {
    rd.Fail(node["noise_at_1m_px2"], "blur_calibration.noise_at_1m_px2",
            "must be > 0 with a finite noise_exponent");
  }
}

}  // namespace

ModelFileError::ModelFileError(const std::string& path, const std::string& key, int line,
                               const std::string& problem)
    : Error(Message(path, key, line, problem)), path_(path), key_(key), line_(line) {}

std::string ModelToYaml(const CalibrationModel& model) {
  YAML::Emitter out;
  out.SetDoublePrecision(std::numeric_limits<double>::max_digits10);
  out << YAML::BeginMap;
  out << YAML::Key << "format_version" << YAML::Value << kModelFormatVersion;

  const FeatureOptions& f = model.features;
  out << YAML::Key << "features" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "roi_policy" << YAML::Value << ToString(f.roi_policy);
  out << YAML::Key << "window_side_px" << YAML::Value << f.window_side_px;
  EmitDouble(out, "threshold_fraction", f.threshold_fraction);
  EmitDouble(out, "moment_threshold_fraction", f.moment_threshold_fraction);
  out << YAML::Key << "moment_method" << YAML::Value << ToString(f.moment_method);
  EmitDouble(out, "aperture_margin_px", f.aperture_margin_px);
  EmitDouble(out, "psf_sigma_px", f.psf_sigma_px);
  out << YAML::Key << "detection_downsample" << YAML::Value << f.detection_downsample;
  EmitDouble(out, "min_contrast_fraction", f.min_contrast_fraction);
  out << YAML::Key << "ellipse_method" << YAML::Value << ToString(f.ellipse_method);
  out << YAML::Key << "inverse_response_m" << YAML::Value << YAML::Flow << f.inverse_response.m;
  out << YAML::Key << "inverse_response_f" << YAML::Value << YAML::Flow << f.inverse_response.f;
  out << YAML::Key << "response_scope" << YAML::Value << ToString(f.response_scope);
  out << YAML::EndMap;

  const ModelScaling& s = model.scaling;
  out << YAML::Key << "scaling" << YAML::Value << YAML::BeginMap;
  EmitDouble(out, "d_ref_mm", s.d_ref_mm);
  EmitDouble(out, "d_scale", s.d_scale);
  EmitDouble(out, "t_scale_ms", s.t_scale_ms);
  EmitDouble(out, "i0_scale_ma", s.i0_scale_ma);
  EmitDouble(out, "df_scale", s.df_scale);
  out << YAML::EndMap;

  const CalibratedRanges& r = model.ranges;
  out << YAML::Key << "ranges" << YAML::Value << YAML::BeginMap;
  auto range = [&out](const char* key, double lo, double hi) {
    out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq << lo << hi
        << YAML::EndSeq;
  };
  range("d_mm", r.d_min_mm, r.d_max_mm);
  range("theta_deg", r.theta_min_deg, r.theta_max_deg);
  range("t_ms", r.t_min_ms, r.t_max_ms);
  range("t_ref_ms", r.t_ref_min_ms, r.t_ref_max_ms);
  range("bias_ma", r.bias_min_ma, r.bias_max_ma);
  out << YAML::EndMap;

  out << YAML::Key << "models" << YAML::Value << YAML::BeginSeq;
  for (const FittedModel& m : model.models) {
    out << YAML::BeginMap;
    out << YAML::Key << "kind" << YAML::Value << ToString(m.kind);
    out << YAML::Key << "form" << YAML::Value << ToString(m.form);
    EmitDouble(out, "sigma_deg", m.sigma_deg);
    out << YAML::Key << "degenerate" << YAML::Value << m.degenerate;
    out << YAML::Key << "coefficients" << YAML::Value << YAML::Flow << m.coefficients;
    EmitFit(out, m.summary);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;

  out << YAML::Key << "geometric" << YAML::Value << YAML::BeginMap;
  EmitDouble(out, "alpha_px2", model.geometric.alpha_px2);
  EmitDouble(out, "beta_px2", model.geometric.beta_px2);
  if (model.geometric.noise_rel_at_1m > 0.0) {
    EmitDouble(out, "noise_rel_at_1m", model.geometric.noise_rel_at_1m);
    EmitDouble(out, "noise_exponent", model.geometric.noise_exponent);
  }
  EmitGeometricBlur(out, model.geometric);
  EmitFit(out, model.geometric.summary);
  out << YAML::EndMap;

  const ThetaCorrection& tc = model.theta_correction;
  if (tc.fitted()) {
    out << YAML::Key << "theta_correction" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "degree" << YAML::Value << tc.degree;
    out << YAML::Key << "coefficients" << YAML::Value << YAML::Flow << tc.coefficients;
    out << YAML::Key << "ratio_sq" << YAML::Value << YAML::Flow << YAML::BeginSeq
        << tc.ratio_sq_min << tc.ratio_sq_max << YAML::EndSeq;
    out << YAML::Key << "d_geometric_mm" << YAML::Value << YAML::Flow << YAML::BeginSeq
        << tc.d_min_mm << tc.d_max_mm << YAML::EndSeq;
    EmitFit(out, tc.summary);
    out << YAML::EndMap;
  }
  EmitBlurCalibration(out, model.blur_calibration);
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

CalibrationModel ModelFromYaml(const std::string& text, const std::string& path) {
  const Reader rd(path);
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw ModelFileError(path, "", e.mark.line + 1, std::string("not valid YAML: ") + e.msg);
  }
  if (!root.IsMap()) rd.Fail(root, "", "the document is not a map");
  const int version = rd.Scalar<int>(root, "", "format_version");
  if (version < kOldestModelFormatVersion || version > kModelFormatVersion) {
    rd.Fail(root["format_version"], "format_version",
            "version " + std::to_string(version) + " is not a supported version (" +
                std::to_string(kOldestModelFormatVersion) + ".." +
                std::to_string(kModelFormatVersion) + ")");
  }
  CalibrationModel model;
  const YAML::Node f = rd.Child(root, "", "features");
  FeatureOptions& fo = model.features;
  if (!ParseRoiPolicy(rd.Scalar<std::string>(f, "features", "roi_policy"), &fo.roi_policy))
    rd.Fail(f["roi_policy"], "features.roi_policy", "unknown ROI policy");
  fo.window_side_px = rd.Scalar<int>(f, "features", "window_side_px");
  fo.threshold_fraction = rd.Scalar<double>(f, "features", "threshold_fraction");
  fo.moment_threshold_fraction = rd.Scalar<double>(f, "features", "moment_threshold_fraction");
  fo.psf_sigma_px = rd.Scalar<double>(f, "features", "psf_sigma_px");
  // Version 2 keys; absent (version 1): what version 1 files were made with (threshold moments,
  // the default then; the default is now aperture moments).
  fo.moment_method = MomentMethod::kThreshold;
  if (f["moment_method"].IsDefined() && !f["moment_method"].IsNull()) {
    if (!ParseMomentMethod(rd.Scalar<std::string>(f, "features", "moment_method"),
                           &fo.moment_method))
      rd.Fail(f["moment_method"], "features.moment_method",
              "unknown moment method (threshold or aperture)");
  }
  if (f["aperture_margin_px"].IsDefined() && !f["aperture_margin_px"].IsNull()) {
    fo.aperture_margin_px = rd.Scalar<double>(f, "features", "aperture_margin_px");
  }
  fo.detection_downsample = rd.Scalar<int>(f, "features", "detection_downsample");
  fo.min_contrast_fraction = rd.Scalar<double>(f, "features", "min_contrast_fraction");
  if (!ParseEllipseMethod(rd.Scalar<std::string>(f, "features", "ellipse_method"),
                          &fo.ellipse_method))
    rd.Fail(f["ellipse_method"], "features.ellipse_method", "unknown ellipse method");
  fo.inverse_response.m = rd.Doubles(f, "features", "inverse_response_m", true);
  fo.inverse_response.f = rd.Doubles(f, "features", "inverse_response_f", true);
  // Version 3 key; absent (versions 1 and 2): the curve entered E_rel only.
  fo.response_scope = ResponseScope::kERelOnly;
  if (f["response_scope"].IsDefined() && !f["response_scope"].IsNull()) {
    if (version < 3)
      rd.Fail(f["response_scope"], "features.response_scope",
              "response_scope is new in format_version 3; this file says " +
                  std::to_string(version));
    if (!ParseResponseScope(rd.Scalar<std::string>(f, "features", "response_scope"),
                            &fo.response_scope))
      rd.Fail(f["response_scope"], "features.response_scope",
              "unknown response scope (e_rel_only or all_pixels)");
  }
  std::string why;
  if (!fo.IsValid(&why)) rd.Fail(f, "features", why);

  const YAML::Node s = rd.Child(root, "", "scaling");
  ModelScaling& sc = model.scaling;
  sc.d_ref_mm = rd.Scalar<double>(s, "scaling", "d_ref_mm");
  sc.d_scale = rd.Scalar<double>(s, "scaling", "d_scale");
  sc.t_scale_ms = rd.Scalar<double>(s, "scaling", "t_scale_ms");
  sc.i0_scale_ma = rd.Scalar<double>(s, "scaling", "i0_scale_ma");
  sc.df_scale = rd.Scalar<double>(s, "scaling", "df_scale");
  for (const char* key : {"d_ref_mm", "d_scale", "t_scale_ms", "i0_scale_ma", "df_scale"}) {
    if (!(s[key].as<double>() > 0.0)) rd.Fail(s[key], std::string("scaling.") + key, "must be > 0");
  }

  const YAML::Node r = rd.Child(root, "", "ranges");
  CalibratedRanges& cr = model.ranges;
  rd.Range(r, "ranges", "d_mm", &cr.d_min_mm, &cr.d_max_mm);
  rd.Range(r, "ranges", "theta_deg", &cr.theta_min_deg, &cr.theta_max_deg);
  rd.Range(r, "ranges", "t_ms", &cr.t_min_ms, &cr.t_max_ms);
  rd.Range(r, "ranges", "t_ref_ms", &cr.t_ref_min_ms, &cr.t_ref_max_ms);
  rd.Range(r, "ranges", "bias_ma", &cr.bias_min_ma, &cr.bias_max_ma);

  const YAML::Node models = rd.Child(root, "", "models");
  if (!models.IsSequence()) rd.Fail(models, "models", "expected a sequence");
  for (size_t i = 0; i < models.size(); ++i) {
    const std::string key = "models[" + std::to_string(i) + "]";
    const YAML::Node m = models[i];
    FittedModel fm;
    if (!ParseModelKind(rd.Scalar<std::string>(m, key, "kind"), &fm.kind))
      rd.Fail(m["kind"], key + ".kind", "unknown model kind");
    if (!ParseModelForm(rd.Scalar<std::string>(m, key, "form"), &fm.form))
      rd.Fail(m["form"], key + ".form", "unknown model form (full or reduced)");
    fm.sigma_deg = rd.Scalar<double>(m, key, "sigma_deg");
    fm.degenerate = rd.Scalar<bool>(m, key, "degenerate");
    fm.coefficients = rd.Doubles(m, key, "coefficients", false);
    const int expected = GetModelSpec(fm.kind).num_coefficients();
    if (static_cast<int>(fm.coefficients.size()) != expected) {
      rd.Fail(m["coefficients"], key + ".coefficients",
              "expected " + std::to_string(expected) + " coefficients for " + ToString(fm.kind) +
                  ", found " + std::to_string(fm.coefficients.size()));
    }
    fm.summary = rd.Fit(m, key);
    model.models.push_back(std::move(fm));
  }
  const YAML::Node g = rd.Child(root, "", "geometric");
  model.geometric.alpha_px2 = rd.Scalar<double>(g, "geometric", "alpha_px2");
  model.geometric.beta_px2 = rd.Scalar<double>(g, "geometric", "beta_px2");
  // Optional (absent in files written before the noise model): standard errors then stay in
  // units of the mean fit error.
  if (g["noise_rel_at_1m"].IsDefined() && !g["noise_rel_at_1m"].IsNull()) {
    model.geometric.noise_rel_at_1m = rd.Scalar<double>(g, "geometric", "noise_rel_at_1m");
    model.geometric.noise_exponent = rd.Scalar<double>(g, "geometric", "noise_exponent");
    if (!(model.geometric.noise_rel_at_1m > 0.0) ||
        !std::isfinite(model.geometric.noise_exponent)) {
      rd.Fail(g["noise_rel_at_1m"], "geometric.noise_rel_at_1m",
              "must be > 0 with a finite noise_exponent (or both absent)");
    }
  }
  ReadGeometricBlur(rd, g, version, &model.geometric);
  model.geometric.summary = rd.Fit(g, "geometric");

  const YAML::Node t = root["theta_correction"];
  if (t.IsDefined() && !t.IsNull()) {
    ThetaCorrection& tc = model.theta_correction;
    tc.degree = rd.Scalar<int>(t, "theta_correction", "degree");
    if (tc.degree < 1 || tc.degree > 3)
      rd.Fail(t["degree"], "theta_correction.degree", "must be 1, 2 or 3");
    tc.coefficients = rd.Doubles(t, "theta_correction", "coefficients", false);
    const int expected = ThetaCorrection::NumTerms(tc.degree);
    if (static_cast<int>(tc.coefficients.size()) != expected) {
      rd.Fail(t["coefficients"], "theta_correction.coefficients",
              "expected " + std::to_string(expected) + " coefficients for degree " +
                  std::to_string(tc.degree) + ", found " +
                  std::to_string(tc.coefficients.size()));
    }
    rd.Range(t, "theta_correction", "ratio_sq", &tc.ratio_sq_min, &tc.ratio_sq_max);
    rd.Range(t, "theta_correction", "d_geometric_mm", &tc.d_min_mm, &tc.d_max_mm);
    tc.summary = rd.Fit(t, "theta_correction");
  }
  ReadBlurCalibration(rd, root, version, &model.blur_calibration);
  return model;
}

void SaveModel(const CalibrationModel& model, const std::string& path) {
  const std::string text = ModelToYaml(model);
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) throw ModelFileError(path, "", 0, "cannot open for writing (check the folder exists)");
  file << text;
  file.close();
  if (!file) throw ModelFileError(path, "", 0, "write failed (disk full?)");
}

CalibrationModel LoadModel(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw ModelFileError(path, "", 0, "cannot open for reading (check the path)");
  std::ostringstream text;
  text << file.rdbuf();
  return ModelFromYaml(text.str(), path);
}

}  // namespace irdist
