#include "app/runs/offline.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <ostream>
#include <set>
#include <sstream>
#include <tuple>

#include "acquisition/pixel_format.h"
#include "acquisition/recording.h"
#include "app/display/show.h"
#include "app/inputs/provenance.h"
#include "app/inputs/recipe.h"
#include "app/processing/position.h"
#include "app/reports/crb.h"
#include "app/runs/resume.h"
#include "estimator/blob_fit.h"
#include "estimator/estimate.h"
#include "estimator/health.h"
#include "estimator/model_file.h"
#include "estimator/models.h"

namespace irdist {

namespace fs = std::filesystem;

namespace {

std::string Num(double value) {
  if (!std::isfinite(value)) return "nan";
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.10g", value);
  return buffer;
}

// Measurement frames of a bracket with the reference each one is differenced with.
struct Pair {
  const FrameRecord* reference = nullptr;
  const FrameRecord* measurement = nullptr;
};

std::vector<Pair> PairsOf(const RecordedBracket& bracket) {
  std::vector<Pair> pairs;
  const FrameRecord* last_reference = nullptr;
  for (const FrameRecord& row : bracket.frames) {
    if (row.role == FrameRole::kReference) {
      last_reference = &row;
    } else if (last_reference != nullptr) {
      pairs.push_back({last_reference, &row});
    }
  }
  return pairs;
}

const Features& FeaturesOf(const FeatureMap& features, const FrameRecord& row) {
  const auto it = features.find(row.index);
  IRDIST_CHECK(it != features.end(), "no features for frame ", row.index);
  return it->second;
}

void Normalise(double poly[4]) {
  double norm = 0.0;
  for (int k = 0; k < 4; ++k) norm += poly[k] * poly[k];
  norm = std::sqrt(norm);
  if (norm > 0.0) {
    for (int k = 0; k < 4; ++k) poly[k] /= norm;
  }
}

// A recording with errors (what `irdist check` reports) is refused before anything is computed
// from it: its first errors are listed with file:line.
void RequireCleanRecording(const std::string& dir) {
  const RecordingCheck check = CheckRecording(dir);
  if (check.ok()) return;
  std::ostringstream message;
  message << dir << ": the recording has " << check.errors.size()
          << " error(s); nothing is computed from it. First:";
  for (size_t i = 0; i < check.errors.size() && i < 5; ++i) {
    const RecordingCheck::Issue& issue = check.errors[i];
    message << "\n  " << issue.file << (issue.line > 0 ? ":" + std::to_string(issue.line) : "")
            << ": " << issue.message;
  }
  message << "\nRun `irdist check " << dir << "` for the full list, repair the recording (or "
          << "restore it from a copy) and try again.";
  throw CheckFailedError(message.str());
}

// Results are never replaced without being asked: refuses when one of `names` exists in `dir`;
// one that is a symbolic link is refused even with --force (never written through).
void RefuseExistingResults(const std::string& dir, const std::vector<std::string>& names,
                           bool force, const std::string& command) {
  for (const std::string& name : names) {
    const fs::path path = fs::path(dir) / name;
    std::error_code ec;
    if (fs::is_symlink(fs::symlink_status(path, ec))) {
      throw RunFolderError(path.string() + " is a symbolic link: irdist " + command +
                           " never writes through a link. Remove it, or give a new folder with "
                           "--out.");
    }
    if (!force && fs::exists(path, ec)) {
      throw RunFolderError(path.string() + " exists: irdist " + command +
                           " does not replace results. Give a new folder with --out, or pass "
                           "--force to replace them.");
    }
  }
}

std::string ParentOf(const std::string& dir) {
  fs::path path = fs::path(dir).lexically_normal();
  if (path.filename().empty()) path = path.parent_path();
  const fs::path parent = path.parent_path();
  return parent.empty() ? "." : parent.string();
}

}  // namespace

int BitDepthOfPixelFormat(const std::string& pixel_format) {
  const PixelFormatInfo* format = FindPixelFormat(pixel_format);  // packed ones too (Mono12p)
  return format == nullptr ? 16 : format->bit_depth;
}

Features FrameFeatures(const cv::Mat& image, int bit_depth, const FeatureOptions& options,
                       const CalibrationModel* blob_fit_model) {
  Features features = ComputeFeatures(image, bit_depth, options);
  if (blob_fit_model != nullptr) RefineWithBlobFit(image, bit_depth, *blob_fit_model, &features);
  return features;
}

const CalibrationModel* BlobFitModelOf(const CalibrationModel& model) {
  return model.features.blob_fit ? &model : nullptr;
}

FeatureMap RecordingFeatures(const RecordingReader& reader, const FeatureOptions& options,
                             const FeatureMap& cache, const CalibrationModel* blob_fit_model) {
  FeatureMap features;
  const int bit_depth = reader.header().bit_depth;
  for (const FrameRecord& row : reader.rows()) {
    const auto cached = cache.find(row.index);
    if (cached != cache.end()) {
      features[row.index] = cached->second;
    } else {
      features[row.index] =
          FrameFeatures(reader.LoadImage(row), bit_depth, options, blob_fit_model);
    }
  }
  return features;
}

void WriteFeaturesCsv(const std::string& path, const std::vector<FrameRecord>& rows,
                      const FeatureMap& features) {
  std::ostringstream out;
  out << "index,file,bracket,frame_in_bracket,role,exposure_us,bias_ma,slide_mm,theta_deg,"
         "blob_found,usable,saturated_pixels,touches_border,clipped,roi_x,roi_y,roi_w,roi_h,"
         "roi_area_px,background,peak,e_rel,f00,sigma,centroid_x_px,centroid_y_px,"
         "major_px,minor_px,ellipse_angle_deg,theta0_deg\n";
  for (const FrameRecord& row : rows) {
    const Features& f = FeaturesOf(features, row);
    const EllipseFit& e = f.ellipse_moments.valid ? f.ellipse_moments : f.ellipse_contour;
    out << row.index << ',' << row.file << ',' << row.bracket_id << ',' << row.frame_in_bracket
        << ',' << FrameRoleName(row.role) << ',' << Num(row.requested_exposure_us) << ','
        << Num(row.bias_ma_set) << ',' << Num(row.slide_mm) << ',' << Num(row.theta_deg) << ','
        << (f.blob_found ? 1 : 0) << ',' << (f.Usable() ? 1 : 0) << ',' << f.saturated_pixels << ','
        << (f.touches_border ? 1 : 0) << ',' << (f.blob_clipped_by_roi ? 1 : 0) << ',' << f.roi.x
        << ',' << f.roi.y << ',' << f.roi.width << ',' << f.roi.height << ',' << f.roi_area_px
        << ',' << Num(f.background) << ',' << Num(f.peak) << ',' << Num(f.e_rel) << ','
        << Num(f.f00) << ',' << Num(f.sigma) << ',' << Num(f.centroid_px.x) << ','
        << Num(f.centroid_px.y) << ',' << Num(e.major_px) << ',' << Num(e.minor_px) << ','
        << Num(e.angle_deg) << ',' << Num(f.theta0_deg) << '\n';
  }
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file << out.str();
  file.flush();
  if (!file) {
    throw RecordingError(path +
                         ": cannot write features.csv; check the folder exists and is "
                         "writable.");
  }
}

std::vector<CalibrationSample> SamplesFromRecording(const RecordingReader& reader,
                                                    const FeatureMap& features) {
  std::vector<CalibrationSample> samples;
  for (const RecordedBracket& bracket : reader.Brackets()) {
    if (!bracket.complete) continue;
    for (const Pair& pair : PairsOf(bracket)) {
      CalibrationSample s;
      s.reference = FeaturesOf(features, *pair.reference);
      s.measurement = FeaturesOf(features, *pair.measurement);
      s.t_ref_ms = pair.reference->requested_exposure_us / 1000.0;
      s.t_ms = pair.measurement->requested_exposure_us / 1000.0;
      s.bias_ma = pair.measurement->bias_ma_set;
      s.d_mm = pair.measurement->slide_mm;
      s.theta_deg = std::fabs(pair.measurement->theta_deg);
      samples.push_back(s);
    }
  }
  return samples;
}

std::vector<CalibrationPoint> CalibrationPointsOf(const CalibrationModel& model,
                                                  const std::vector<CalibrationSample>& samples,
                                                  int eq25_curves) {
  std::vector<CalibrationPoint> points;
  const FittedModel* free_e = model.Find(ModelKind::kFreeE);
  const FittedModel* free_s = model.Find(ModelKind::kFreeSigma);
  if (free_e == nullptr || free_s == nullptr) return points;
  const size_t stride =
      eq25_curves > 0 ? std::max<size_t>(1, samples.size() / static_cast<size_t>(eq25_curves)) : 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const CalibrationSample& s = samples[i];
    if (!s.reference.Usable() || !s.measurement.Usable()) continue;
    CalibrationPoint p;
    p.d_mm = s.d_mm;
    p.theta_deg = s.theta_deg;
    p.bias_ma = s.bias_ma;
    p.dt_ms = s.t_ms - s.t_ref_ms;
    ModelInputs in;
    in.d_mm = s.d_mm;
    in.theta_deg = s.theta_deg;
    in.bias_ma = s.bias_ma;
    in.dt_ms = p.dt_ms;
    in.df = s.measurement.f00 - s.reference.f00;
    p.de_measured = s.measurement.e_rel - s.reference.e_rel;
    p.ds_measured = s.measurement.sigma - s.reference.sigma;
    p.de_model = free_e->Predict(model.scaling, in);
    p.ds_model = free_s->Predict(model.scaling, in);
    if (stride > 0 && i % stride == 0 && static_cast<int>(i / stride) < eq25_curves) {
      // Eq. 25 (c - a) as a function of d at the true theta, each polynomial normalised.
      std::array<double, kNumModelVars> vars = ScaleInputs(in, model.scaling);
      double a[4], c[4];
      vars[kVarRho] = Rho(s.theta_deg, free_s->sigma_deg);
      AlgebraicPolynomialInD(GetModelSpec(ModelKind::kFreeSigma), free_s->coefficients.data(),
                             vars.data(), p.ds_measured, c);
      vars[kVarRho] = Rho(s.theta_deg, free_e->sigma_deg);
      AlgebraicPolynomialInD(GetModelSpec(ModelKind::kFreeE), free_e->coefficients.data(),
                             vars.data(), p.de_measured, a);
      Normalise(a);
      Normalise(c);
      const double d_lo = 0.8 * model.ranges.d_min_mm, d_hi = 1.2 * model.ranges.d_max_mm;
      for (int k = 0; k <= 60; ++k) {
        const double d_mm = d_lo + (d_hi - d_lo) * k / 60.0;
        const double x = model.scaling.ScaledD(d_mm);
        double value = 0.0;
        for (int j = 3; j >= 0; --j) value = value * x + (c[j] - a[j]);
        p.eq25_d_mm.push_back(d_mm);
        p.eq25_value.push_back(value);
      }
    }
    points.push_back(std::move(p));
  }
  return points;
}

