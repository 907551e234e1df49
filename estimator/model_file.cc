#include "estimator/model_file.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <type_traits>

#include "base/regular_file.h"
#include "base/safe_file.h"
#include "estimator/defect_map_file.h"
#include "estimator/model_file_bounds.h"
#include "estimator/model_file_fitness.h"
#include "estimator/model_file_geometric.h"
#include "estimator/model_file_reader.h"

namespace irdist {
namespace {

using model_file::Reader;

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

// The `provenance:` block (estimator/provenance.h); written only when known.
void EmitProvenance(YAML::Emitter& out, const ModelProvenance& p) {
  if (!p.known) return;
  out << YAML::Key << "provenance" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "rig_name" << YAML::Value << p.rig_name;
  out << YAML::Key << "rig_path" << YAML::Value << p.rig_path;
  out << YAML::Key << "camera_vendor" << YAML::Value << p.camera_vendor;
  out << YAML::Key << "camera_model" << YAML::Value << p.camera_model;
  out << YAML::Key << "camera_serial" << YAML::Value << p.camera_serial;
  out << YAML::Key << "pixel_format" << YAML::Value << p.pixel_format;
  out << YAML::Key << "bit_depth" << YAML::Value << p.bit_depth;
  out << YAML::Key << "roi_px" << YAML::Value << YAML::Flow << YAML::BeginSeq << p.roi_offset_x
      << p.roi_offset_y << p.roi_width << p.roi_height << YAML::EndSeq;
  out << YAML::Key << "recipe_path" << YAML::Value << p.recipe_path;
  out << YAML::Key << "calibration_date" << YAML::Value << p.calibration_date;
  out << YAML::Key << "t_ref_ms" << YAML::Value << p.t_ref_ms;
  out << YAML::Key << "t_meas_ms" << YAML::Value << YAML::Flow << p.t_meas_ms;
  out << YAML::Key << "retake_reference" << YAML::Value << p.retake_reference;
  out << YAML::EndMap;
}

// provenance.roi_px: [x, y, width, height], whole pixels inside any sensor, width and height 0
// for the full sensor; checked before the cast to int (1e300 would be undefined behaviour).
void ReadRoi(const Reader& rd, const YAML::Node& n, const std::string& k, ModelProvenance* p) {
  constexpr double kMaxSensorPx = 1 << 20;
  const std::vector<double> roi = rd.Doubles(n, k, "roi_px", false);
  const std::string shape = "expected [x, y, width, height], each a whole number of sensor "
                            "pixels in [0, 1048576] (width and height 0: the full sensor)";
  if (roi.size() != 4) rd.Fail(n["roi_px"], k + ".roi_px", shape);
  for (double v : roi) {
    if (!(v >= 0.0 && v <= kMaxSensorPx) || v != std::floor(v)) {
      rd.Fail(n["roi_px"], k + ".roi_px", shape);
    }
  }
  if ((roi[2] == 0.0) != (roi[3] == 0.0)) {
    rd.Fail(n["roi_px"], k + ".roi_px", shape + "; width and height are both 0 or both > 0");
  }
  p->roi_offset_x = static_cast<int>(roi[0]);
  p->roi_offset_y = static_cast<int>(roi[1]);
  p->roi_width = static_cast<int>(roi[2]);
  p->roi_height = static_cast<int>(roi[3]);
}

// The optional `provenance:` block; provenance.known says whether it was there.
ModelProvenance ReadProvenance(const Reader& rd, const YAML::Node& root) {
  ModelProvenance p;
  const YAML::Node n = root["provenance"];
  if (!n.IsDefined() || n.IsNull()) return p;
  const std::string k = "provenance";
  rd.Keys(n, k, {"rig_name", "rig_path", "camera_vendor", "camera_model", "camera_serial",
                 "pixel_format", "bit_depth", "roi_px", "recipe_path", "calibration_date",
                 "t_ref_ms", "t_meas_ms", "retake_reference"});
  p.known = true;
  p.rig_name = rd.Scalar<std::string>(n, k, "rig_name");
  p.rig_path = rd.Scalar<std::string>(n, k, "rig_path");
  p.camera_vendor = rd.Scalar<std::string>(n, k, "camera_vendor");
  p.camera_model = rd.Scalar<std::string>(n, k, "camera_model");
  p.camera_serial = rd.Scalar<std::string>(n, k, "camera_serial");
  p.pixel_format = rd.Scalar<std::string>(n, k, "pixel_format");
  p.bit_depth = rd.Scalar<int>(n, k, "bit_depth");
  if (p.bit_depth < 1 || p.bit_depth > 16) {
    rd.Fail(n["bit_depth"], k + ".bit_depth",
            std::to_string(p.bit_depth) + " is not a camera bit depth; valid: 1..16 (Mono8: 8, "
            "Mono12: 12)");
  }
  ReadRoi(rd, n, k, &p);
  p.recipe_path = rd.Scalar<std::string>(n, k, "recipe_path");
  p.calibration_date = rd.Scalar<std::string>(n, k, "calibration_date");
  p.t_ref_ms = rd.Scalar<double>(n, k, "t_ref_ms");
  p.t_meas_ms = rd.Doubles(n, k, "t_meas_ms", false);
  p.retake_reference = rd.Scalar<bool>(n, k, "retake_reference");
  return p;
}

// An optional key: present and not null.
bool Present(const YAML::Node& parent, const char* name) {
  return parent[name].IsDefined() && !parent[name].IsNull();
}

// Format 4: the calibrated blur of the health check (blur_model.h); absent: no health check.
void EmitBlurCalibration(YAML::Emitter& out, const BlurCalibration& b) {
  if (!b.fitted()) return;
  out << YAML::Key << "blur_calibration" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "blur_var_px2" << YAML::Value << YAML::Flow << YAML::BeginSeq << b.c0_px2
      << b.c1_px2 << b.c2_px2 << YAML::EndSeq;
  EmitDouble(out, "noise_at_1m_px2", b.noise_at_1m_px2);
  EmitDouble(out, "noise_exponent", b.noise_exponent);
  out << YAML::Key << "frames" << YAML::Value << b.frames;
  if (b.crosstalk_var_px2 > 0.0) {
    EmitDouble(out, "crosstalk_var_px2", b.crosstalk_var_px2);
    EmitDouble(out, "crosstalk_lattice_share", b.crosstalk_lattice_share);
  }
  if (b.optics_excess != 0.0) EmitDouble(out, "optics_excess", b.optics_excess);
  if (b.fit_offset_px2 != 0.0 || b.fit_offset_u_px2 != 0.0) {
    EmitDouble(out, "fit_offset_px2", b.fit_offset_px2);
    EmitDouble(out, "fit_offset_u_px2", b.fit_offset_u_px2);
  }
  if (b.fit_offset_u2_px2 != 0.0) EmitDouble(out, "fit_offset_u2_px2", b.fit_offset_u2_px2);
  if (b.psf_aniso_c_px2 != 0.0 || b.psf_aniso_s_px2 != 0.0) {
    EmitDouble(out, "psf_aniso_c_px2", b.psf_aniso_c_px2);
    EmitDouble(out, "psf_aniso_s_px2", b.psf_aniso_s_px2);
  }
  if (!b.edge_correction.empty()) {  // whole 1e-6 (LearnEdgeCorrection): 6 digits are exact
    out.SetDoublePrecision(6);
    out << YAML::Key << "edge_correction" << YAML::Value << YAML::Flow << b.edge_correction;
    out.SetDoublePrecision(std::numeric_limits<double>::max_digits10);  // SaveModel's
  }
  out << YAML::EndMap;
}

// blur_calibration.edge_correction: optional (absent: none), kEdgeCorrectionKnots numbers; its
// values bounded by model_file_bounds.h.
void ReadEdgeCorrection(const Reader& rd, const YAML::Node& node, BlurCalibration* b) {
  if (!Present(node, "edge_correction")) return;
  b->edge_correction = rd.Doubles(node, "blur_calibration", "edge_correction", false);
  if (b->edge_correction.size() != static_cast<std::size_t>(kEdgeCorrectionKnots)) {
    rd.Fail(node["edge_correction"], "blur_calibration.edge_correction",
            "expected " + std::to_string(kEdgeCorrectionKnots) +
                " numbers (the edge's correction every 0.1 px from 5 px outside the edge to 5 "
                "px inside); to use none, delete the key");
  }
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
  if (Present(node, "crosstalk_var_px2")) {  // optional: absent = all of the blur is the optics'
    b->crosstalk_var_px2 = rd.Scalar<double>(node, "blur_calibration", "crosstalk_var_px2");
    if (!(b->crosstalk_var_px2 >= 0.0) || !(b->crosstalk_var_px2 < b->c0_px2 + 10.0)) {
      rd.Fail(node["crosstalk_var_px2"], "blur_calibration.crosstalk_var_px2",
              "must be >= 0 and below the blur itself (px^2)");
    }
  }
  if (Present(node, "crosstalk_lattice_share")) {  // optional: absent = a sampled Gaussian
    b->crosstalk_lattice_share =
        rd.Scalar<double>(node, "blur_calibration", "crosstalk_lattice_share");
    if (!(b->crosstalk_lattice_share >= 0.0 && b->crosstalk_lattice_share <= 1.0)) {
      rd.Fail(node["crosstalk_lattice_share"], "blur_calibration.crosstalk_lattice_share",
              "must lie within [0, 1]");
    }
  }
  // Optional (absent: a Gaussian optics' edge); bounded by model_file_bounds.h.
  if (Present(node, "optics_excess")) {
    b->optics_excess = rd.Scalar<double>(node, "blur_calibration", "optics_excess");
  }
  // Optional (absent: the cumulants' blur as it is, no slope); bounded by model_file_bounds.h.
  if (Present(node, "fit_offset_px2")) {
    b->fit_offset_px2 = rd.Scalar<double>(node, "blur_calibration", "fit_offset_px2");
  }
  if (Present(node, "fit_offset_u_px2")) {
    b->fit_offset_u_px2 = rd.Scalar<double>(node, "blur_calibration", "fit_offset_u_px2");
  }
  if (Present(node, "fit_offset_u2_px2")) {
    b->fit_offset_u2_px2 = rd.Scalar<double>(node, "blur_calibration", "fit_offset_u2_px2");
  }
  ReadEdgeCorrection(rd, node, b);
  // Optional (absent: a round PSF); bounded by model_file_bounds.h.
  if (Present(node, "psf_aniso_c_px2")) {
    b->psf_aniso_c_px2 = rd.Scalar<double>(node, "blur_calibration", "psf_aniso_c_px2");
  }
  if (Present(node, "psf_aniso_s_px2")) {
    b->psf_aniso_s_px2 = rd.Scalar<double>(node, "blur_calibration", "psf_aniso_s_px2");
  }
  if (!(b->noise_at_1m_px2 > 0.0) || !std::isfinite(b->noise_exponent)) {
    rd.Fail(node["noise_at_1m_px2"], "blur_calibration.noise_at_1m_px2",
            "must be > 0 with a finite noise_exponent");
  }
}

}  // namespace

namespace {

void EmitFeatures(YAML::Emitter& out, const FeatureOptions& f) {
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
  // Written only when the moments path is chosen: files without it keep the default (blob fit).
  if (!f.blob_fit) out << YAML::Key << "blob_fit" << YAML::Value << false;
  out << YAML::Key << "subtract_background" << YAML::Value << f.subtract_background;
  if (!f.scene.defect_map.empty()) model_file::EmitDefectMap(out, f.scene.defect_map);
  out << YAML::EndMap;
}

void EmitScalingAndRanges(YAML::Emitter& out, const ModelScaling& s, const CalibratedRanges& r) {
  out << YAML::Key << "scaling" << YAML::Value << YAML::BeginMap;
  EmitDouble(out, "d_ref_mm", s.d_ref_mm);
  EmitDouble(out, "d_scale", s.d_scale);
  EmitDouble(out, "t_scale_ms", s.t_scale_ms);
  EmitDouble(out, "i0_scale_ma", s.i0_scale_ma);
  EmitDouble(out, "df_scale", s.df_scale);
  out << YAML::EndMap;
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
  if (r.peak_max > 0.0) range("peak", r.peak_min, r.peak_max);
  out << YAML::EndMap;
}

void EmitModels(YAML::Emitter& out, const std::vector<FittedModel>& models) {
  out << YAML::Key << "models" << YAML::Value << YAML::BeginSeq;
  for (const FittedModel& m : models) {
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
}

void EmitGeometric(YAML::Emitter& out, const GeometricModel& g) {
  out << YAML::Key << "geometric" << YAML::Value << YAML::BeginMap;
  EmitDouble(out, "alpha_px2", g.alpha_px2);
  EmitDouble(out, "beta_px2", g.beta_px2);
  if (g.noise_rel_at_1m > 0.0) {
    EmitDouble(out, "noise_rel_at_1m", g.noise_rel_at_1m);
    EmitDouble(out, "noise_exponent", g.noise_exponent);
  }
  model_file::EmitGeometricTerms(out, g);
  EmitFit(out, g.summary);
  out << YAML::EndMap;
}

void EmitThetaCorrection(YAML::Emitter& out, const ThetaCorrection& tc) {
  if (!tc.fitted()) return;
  out << YAML::Key << "theta_correction" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "degree" << YAML::Value << tc.degree;
  out << YAML::Key << "coefficients" << YAML::Value << YAML::Flow << tc.coefficients;
  out << YAML::Key << "ratio_sq" << YAML::Value << YAML::Flow << YAML::BeginSeq << tc.ratio_sq_min
      << tc.ratio_sq_max << YAML::EndSeq;
  out << YAML::Key << "d_geometric_mm" << YAML::Value << YAML::Flow << YAML::BeginSeq
      << tc.d_min_mm << tc.d_max_mm << YAML::EndSeq;
  EmitFit(out, tc.summary);
  out << YAML::EndMap;
}

FeatureOptions ReadFeatures(const Reader& rd, const YAML::Node& root, int version) {
  const YAML::Node f = rd.Child(root, "", "features");
  rd.Keys(f, "features",
          {"roi_policy", "window_side_px", "threshold_fraction", "moment_threshold_fraction",
           "moment_method", "aperture_margin_px", "psf_sigma_px", "detection_downsample",
           "min_contrast_fraction", "ellipse_method", "inverse_response_m", "inverse_response_f",
           "response_scope", "blob_fit", "subtract_background", "defect_map"});
  FeatureOptions fo;
  if (!ParseRoiPolicy(rd.Scalar<std::string>(f, "features", "roi_policy"), &fo.roi_policy))
    rd.Fail(f["roi_policy"], "features.roi_policy", "unknown ROI policy");
  fo.window_side_px = rd.Scalar<int>(f, "features", "window_side_px");
  fo.threshold_fraction = rd.Scalar<double>(f, "features", "threshold_fraction");
  fo.moment_threshold_fraction = rd.Scalar<double>(f, "features", "moment_threshold_fraction");
  fo.psf_sigma_px = rd.Scalar<double>(f, "features", "psf_sigma_px");
  // Version 2 keys; absent (version 1): what version 1 files were made with (threshold moments,
  // the default then; the default is now aperture moments).
  fo.moment_method = MomentMethod::kThreshold;
  if (Present(f, "moment_method") &&
      !ParseMomentMethod(rd.Scalar<std::string>(f, "features", "moment_method"),
                         &fo.moment_method)) {
    rd.Fail(f["moment_method"], "features.moment_method",
            "unknown moment method (threshold or aperture)");
  }
  if (Present(f, "aperture_margin_px")) {
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
  if (Present(f, "response_scope")) {
    if (version < 3)
      rd.Fail(f["response_scope"], "features.response_scope",
              "response_scope is new in format_version 3; this file says " +
                  std::to_string(version));
    if (!ParseResponseScope(rd.Scalar<std::string>(f, "features", "response_scope"),
                            &fo.response_scope))
      rd.Fail(f["response_scope"], "features.response_scope",
              "unknown response scope (e_rel_only or all_pixels)");
  }
  if (Present(f, "blob_fit")) fo.blob_fit = rd.Scalar<bool>(f, "features", "blob_fit");
  fo.subtract_background = Present(f, "subtract_background") &&
                           rd.Scalar<bool>(f, "features", "subtract_background");
  if (Present(f, "defect_map")) fo.scene.defect_map = model_file::ReadDefectMap(rd, f, "features");
  std::string why;
  if (!fo.IsValid(&why)) rd.Fail(f, "features", why);
  return fo;
}

ModelScaling ReadScaling(const Reader& rd, const YAML::Node& root) {
  const YAML::Node s = rd.Child(root, "", "scaling");
  rd.Keys(s, "scaling", {"d_ref_mm", "d_scale", "t_scale_ms", "i0_scale_ma", "df_scale"});
  ModelScaling sc;
  sc.d_ref_mm = rd.Scalar<double>(s, "scaling", "d_ref_mm");
  sc.d_scale = rd.Scalar<double>(s, "scaling", "d_scale");
  sc.t_scale_ms = rd.Scalar<double>(s, "scaling", "t_scale_ms");
  sc.i0_scale_ma = rd.Scalar<double>(s, "scaling", "i0_scale_ma");
  sc.df_scale = rd.Scalar<double>(s, "scaling", "df_scale");
  for (const char* key : {"d_ref_mm", "d_scale", "t_scale_ms", "i0_scale_ma", "df_scale"}) {
    if (!(s[key].as<double>() > 0.0)) rd.Fail(s[key], std::string("scaling.") + key, "must be > 0");
  }
  return sc;
}

CalibratedRanges ReadRanges(const Reader& rd, const YAML::Node& root) {
  const YAML::Node r = rd.Child(root, "", "ranges");
  rd.Keys(r, "ranges", {"d_mm", "theta_deg", "t_ms", "t_ref_ms", "bias_ma", "peak"});
  CalibratedRanges cr;
  rd.Range(r, "ranges", "d_mm", &cr.d_min_mm, &cr.d_max_mm);
  rd.Range(r, "ranges", "theta_deg", &cr.theta_min_deg, &cr.theta_max_deg);
  rd.Range(r, "ranges", "t_ms", &cr.t_min_ms, &cr.t_max_ms);
  rd.Range(r, "ranges", "t_ref_ms", &cr.t_ref_min_ms, &cr.t_ref_max_ms);
  rd.Range(r, "ranges", "bias_ma", &cr.bias_min_ma, &cr.bias_max_ma);
  if (r["peak"]) rd.Range(r, "ranges", "peak", &cr.peak_min, &cr.peak_max);  // optional
  return cr;
}

FittedModel ReadFittedModel(const Reader& rd, const YAML::Node& m, const std::string& key) {
  rd.Keys(m, key, {"kind", "form", "sigma_deg", "degenerate", "coefficients", "fit"});
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
  return fm;
}

// The models; free_e (Eq. 17) and free_sigma (Eq. 18) must be there: every estimate uses both.
std::vector<FittedModel> ReadModels(const Reader& rd, const YAML::Node& root) {
  const YAML::Node models = rd.Child(root, "", "models");
  if (!models.IsSequence()) rd.Fail(models, "models", "expected a sequence");
  std::vector<FittedModel> out;
  for (size_t i = 0; i < models.size(); ++i) {
    out.push_back(ReadFittedModel(rd, models[i], "models[" + std::to_string(i) + "]"));
  }
  for (ModelKind kind : {ModelKind::kFreeE, ModelKind::kFreeSigma}) {
    const bool found = std::any_of(out.begin(), out.end(),
                                   [kind](const FittedModel& m) { return m.kind == kind; });
    if (!found) {
      rd.Fail(models, "models",
              std::string("no ") + ToString(kind) + " model; the estimate needs free_e and "
              "free_sigma");
    }
  }
  return out;
}

GeometricModel ReadGeometric(const Reader& rd, const YAML::Node& root, int version) {
  const YAML::Node g = rd.Child(root, "", "geometric");
  rd.Keys(g, "geometric",
          {"alpha_px2", "beta_px2", "noise_rel_at_1m", "noise_exponent", "blur_u1_px2",
           "blur_u2_px2", "blur_u3_px2", "tilt_theta_deg", "tilt_var_px2", "fit"});
  GeometricModel geometric;
  geometric.alpha_px2 = rd.Scalar<double>(g, "geometric", "alpha_px2");
  geometric.beta_px2 = rd.Scalar<double>(g, "geometric", "beta_px2");
  // Optional (absent in files written before the noise model): standard errors then stay in
  // units of the mean fit error.
  if (Present(g, "noise_rel_at_1m")) {
    geometric.noise_rel_at_1m = rd.Scalar<double>(g, "geometric", "noise_rel_at_1m");
    geometric.noise_exponent = rd.Scalar<double>(g, "geometric", "noise_exponent");
    if (!(geometric.noise_rel_at_1m > 0.0)) {
      rd.Fail(g["noise_rel_at_1m"], "geometric.noise_rel_at_1m",
              "must be > 0 with a finite noise_exponent (or both absent)");
    }
  }
  model_file::ReadGeometricTerms(rd, g, version, &geometric);
  geometric.summary = rd.Fit(g, "geometric");
  return geometric;
}

ThetaCorrection ReadThetaCorrection(const Reader& rd, const YAML::Node& root) {
  ThetaCorrection tc;
  const YAML::Node t = root["theta_correction"];
  if (!t.IsDefined() || t.IsNull()) return tc;
  rd.Keys(t, "theta_correction", {"degree", "coefficients", "ratio_sq", "d_geometric_mm", "fit"});
  tc.degree = rd.Scalar<int>(t, "theta_correction", "degree");
  if (tc.degree < 1 || tc.degree > 3)
    rd.Fail(t["degree"], "theta_correction.degree", "must be 1, 2 or 3");
  tc.coefficients = rd.Doubles(t, "theta_correction", "coefficients", false);
  const int expected = ThetaCorrection::NumTerms(tc.degree);
  if (static_cast<int>(tc.coefficients.size()) != expected) {
    rd.Fail(t["coefficients"], "theta_correction.coefficients",
            "expected " + std::to_string(expected) + " coefficients for degree " +
                std::to_string(tc.degree) + ", found " + std::to_string(tc.coefficients.size()));
  }
  rd.Range(t, "theta_correction", "ratio_sq", &tc.ratio_sq_min, &tc.ratio_sq_max);
  rd.Range(t, "theta_correction", "d_geometric_mm", &tc.d_min_mm, &tc.d_max_mm);
  tc.summary = rd.Fit(t, "theta_correction");
  return tc;
}

// The node of a model file's key ("provenance.t_meas_ms[1]"), or an undefined node.
YAML::Node Locate(const YAML::Node& root, const std::string& key) {
  YAML::Node node = root;
  std::string::size_type start = 0;
  while (start <= key.size() && node.IsDefined()) {
    const std::string::size_type end = std::min(key.find('.', start), key.size());
    const std::string part = key.substr(start, end - start);
    const std::string::size_type bracket = part.find('[');
    const YAML::Node& parent = node;  // const lookups: the tree is never changed
    YAML::Node child = parent[part.substr(0, bracket)];
    if (bracket != std::string::npos && child.IsSequence()) {
      const YAML::Node& sequence = child;
      const size_t index = std::stoul(part.substr(bracket + 1));
      child.reset(index < sequence.size() ? sequence[index] : YAML::Node());
    }
    node.reset(child);
    start = end + 1;
  }
  return node;
}

YAML::Node ParseModelText(const std::string& text, const std::string& path) {
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw ModelFileError(path, "", e.mark.line + 1, std::string("not valid YAML: ") + e.msg);
  }
}

}  // namespace

std::string ModelToYaml(const CalibrationModel& model) {
  YAML::Emitter out;
  out.SetDoublePrecision(std::numeric_limits<double>::max_digits10);
  out << YAML::BeginMap;
  out << YAML::Key << "format_version" << YAML::Value << kModelFormatVersion;
  EmitFeatures(out, model.features);
  EmitScalingAndRanges(out, model.scaling, model.ranges);
  EmitModels(out, model.models);
  EmitGeometric(out, model.geometric);
  EmitThetaCorrection(out, model.theta_correction);
  EmitBlurCalibration(out, model.blur_calibration);
  EmitProvenance(out, model.provenance);
  model_file::EmitFitness(out, model.fitness);
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

CalibrationModel ModelFromYaml(const std::string& text, const std::string& path) {
  const Reader rd(path);
  const YAML::Node root = ParseModelText(text, path);
  if (!root.IsMap()) rd.Fail(root, "", "the document is not a map");
  rd.Keys(root, "", {"format_version", "features", "scaling", "ranges", "models", "geometric",
                     "theta_correction", "provenance", "blur_calibration", "fitness"});
  const int version = rd.Scalar<int>(root, "", "format_version");
  if (version < kOldestModelFormatVersion || version > kModelFormatVersion) {
    rd.Fail(root["format_version"], "format_version",
            "version " + std::to_string(version) + " is not a supported version (" +
                std::to_string(kOldestModelFormatVersion) + ".." +
                std::to_string(kModelFormatVersion) + ")");
  }
  CalibrationModel model;
  model.features = ReadFeatures(rd, root, version);
  model.scaling = ReadScaling(rd, root);
  model.ranges = ReadRanges(rd, root);
  model.models = ReadModels(rd, root);
  model.geometric = ReadGeometric(rd, root, version);
  model.theta_correction = ReadThetaCorrection(rd, root);
  model.provenance = ReadProvenance(rd, root);
  ReadBlurCalibration(rd, root, version, &model.blur_calibration);
  model.fitness = model_file::ReadFitness(rd, root);
  for (const ModelBoundFailure& failure : CheckModelBounds(model)) {
    rd.Fail(Locate(root, failure.key), failure.key,
            failure.message + "; irdist fit never writes such a model: restore the file as fit "
                              "wrote it, or calibrate again");
  }
  return model;
}

// Written to path.tmp (created new: a stale or planted one is unlinked, never followed), synced,
// then renamed: a crash leaves the old file or the new one, whole. A model.yaml that is a
// symbolic link is refused.
// A model outside its bounds (model_file_bounds.h) is refused, never written: every reader would
// refuse it.
void SaveModel(const CalibrationModel& model, const std::string& path) {
  const std::vector<ModelBoundFailure> failures = CheckModelBounds(model);
  if (!failures.empty()) {
    throw ModelFileError(path, failures.front().key, 0,
                         "not written: the calibration landed outside the bounds every reader "
                         "checks: " + failures.front().message + "; check the calibration's "
                         "frames and the lens (docs/recipes.md, Bounds)");
  }
  std::string why;
  if (!WriteFileAtomically(path, ModelToYaml(model), 0644, &why)) {
    throw ModelFileError(path, "", 0, why + "; check the folder (and the disk)");
  }
}

CalibrationModel LoadModel(const std::string& path) {
  std::string text, why;
  if (!ReadRegularFile(path, kMaxInputTextBytes, &text, &why)) {
    throw ModelFileError(path, "", 0, why + "; give the path of a model.yaml that calibrate or "
                                            "fit wrote");
  }
  return ModelFromYaml(text, path);
}

}  // namespace irdist