bool RecipeAsksForResponse(const RecordingReader& reader) {
  const RecordingHeader& header = reader.header();
  if (header.recipe_text.empty()) return false;
  const std::string file =
      header.recipe_path.empty() ? reader.dir() + "/recording.yaml (recipe)" : header.recipe_path;
  return CameraResponseOfRecipeText(header.recipe_text, file) == CameraResponse::kRecover;
}

ResponseRecovery RecoverRecordingResponse(const RecordingReader& reader,
                                          const FeatureOptions& options, std::ostream& out) {
  const int bit_depth = reader.header().bit_depth;
  ResponseOptions response_options;
  response_options.neighbourhood_px = options.window_side_px;
  ResponseRecoverer recoverer(bit_depth, response_options);
  FeatureOptions locate = options;
  locate.inverse_response = InverseResponse();
  locate.response_scope = ResponseScope::kERelOnly;
  int brackets = 0;
  for (const RecordedBracket& bracket : reader.Brackets()) {
    if (!bracket.complete) continue;
    std::vector<cv::Mat> frames;
    std::vector<double> exposures_us;
    for (const FrameRecord& row : bracket.frames) {
      cv::Mat image = reader.LoadImage(row);
      if (image.type() != CV_16UC1) image.convertTo(image, CV_16UC1);
      frames.push_back(image);
      // The camera's own exposure when it reported one (the ratio is what the method uses).
      exposures_us.push_back(row.actual_exposure_us > 0.0 ? row.actual_exposure_us
                                                           : row.requested_exposure_us);
    }
    recoverer.AddStack(frames, exposures_us, locate);
    ++brackets;
  }
  out << "Recovering the camera response from " << brackets << " brackets of " << reader.dir()
      << "\n";
  ResponseRecovery recovery = recoverer.Solve();
  out << "  " << recovery.BriefReport() << "\n  f(M) at M =";
  for (double m : {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9}) out << " " << Num(m);
  out << ":";
  for (double m : {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9})
    out << " " << Num(std::round(recovery.curve.Apply(m) * 1e4) / 1e4);
  out << "\n";
  return recovery;
}

FeatureOptions WithResponse(const FeatureOptions& options, const ResponseRecovery& recovery) {
  FeatureOptions out = options;
  out.inverse_response = recovery.curve;
  out.response_scope = ResponseScope::kAllPixels;
  return out;
}

namespace {

// The features a fit of `reader` uses: `options`, or with the camera response recovered from
// the brackets when `force` or the recording's recipe asks for it (`*recovered` says which).
FeatureOptions FitFeatureOptions(const RecordingReader& reader, const FeatureOptions& options,
                                 bool force, std::ostream& out, bool* recovered = nullptr) {
  const bool recover = force || RecipeAsksForResponse(reader);
  if (recovered != nullptr) *recovered = recover;
  return recover ? WithResponse(options, RecoverRecordingResponse(reader, options, out)) : options;
}

}  // namespace

// Fewer calibrated distances than Table 3's leave the I0-free Sigma model underdetermined
// between them (docs/estimator.md).
constexpr size_t kDenseDistances = 4;

namespace {

// Differences with a clean blob in both frames; throws when there is none.
int CountUsableSamples(const RecordingReader& reader,
                       const std::vector<CalibrationSample>& samples) {
  int usable = 0;
  for (const CalibrationSample& s : samples)
    usable += s.reference.Usable() && s.measurement.Usable();
  if (usable == 0) {
    throw RecordingError(reader.dir() + ": no usable calibration sample (" +
                         std::to_string(samples.size()) +
                         " differences, none with a clean blob in both frames); check the "
                         "exposures and the IRED current of the recipe.");
  }
  return usable;
}

void NoteSparseDistances(const std::vector<CalibrationSample>& samples, std::ostream& out) {
  std::set<double> distances;
  for (const CalibrationSample& s : samples) distances.insert(s.d_mm);
  if (distances.size() < kDenseDistances) {
    out << "  note: " << distances.size() << " calibrated distance"
        << (distances.size() == 1 ? "" : "s") << ": the Sigma model interpolates poorly between "
        << "so few (14% off halfway between 2 and 2.5 m on the virtual rig, against 0.1% with "
        << "Table 3's 4); the estimates lean on the apparent size there. Calibrate at "
        << kDenseDistances << " or more distances for the full accuracy.\n";
  }
}

// Usable frames of the usable differences: each measurement, and each distinct reference once.
int CountUsableFrames(const std::vector<CalibrationSample>& samples) {
  std::set<std::tuple<double, double, double, double>> references;
  int usable_frames = 0;
  for (const CalibrationSample& s : samples) {
    if (!s.reference.Usable() || !s.measurement.Usable()) continue;
    usable_frames +=
        1 + (references.insert({s.d_mm, s.theta_deg, s.bias_ma, s.t_ref_ms}).second ? 1 : 0);
  }
  return usable_frames;
}

// Unknowns of a model in its fitted form: its active coefficients and sigma.
int ModelUnknowns(ModelKind kind, const FitOptions& fit_options) {
  const bool free = kind == ModelKind::kFreeE || kind == ModelKind::kFreeSigma;
  const ModelSpec& spec = GetModelSpec(kind);
  int unknowns = 1;  // sigma
  for (int i = 0; i < spec.num_coefficients(); ++i) {
    unknowns += IsTermActive(spec, free ? fit_options.free_form : ModelForm::kFull, i) ? 1 : 0;
  }
  return unknowns;
}

// Models with more unknowns (coefficients + sigma) than observations are left out (a small
// recipe with fewer than 25 differences cannot determine the 24-term direct Sigma model); an
// undetermined I0-free model (Algorithm 1 needs both) is a RecordingError.
std::vector<ModelKind> DeterminedModels(const RecordingReader& reader,
                                        const std::vector<CalibrationSample>& samples, int usable,
                                        const FitOptions& fit_options, std::ostream& out) {
  const int usable_frames = CountUsableFrames(samples);
  std::vector<ModelKind> kept;
  for (ModelKind kind : fit_options.models) {
    const bool direct = kind == ModelKind::kDirectE || kind == ModelKind::kDirectF ||
                        kind == ModelKind::kDirectSigma;
    const int observations = direct ? usable_frames : usable;
    const int unknowns = ModelUnknowns(kind, fit_options);
    if (observations > unknowns) {
      kept.push_back(kind);
    } else if (kind == ModelKind::kFreeE || kind == ModelKind::kFreeSigma) {
      throw RecordingError(reader.dir() + ": " + std::to_string(observations) +
                           " usable differences cannot determine the " + ToString(kind) +
                           " model (" + std::to_string(unknowns) +
                           " unknowns); record more poses (recipes/table3-calibration.yaml).");
    } else {
      out << "  " << ToString(kind) << ": not fitted (" << observations << " observations for "
          << unknowns << " unknowns)\n";
    }
  }
  return kept;
}

void PrintFitSummaries(const CalibrationModel& model, const std::string& model_path,
                       std::ostream& out) {
  for (const FittedModel& m : model.models) {
    out << "  " << ToString(m.kind) << " (" << ToString(m.form) << "): " << m.summary.BriefReport()
        << "\n";
  }
  out << "  geometric: " << model.geometric.summary.BriefReport() << "\n";
  out << "Model: " << model_path << "\n";
}

// The calibration report; returns its index page.
std::string WriteCalibrationReport(const RecordingReader& reader,
                                   const std::vector<CalibrationSample>& samples,
                                   const CalibrationModel& model, const std::string& model_path,
                                   const std::string& report_dir) {
  std::ostringstream text;
  text << "Calibration from " << reader.dir() << "\n" << model.BriefReport() << "\n";
  return WriteReport(report_dir, "irdist calibration",
                     CalibrationReportFields(reader.dir(), model_path, model), text.str(),
                     CalibrationPlots(CalibrationPointsOf(model, samples), model));
}

}  // namespace

CalibrationModel FitRecording(const RecordingReader& reader, const FeatureMap& features,
                              const FeatureOptions& feature_options, const std::string& model_path,
                              const std::string& report_dir, std::ostream& out) {
  const std::vector<CalibrationSample> samples = SamplesFromRecording(reader, features);
  const int usable = CountUsableSamples(reader, samples);
  out << "Fitting " << samples.size() << " differences (" << usable << " usable) from "
      << reader.dir() << "\n";
  NoteSparseDistances(samples, out);
  FitOptions fit_options;
  fit_options.models = DeterminedModels(reader, samples, usable, fit_options, out);
  CalibrationModel model = Fit(samples, feature_options, fit_options);
  model.provenance = ProvenanceOfRecording(reader);
  SaveModel(model, model_path);
  PrintFitSummaries(model, model_path, out);
  if (!report_dir.empty()) {
    out << "Report: " << WriteCalibrationReport(reader, samples, model, model_path, report_dir)
        << "\n";
  }
  return model;
}

namespace {

// The health of an estimate at d_mm from its measurement frames (estimator/health.h).
HealthCheck HealthOfFrames(const CalibrationModel& model, double d_mm,
                           const std::vector<Features>& measurements) {
  std::vector<const Features*> frames;
  for (const Features& f : measurements) frames.push_back(&f);
  return CheckHealth(model, d_mm, frames);
}

// The range check's options for `model`: the calibration's error, its geometric fit's mean
// relative error (what the distance leans on), beside each estimate's own.
RangeOptions RangeOptionsOf(const CalibrationModel& model) {
  RangeOptions options;
  if (model.geometric.fitted()) {
    options.calibration_rel_error = std::max(model.geometric.summary.mean_relative_error, 0.0);
  }
  return options;
}

// A row from estimate `e` of the exposures (t_ref_ms, t_ms) taken in `frames`: its values, the
// calibrated ranges it lies outside, and whether it is an estimate at all.
void FillRow(const CalibrationModel& model, const DistanceEstimate& e, double t_ref_ms,
             const std::vector<double>& t_ms, const std::vector<const Features*>& frames,
             EstimateRow* row) {
  row->d_mm = e.d_mm;
  row->theta_deg = e.theta_deg;
  row->d_std_mm = e.d_std_mm;
  row->theta_std_deg = e.theta_std_deg;
  row->outside = OutsideRanges(model.ranges, e, t_ref_ms, t_ms, frames, RangeOptionsOf(model));
  row->outside_range = !row->outside.empty();
  // A fallback start (no root of Eq. 25 in range) is not a failure when the solver converged
  // from it; a non-converged solve is.
  row->ok = std::isfinite(e.d_mm) && e.d_mm > 0.0 && e.converged;
}

// Motion (estimator/estimate.h CheckMotion) of the joint row from its per-exposure rows.
MotionCheck MotionOfRows(const std::vector<EstimateRow>& per_dt, EstimateRow* joint) {
  if (!joint->ok) return MotionCheck{};
  std::vector<double> d_mm, d_se_mm;
  for (const EstimateRow& row : per_dt) {
    if (!row.ok) continue;
    d_mm.push_back(row.d_mm);
    d_se_mm.push_back(row.d_std_mm);
  }
  const MotionCheck m = CheckMotion(joint->d_mm, d_mm, d_se_mm);
  if (m.assessed) {
    joint->motion = m.moving ? "moving" : "static";
    joint->spread_mm = m.spread_mm;
  }
  return m;
}

// The rows of a bracket by one method before estimation: the joint (dt_ms = 0), then one per t_n.
std::vector<EstimateRow> EmptyRows(const std::string& method, const EstimateRow& base,
                                   const std::vector<Pair>& pairs) {
  std::vector<EstimateRow> rows(1 + pairs.size(), base);
  for (size_t k = 0; k < rows.size(); ++k) {
    rows[k].method = method;
    rows[k].ok = false;
    rows[k].dt_ms = k == 0 ? 0.0
                           : (pairs[k - 1].measurement->requested_exposure_us -
                              pairs[k - 1].reference->requested_exposure_us) /
                                 1000.0;
  }
  return rows;
}

// One method's rows for a bracket: the joint estimate (dt_ms = 0), then one row per t_n. With
// `checks`, the bracket's calibration health and motion (from this method's rows) go there.
void EstimateMethodRows(const CalibrationModel& model, const EstimateOptions& options,
                        const std::string& method, const EstimateRow& base,
                        const std::vector<Pair>& pairs, const FeatureMap& features, bool all_usable,
                        std::vector<EstimateRow>* out, BracketEstimateRows* checks = nullptr) {
  const FrameRecord& reference = *pairs.front().reference;
  std::vector<Features> measurements;
  std::vector<double> t_ms;
  std::vector<const Features*> frames;  // every frame of the bracket, for the signal's range
  for (const Pair& pair : pairs) {
    measurements.push_back(FeaturesOf(features, *pair.measurement));
    t_ms.push_back(pair.measurement->requested_exposure_us / 1000.0);
    frames.push_back(&FeaturesOf(features, *pair.reference));
    frames.push_back(&FeaturesOf(features, *pair.measurement));
  }
  std::vector<EstimateRow> rows = EmptyRows(method, base, pairs);
  DistanceEstimate none;  // without an estimate: the exposures' and the signal's ranges only
  none.d_mm = none.theta_deg = NAN;
  rows[0].outside = OutsideRanges(model.ranges, none, reference.requested_exposure_us / 1000.0,
                                  t_ms, frames);
  rows[0].outside_range = !rows[0].outside.empty();
  if (all_usable && measurements.size() <= static_cast<size_t>(kMaxBracketExposures)) {
    const double t_ref_ms = reference.requested_exposure_us / 1000.0;
    const BracketEstimate estimate = EstimateBracket(model, FeaturesOf(features, reference),
                                                     t_ref_ms, measurements, t_ms, options);
    FillRow(model, estimate.joint, t_ref_ms, t_ms, frames, &rows[0]);
    const HealthCheck health = HealthOfFrames(model, estimate.joint.d_mm, measurements);
    rows[0].health = health.Label();
    for (size_t k = 0; k < pairs.size(); ++k) {
      // Each t_n with the reference it is differenced with (interleaved brackets).
      const Features& ref = FeaturesOf(features, *pairs[k].reference);
      const double ref_ms = pairs[k].reference->requested_exposure_us / 1000.0;
      const DistanceEstimate e =
          pairs[k].reference == &reference
              ? estimate.per_exposure[k]
              : EstimatePair(model, ref, ref_ms, measurements[k], t_ms[k], options);
      FillRow(model, e, ref_ms, {t_ms[k]}, {&ref, &measurements[k]}, &rows[k + 1]);
    }
    const MotionCheck motion =
        MotionOfRows(std::vector<EstimateRow>(rows.begin() + 1, rows.end()), &rows[0]);
    if (checks != nullptr) {
      checks->health = health;
      checks->motion = motion;
    }
  }
  out->insert(out->end(), rows.begin(), rows.end());
}

}  // namespace

namespace {

// The I0-dependent comparison's row of a bracket; it assumes the calibration's mean current.
EstimateRow I0DependentRow(const CalibrationModel& model, const EstimateRow& base,
                           const std::vector<Pair>& pairs, const FeatureMap& features,
                           bool all_usable) {
  EstimateRow row = base;
  row.method = "i0_dependent";
  row.ok = false;
  if (!all_usable) return row;
  std::vector<Features> measurements;
  std::vector<double> t_ms;
  for (const Pair& pair : pairs) {
    measurements.push_back(FeaturesOf(features, *pair.measurement));
    t_ms.push_back(pair.measurement->requested_exposure_us / 1000.0);
  }
  const FrameRecord& reference = *pairs.front().reference;
  const I0DependentEstimate e =
      EstimateI0Dependent(model, FeaturesOf(features, reference),
                          reference.requested_exposure_us / 1000.0, measurements, t_ms,
                          model.scaling.i0_scale_ma);
  row.ok = e.valid;
  row.d_mm = e.d_mm;
  row.theta_deg = e.theta_deg;
  row.outside_range = e.outside_calibrated_range;
  if (row.outside_range) row.outside = {"distance"};
  return row;
}

// Geometric baseline: the mean over the measurement frames; theta from their ellipses.
EstimateRow GeometricRow(const CalibrationModel& model, const EstimateRow& base,
                         const std::vector<Pair>& pairs, const FeatureMap& features) {
  EstimateRow row = base;
  row.method = "geometric";
  double sum_d = 0.0, sum_theta = 0.0;
  int n = 0;
  bool outside = false;
  for (const Pair& pair : pairs) {
    const Features& f = FeaturesOf(features, *pair.measurement);
    if (!f.Usable()) continue;
    const GeometricEstimate g = EstimateGeometric(model, f);
    if (!g.valid) continue;
    sum_d += g.d_mm;
    sum_theta += f.theta0_deg;
    outside = outside || g.outside_calibrated_range;
    ++n;
  }
  row.ok = n > 0;
  row.d_mm = n > 0 ? sum_d / n : 0.0;
  row.theta_deg = n > 0 ? sum_theta / n : 0.0;
  row.outside_range = outside;
  if (outside) row.outside = {"distance"};
  return row;
}

// The bracket's row before estimation: its ids and ground truth. The truth is the geometry of
// the recorded pose; a recording without pan and tilt (NaN) keeps its slide and theta.
EstimateRow BaseRowOf(const RecordedBracket& bracket, const FrameRecord& first,
                      const CameraGeometry& geometry) {
  EstimateRow base;
  base.bracket = static_cast<int>(bracket.bracket_id);
  base.pose = static_cast<int>(bracket.bracket_id);
  base.repeat = first.repeat;
  base.true_d_mm = first.slide_mm;
  base.true_theta_deg = first.theta_deg;
  base.bias_ma = first.bias_ma_set;
  // The bracket's time: its last frame's arrival (the estimate's data complete then).
  const FrameRecord& last = bracket.frames.back();
  base.utc_ns = last.host_time_ns;
  base.host_monotonic_ns = last.host_monotonic_ns;
  base.camera_timestamp_ns = last.camera_timestamp_ns;
  const TrueGeometry truth =
      TrueGeometryOf(geometry, first.slide_mm, first.pan_deg, first.tilt_deg);
  if (std::isfinite(truth.d_mm)) {
    base.true_d_mm = truth.d_mm;
    base.true_theta_deg = truth.theta_deg;
    base.true_x_mm = truth.x_mm;
    base.true_y_mm = truth.y_mm;
    base.true_z_mm = truth.z_mm;
  }
  return base;
}

}  // namespace

namespace {

// The blob's centre in the sensor's pixels: the mean centroid of the measurement frames (NaN
// when some frame has no blob), with the standard error of that mean from their scatter (NaN
// with one frame).
BlobPoint BlobOf(const std::vector<Pair>& pairs, const FeatureMap& features,
                 const CameraGeometry& geometry) {
  std::vector<cv::Point2d> centroids;
  for (const Pair& pair : pairs) {
    const Features& f = FeaturesOf(features, *pair.measurement);
    if (!f.blob_found) return BlobPoint{NAN, NAN, NAN, NAN};
    centroids.push_back(f.centroid_px);
  }
  const double n = static_cast<double>(centroids.size());
  cv::Point2d mean(0.0, 0.0);
  for (const cv::Point2d& c : centroids) mean += c / n;
  BlobPoint blob{mean.x + geometry.roi_offset_x, mean.y + geometry.roi_offset_y, NAN, NAN};
  if (centroids.size() < 2) return blob;
  double su = 0.0, sv = 0.0;
  for (const cv::Point2d& c : centroids) {
    su += (c.x - mean.x) * (c.x - mean.x);
    sv += (c.y - mean.y) * (c.y - mean.y);
  }
  blob.u_se_px = std::sqrt(su / (n - 1.0) / n);
  blob.v_se_px = std::sqrt(sv / (n - 1.0) / n);
  return blob;
}

}  // namespace

CameraGeometry GeometryOfRecording(const RecordingReader& reader) {
  const RecordingHeader& h = reader.header();
  if (h.rig_text.empty()) return CameraGeometry{};
  return GeometryOfRigText(h.rig_text, h.rig_path.empty() ? reader.dir() + " (rig)" : h.rig_path);
}

BracketEstimateRows EstimateRecordedBracket(const RecordedBracket& bracket,
                                            const FeatureMap& features,
                                            const CalibrationModel& model,
                                            const CameraGeometry& geometry) {
  BracketEstimateRows rows;
  if (!bracket.complete) return rows;
  const std::vector<Pair> pairs = PairsOf(bracket);
  if (pairs.empty()) return rows;
  const EstimateRow base = BaseRowOf(bracket, *pairs.front().measurement, geometry);
  bool all_usable = true;
  for (const Pair& pair : pairs) {
    all_usable = all_usable && FeaturesOf(features, *pair.reference).Usable() &&
                 FeaturesOf(features, *pair.measurement).Usable();
  }
  EstimateMethodRows(model, EstimateOptions{}, "i0_free", base, pairs, features, all_usable,
                     &rows.i0_free, &rows);
  EstimateMethodRows(model, PaperEstimateOptions(), "paper", base, pairs, features, all_usable,
                     &rows.paper);
  if (model.Find(ModelKind::kDiffF) != nullptr) {
    rows.i0_dependent.push_back(I0DependentRow(model, base, pairs, features, all_usable));
  }
  if (model.geometric.fitted()) rows.geometric.push_back(GeometricRow(model, base, pairs, features));
  AddPositions(geometry, BlobOf(pairs, features, geometry),
               {&rows.i0_free, &rows.paper, &rows.i0_dependent, &rows.geometric});
  return rows;
}

std::vector<EstimateRow> FlattenRows(const BracketEstimateRows& bracket) {
  std::vector<EstimateRow> rows = bracket.i0_free;
  for (const auto* block : {&bracket.paper, &bracket.i0_dependent, &bracket.geometric}) {
    rows.insert(rows.end(), block->begin(), block->end());
  }
  return rows;
}

std::vector<std::string> ModelFitnessWarnings(const CalibrationModel& model,
                                              const std::string& model_path) {
  std::vector<std::string> out;
  const std::string head = "warning: model fitness (";
  if (!model.provenance.known) {
    out.push_back(head + "no_provenance): " + model_path +
                  " has no provenance: block, so its camera, ROI and bracket cannot be checked "
                  "against this one. Recalibrate with this build (irdist calibrate) to record it.");
  } else if (model.provenance.camera_serial.empty()) {
    out.push_back(head + "blank_serial): " + model_path +
                  " names no camera serial (provenance.camera_serial is blank), so it is accepted "
                  "for any camera. Write the calibration camera's serial there, or recalibrate.");
  }
  if (!model.blur_calibration.fitted()) {
    out.push_back(head + "no_fingerprint): " + model_path +
                  " has no calibrated blur (blur_calibration), the optics' fingerprint: neither "
                  "its optics nor the calibration's health can be checked. Recalibrate with this "
                  "build.");
  }
  return out;
}

std::string OpticsFingerprintWarning(const CalibrationModel& model, const HealthCheck& first,
                                     double d_mm) {
  if (!first.assessed || !first.flagged) return "";
  const CalibratedRanges& r = model.ranges;
  std::ostringstream out;
  out.precision(3);
  out << "warning: model fitness (optics_differ): the first bracket's blur is " << first.blur_var_px2
      << " px^2 at " << std::lround(d_mm) << " mm, the model's " << first.calibrated_px2
      << " px^2 there (its fingerprint:";
  for (double d : {r.d_min_mm, 0.5 * (r.d_min_mm + r.d_max_mm), r.d_max_mm}) {
    out << " " << std::lround(d) << " mm " << model.blur_calibration.BlurVarPx2(d) << " px^2";
  }
  out << "). The model was calibrated with other optics (another rig with this camera, another "
         "lens or focus): use that rig's model, restore the focus, or recalibrate.";
  return out.str();
}

std::string MotionWarning(int moving, int brackets) {
  return std::to_string(moving) + " of " + std::to_string(brackets) +
         " brackets flagged moving: their per-exposure distances disagree beyond their noise, "
         "the IRED moved while the bracket was taken. Hold it still during a bracket (a station "
         "settles after each move), or discard those estimates";
}

std::vector<EstimateRow> EstimateRecording(const RecordingReader& reader,
                                           const FeatureMap& features,
                                           const CalibrationModel& model) {
  std::vector<EstimateRow> all;
  HealthCheck health;
  const CameraGeometry geometry = GeometryOfRecording(reader);
  int brackets = 0, moving = 0;
  bool fingerprint_checked = false;
  for (const RecordedBracket& bracket : reader.Brackets()) {
    const BracketEstimateRows rows = EstimateRecordedBracket(bracket, features, model, geometry);
    if (rows.health.assessed && !fingerprint_checked) {
      fingerprint_checked = true;
      const std::string warning =
          OpticsFingerprintWarning(model, rows.health, rows.i0_free.front().d_mm);
      if (!warning.empty()) std::fprintf(stderr, "%s\n", warning.c_str());
    }
    if (rows.health.flagged && !health.flagged) health = rows.health;
    brackets += rows.i0_free.empty() ? 0 : 1;
    moving += rows.motion.moving ? 1 : 0;
    const std::vector<EstimateRow> flat = FlattenRows(rows);
    all.insert(all.end(), flat.begin(), flat.end());
  }
  if (health.flagged) {  // once per recording
    std::fprintf(stderr, "warning: calibration health: %s (estimates.csv column health).\n",
                 health.Advice().c_str());
  }
  if (moving > 0) {
    std::fprintf(stderr, "warning: %s (estimates.csv columns motion, spread_mm).\n",
                 MotionWarning(moving, brackets).c_str());
  }
  return all;
}

ValidationSummary WriteValidation(const std::string& dir, const std::vector<EstimateRow>& rows,
                                  const std::map<std::string, std::string>& context,
                                  std::ostream& out) {
  WriteEstimatesCsv(dir + "/estimates.csv", rows);
  ValidationSummary summary = Summarize(rows);
  const std::map<std::string, CrbFigures> crb = ValidationCrb(context, summary);
  WriteSummaryYaml(dir + "/summary.yaml", summary, context, crb);
  const std::string index =
      WriteReport(dir + "/report", "irdist validation",
                  ValidationReportFields(context, summary, crb), summary.BriefReport(),
                  ValidationPlots(rows, summary));
  out << summary.BriefReport() << "\n";
  out << "Estimates: " << dir << "/estimates.csv\nSummary: " << dir
      << "/summary.yaml\nReport: " << index << "\n";
  return summary;
}

void ProcessRecordingOnly(const std::string& run_dir, const FeatureOptions& options,
                          const FeatureMap& cache, std::ostream& out) {
  RequireCleanRecording(run_dir + "/recording");
  const RecordingReader reader(run_dir + "/recording");
  const FeatureMap features = RecordingFeatures(reader, options, cache);
  WriteFeaturesCsv(run_dir + "/features.csv", reader.rows(), features);
  out << "Recorded " << reader.rows().size()
      << " frames (recipe: after: none); features: " << run_dir << "/features.csv\n";
}

void ProcessCalibration(const std::string& run_dir, const FeatureOptions& options,
                        const FeatureMap& cache, std::ostream& out) {
  RequireCleanRecording(run_dir + "/recording");
  const RecordingReader reader(run_dir + "/recording");
  bool recovered = false;
  const FeatureOptions fit_options = FitFeatureOptions(reader, options, false, out, &recovered);
  // The live cache was computed without the curve: after a recovery every frame is recomputed.
  const FeatureMap features =
      RecordingFeatures(reader, fit_options, recovered ? FeatureMap{} : cache);
  WriteFeaturesCsv(run_dir + "/features.csv", reader.rows(), features);
  FitRecording(reader, features, fit_options, run_dir + "/model.yaml", run_dir + "/report", out);
}

void ProcessValidation(const std::string& run_dir, const CalibrationModel& model,
                       const std::map<std::string, std::string>& context, const FeatureMap& cache,
                       std::ostream& out) {
  RequireCleanRecording(run_dir + "/recording");
  const RecordingReader reader(run_dir + "/recording");
  const FeatureMap features =
      RecordingFeatures(reader, model.features, cache, BlobFitModelOf(model));
  WriteFeaturesCsv(run_dir + "/features.csv", reader.rows(), features);
  WriteValidation(run_dir, EstimateRecording(reader, features, model), context, out);
}

void RunFit(const FitArgs& args, CommandIo io) {
  const std::string writer = LiveWriterOf(args.recording);
  if (!writer.empty()) {
    throw RunFolderError(args.recording + " is being written by a live run (process " + writer +
                         "); fit it once that run has ended (or stop it and resume it).");
  }
  RequireCleanRecording(args.recording);
  const RecordingReader reader(args.recording);
  if (!reader.IsComplete()) {
    io.err << "warning: " << args.recording << " is " << CompletionName(reader.completion())
           << "; fitting its complete brackets.\n";
  }
  const std::string model_path =
      args.out.empty() ? ParentOf(args.recording) + "/model.yaml" : args.out;
  const std::string out_dir = ParentOf(model_path);
  RefuseExistingResults(out_dir, {fs::path(model_path).filename().string(), "features.csv", "report"},
                        args.force, "fit");
  RefuseLiveRun(out_dir, "fit");
  fs::create_directories(out_dir);
  const FeatureOptions options =
      FitFeatureOptions(reader, FeatureOptions{}, args.recover_response, io.out);
  const FeatureMap features = RecordingFeatures(reader, options);
  WriteFeaturesCsv(out_dir + "/features.csv", reader.rows(), features);
  FitRecording(reader, features, options, model_path, out_dir + "/report", io.out);
}

namespace {

bool HasGroundTruth(const std::vector<EstimateRow>& rows) {
  for (const EstimateRow& row : rows) {
    if (std::isfinite(row.true_d_mm)) return true;
  }
  return false;
}

}  // namespace

void RunPlayback(const PlaybackArgs& args, CommandIo io) {
  RequireCleanRecording(args.recording);
  const RecordingReader reader(args.recording);
  std::optional<CalibrationModel> model;
  if (!args.model.empty()) {
    model = LoadModel(args.model);
    std::string warning;
    CheckModelProvenance(model->provenance, args.model, ProvenanceOfRecording(reader),
                         "the recording " + args.recording, args.allow_model_mismatch, &warning);
    if (!warning.empty()) io.err << warning << "\n";
    for (const std::string& w : ModelFitnessWarnings(*model, args.model)) io.err << w << "\n";
  }
  const FeatureOptions options = model ? model->features : FeatureOptions{};
  const std::string out_dir = args.out_dir.empty() ? ParentOf(args.recording) : args.out_dir;
  RefuseExistingResults(out_dir, {"features.csv", "estimates.csv", "summary.yaml", "report"},
                        args.force, "playback");
  fs::create_directories(out_dir);
 const FeatureMap features =
      RecordingFeatures(reader, options, {}, model ? BlobFitModelOf(*model) : nullptr);
  WriteFeaturesCsv(out_dir + "/features.csv", reader.rows(), features);
  io.out << "Features: " << out_dir << "/features.csv (" << features.size() << " frames)\n";
  std::vector<EstimateRow> rows;
  if (model) {
    rows = EstimateRecording(reader, features, *model);
    if (HasGroundTruth(rows)) {
      WriteValidation(out_dir, rows,
                      {{"recipe", reader.header().recipe_path},
                       {"model", args.model},
                       {"recording", args.recording}},
                      io.out);
    } else {  // a recording of `irdist measure`: no ground truth to summarise against
      WriteEstimatesCsv(out_dir + "/estimates.csv", rows);
      io.out << "Estimates: " << out_dir << "/estimates.csv (no ground truth)\n";
    }
  }
  if (args.show) ShowPlayback(reader, features, rows);
}

namespace {

// `irdist check FILE`: an estimates.csv (irdist measure's, also after a crash): every row read, a
// torn last line dropped with a note.
void CheckEstimatesFile(const std::string& path, std::ostream& out) {
  std::string note;
  std::vector<EstimateRow> rows;
  try {
    rows = ReadEstimatesCsv(path, &note);
  } catch (const EstimatesFileError& e) {
    throw CheckFailedError(e.what());
  }
  std::set<int> brackets;
  for (const EstimateRow& row : rows) brackets.insert(row.bracket);
  out << path << ": " << rows.size() << " estimate rows of " << brackets.size() << " brackets";
  if (!brackets.empty()) out << " (" << *brackets.begin() << " to " << *brackets.rbegin() << ")";
  out << ", readable\n";
  if (!note.empty()) out << "note: " << note << "\n";
}

}  // namespace

void RunCheck(const CheckArgs& args, CommandIo io) {
  if (fs::is_regular_file(args.recording)) {
    CheckEstimatesFile(args.recording, io.out);
    return;
  }
  const RecordingCheck check = CheckRecording(args.recording);
  io.out << check.BriefReport() << "\n";
  if (!check.ok()) {
    throw CheckFailedError(args.recording + ": " + std::to_string(check.errors.size()) +
                           " error(s) in the recording (listed above).");
  }
}

}  // namespace irdist
