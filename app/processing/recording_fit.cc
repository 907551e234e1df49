#include "app/processing/recording_fit.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <ostream>
#include <set>
#include <sstream>
#include <tuple>
#include <utility>

#include "acquisition/recording_reader.h"
#include "app/inputs/provenance.h"
#include "app/inputs/recipe.h"
#include "app/processing/position.h"
#include "estimator/blob_fit.h"
#include "estimator/blur_level.h"
#include "estimator/defect_map.h"
#include "estimator/edge_correction.h"
#include "estimator/model_file.h"
#include "estimator/models.h"
#include "estimator/psf_anisotropy.h"
#include "estimator/round_blob.h"

namespace irdist {
namespace {

// The sample's known range and theta: the slide and the pose's theta, or, where the emitter sits
// off the pan and tilt axes' line (a virtual rig's emitter offset, a hardware rig's lever), the
// true range from the camera and theta from the line of sight (position.h TrueGeometryOf), which
// is what the frames turned onto the line of sight show.
void SetKnownGeometry(const CameraGeometry& g, const FrameRecord& row, CalibrationSample* s) {
  s->d_mm = row.slide_mm;
  s->theta_deg = std::fabs(row.theta_deg);
  const bool off_axis = g.emitter_offset_x_mm != 0.0 || g.emitter_offset_y_mm != 0.0 ||
                        g.lever_mm[0] != 0.0 || g.lever_mm[1] != 0.0 || g.lever_mm[2] != 0.0;
  if (!off_axis) return;
  const TrueGeometry t = TrueGeometryOf(g, row.slide_mm, row.pan_deg, row.tilt_deg);
  if (std::isfinite(t.d_mm) && std::isfinite(t.theta_deg)) {
    s->d_mm = t.d_mm;
    s->theta_deg = t.theta_deg;
  }
}

}  // namespace

std::vector<CalibrationSample> SamplesFromRecording(const RecordingReader& reader,
                                                    const FeatureMap& features) {
  std::vector<CalibrationSample> samples;
  const CameraGeometry geometry = GeometryOfRecording(reader);
  const std::vector<RecordedBracket> brackets = reader.Brackets();
  for (size_t pose = 0; pose < brackets.size(); ++pose) {
    const RecordedBracket& bracket = brackets[pose];
    if (!bracket.complete) continue;
    // The models read the camera turned onto the line of sight, as the estimates do.
    const FeatureMap turned = BracketOnLineOfSight(bracket, features, geometry);
    for (const DifferencePair& pair : DifferencePairsOf(bracket)) {
      CalibrationSample s;
      s.reference = FeaturesOf(turned, *pair.reference);
      s.measurement = FeaturesOf(turned, *pair.measurement);
      s.t_ref_ms = pair.reference->requested_exposure_us / 1000.0;
      s.t_ms = pair.measurement->requested_exposure_us / 1000.0;
      s.bias_ma = pair.measurement->bias_ma_set;
      SetKnownGeometry(geometry, *pair.measurement, &s);
      s.pose = static_cast<int>(pose);
      samples.push_back(s);
    }
  }
  return samples;
}

std::vector<FitnessPose> FitnessPosesOf(const RecordingReader& reader) {
  std::vector<FitnessPose> poses;
  for (const RecordedBracket& bracket : reader.Brackets()) {
    FitnessPose pose;
    if (!bracket.frames.empty()) {
      const FrameRecord& row = bracket.frames.front();
      pose = {row.slide_mm, row.pan_deg, row.tilt_deg, row.bias_ma_set};
    }
    poses.push_back(pose);
  }
  return poses;
}

std::string RejectedModelPath(const std::string& model_path) {
  const std::string yaml = ".yaml";
  const bool ends_yaml = model_path.size() >= yaml.size() &&
                         model_path.compare(model_path.size() - yaml.size(), yaml.size(), yaml) == 0;
  return (ends_yaml ? model_path.substr(0, model_path.size() - yaml.size()) : model_path) +
         ".rejected.yaml";
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
  for (double m : {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9}) out << " " << FeatureNumber(m);
  out << ":";
  for (double m : {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9})
    out << " " << FeatureNumber(std::round(recovery.curve.Apply(m) * 1e4) / 1e4);
  out << "\n";
  return recovery;
}

FeatureOptions WithResponse(const FeatureOptions& options, const ResponseRecovery& recovery) {
  FeatureOptions out = options;
  out.inverse_response = recovery.curve;
  out.response_scope = ResponseScope::kAllPixels;
  return out;
}

// The features a fit of `reader` uses: `options`, or with the camera response recovered from
// the brackets when `force` or the recording's recipe asks for it (`*recovered` says which).
FeatureOptions FitFeatureOptions(const RecordingReader& reader, const FeatureOptions& options,
                                 bool force, std::ostream& out, bool* recovered) {
  const bool recover = force || RecipeAsksForResponse(reader);
  if (recovered != nullptr) *recovered = recover;
  return recover ? WithResponse(options, RecoverRecordingResponse(reader, options, out)) : options;
}

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

// The optics' PSF anisotropy (estimator/psf_anisotropy.h) from the face-on frames' moments in the
// camera's own axes (a round disc: what anisotropy they show is the lens's), into the model.
void CalibratePsfAnisotropy(const RecordingReader& reader, const FeatureMap& features,
                            CalibrationModel* model, std::ostream& out) {
  std::vector<Features> face_on;
  for (const FrameRecord& row : reader.rows()) {
    const auto f = features.find(row.index);
    if (std::fabs(row.theta_deg) <= kPsfAnisotropyFaceOnDeg && f != features.end() &&
        f->second.Usable()) {
      face_on.push_back(f->second);
    }
  }
  const PsfAnisotropy psf = FitPsfAnisotropy(face_on);
  const double optics_px2 =
      model->blur_calibration.LeastOpticsVarPx2(model->ranges.d_min_mm, model->ranges.d_max_mm);
  const bool possible = PsfAnisotropyPossible(psf, optics_px2);
  const bool kept = SetPsfAnisotropy(psf, optics_px2, &model->blur_calibration);
  out << "  PSF anisotropy: " << psf.c_px2 << " +- " << psf.c_se_px2 << ", " << psf.s_px2
      << " +- " << psf.s_se_px2 << " px^2 ((Sxx - Syy) / 2, Sxy) from " << psf.frames
      << " face-on frames: "
      << (kept        ? "kept"
          : !possible ? "larger than the blur itself, not a lens's (a cut or dirty disc?): the "
                        "PSF taken as round"
                      : "within its noise, the PSF taken as round")
      << "\n";
}

// The most calibration frames the crosstalk's split and the blob fit's blur level (its offset's
// line) are refined on (estimator/blur_level.h), spread over the recording (Table 3's 256
// measurement frames all take part); the split itself is fitted on kBlurSplitFrames (blob_fit.h).
constexpr std::size_t kBlurLevelFrames = 512;

// Calls `use` with up to `most` of `rows` spread over them (every k-th) as FitBlurSplit's frames,
// one at a time (a full-frame recording's hundreds would not fit in memory at once): the scene's
// cleaned frame, its features less the PSF's anisotropy and the blob fit's blur at its distance.
template <typename Use>
void ForCrosstalkFrames(const RecordingReader& reader, const FeatureMap& features,
                        const std::vector<const FrameRecord*>& rows, std::size_t most,
                        const CalibrationModel& model, Use use) {
  const std::size_t stride = std::max<std::size_t>(1, rows.size() / most);
  std::size_t used = 0;
  for (std::size_t i = 0; i < rows.size() && used < most; i += stride) {
    Features f = features.at(rows[i]->index);  // its moments less the PSF's anisotropy
    RemovePsfAnisotropy(model.blur_calibration.psf_aniso_c_px2,
                        model.blur_calibration.psf_aniso_s_px2, &f);
    const double blur_var_px2 = BlobFitBlurVarPx2(model, f);
    if (!(blur_var_px2 > 0.0)) continue;
    const int bit_depth = reader.header().bit_depth;  // the frame FrameFeatures measured
    use(CrosstalkFrame{SceneCleanedFrame(reader.LoadImage(*rows[i]), bit_depth, model.features),
                       bit_depth, f, blur_var_px2,
                       model.geometric.DistanceMm(f.moment_major_var_px2)});
    ++used;
  }
}

// RefineBlurSplit's frames (up to kBlurLevelFrames, ForCrosstalkFrames), loaded and scene-cleaned
// once and kept while they fit in kKeptFrameBytes (a ROI recording's hundreds take a few MB);
// past that (full frames) each pass loads them again, one at a time.
constexpr std::size_t kKeptFrameBytes = std::size_t{256} << 20;
class RefinementFrames {
 public:
  RefinementFrames(const RecordingReader& reader, const FeatureMap& features,
                   const std::vector<const FrameRecord*>& rows, const CalibrationModel& model)
      : reader_(reader), features_(features), rows_(rows), model_(model) {}
  template <typename Use>
  void operator()(const Use& use) {
    if (loaded_ && all_kept_) {
      for (const CrosstalkFrame& f : kept_) use(f);
      return;
    }
    ForCrosstalkFrames(reader_, features_, rows_, kBlurLevelFrames, model_, [&](CrosstalkFrame f) {
      use(f);
      if (loaded_ || !all_kept_) return;
      bytes_ += f.image.total() * f.image.elemSize();
      all_kept_ = bytes_ <= kKeptFrameBytes;
      if (all_kept_) {
        kept_.push_back(std::move(f));
      } else {
        kept_ = {};
      }
    });
    loaded_ = true;
  }

 private:
  const RecordingReader& reader_;
  const FeatureMap& features_;
  const std::vector<const FrameRecord*>& rows_;
  const CalibrationModel& model_;
  std::vector<CrosstalkFrame> kept_;
  std::size_t bytes_ = 0;
  bool loaded_ = false, all_kept_ = true;
};

// The split of the calibrated blur into optics and crosstalk (estimator/blob_fit.h FitBlurSplit)
// from up to kBlurSplitFrames usable measurement frames, then refined with the blob fit's blur
// level on up to kBlurLevelFrames (RefineBlurSplit), each frame with the blob fit's blur at its
// distance; then the blob fit's edge correction learned on the same frames (LearnEdgeCorrection).
void CalibrateCrosstalk(const RecordingReader& reader, const FeatureMap& features,
                        CalibrationModel* model, std::ostream& out) {
  std::vector<const FrameRecord*> rows;
  for (const FrameRecord& row : reader.rows()) {
    const auto f = features.find(row.index);
    if (row.role == FrameRole::kMeasurement && f != features.end() && f->second.Usable()) {
      rows.push_back(&row);
    }
  }
  std::vector<CrosstalkFrame> frames;
  ForCrosstalkFrames(reader, features, rows, kBlurSplitFrames, *model,
                     [&](CrosstalkFrame f) { frames.push_back(std::move(f)); });
  const BlurSplit first = FitBlurSplit(frames);
  frames.clear();
  RefinementFrames refinement_frames(reader, features, rows, *model);
  const BlurSplit split = RefineBlurSplit(first, [&](const auto& use) { refinement_frames(use); });
  SetSplit(split, &model->blur_calibration);
  const BlurCalibration& b = model->blur_calibration;
  const double near_mm = model->ranges.d_min_mm, far_mm = model->ranges.d_max_mm;
  out << "  blur split: " << split.crosstalk_var_px2
      << " px^2 after the pixels (crosstalk; a lattice walk's share "
      << split.crosstalk_lattice_share << "), the rest before them (optics; their edge's excess "
      << "kurtosis " << split.optics_excess << "); the blob fit's blur " << std::showpos
      << b.FitBlurVarPx2(near_mm) - b.BlurVarPx2(near_mm) << " px^2 at " << std::noshowpos
      << std::lround(near_mm) << " mm, " << std::showpos
      << b.FitBlurVarPx2(far_mm) - b.BlurVarPx2(far_mm) << std::noshowpos << " px^2 at "
      << std::lround(far_mm) << " mm from the cumulants'; the split fitted on " << split.frames
      << " frames (" << first.crosstalk_var_px2 << " px^2), refined on "
      << (split.level_frames > 0 ? split.level_frames : split.frames) << "\n";
  const EdgeCorrectionFit edge = LearnEdgeCorrection(
      [&](const auto& use) { refinement_frames(use); }, &model->blur_calibration);
  out << "  edge correction: " << DescribeEdgeCorrection(edge) << "\n";
}

// The round-blob rule on each bracket's frames together, as measurement pools them
// (estimator/round_blob.h): the calibrated law then reads a near-round disc's size as the
// estimate will (one frame's rule leaves a round blob's noise in its major axis and shrinks a
// 5 deg blob's more).
void PoolBrackets(const RecordingReader& reader, FeatureMap* features) {
  for (const RecordedBracket& bracket : reader.Brackets()) {
    std::vector<Features*> frames;
    for (const FrameRecord& row : bracket.frames) {
      const auto f = features->find(row.index);
      if (f != features->end()) frames.push_back(&f->second);
    }
    PoolRoundBlobRule(frames);
  }
}

// The second pass of a calibration whose estimates use the blob fit: every frame's size from the
// blob fit with the first pass's calibrated blur and split (what measurement computes), and the
// models fitted again on those sizes, so the distance reads the size as measurement measures it
// (any smooth difference between the moments and the fit calibrates out).
// `*samples` become the refined ones (what the returned model was fitted on).
CalibrationModel RefitOnBlobFitSizes(const RecordingReader& reader, const FeatureMap& features,
                                     const FeatureOptions& feature_options,
                                     const FitOptions& fit_options, const CalibrationModel& first,
                                     std::vector<CalibrationSample>* samples, std::ostream& out) {
  FeatureMap refined = features;
  int replaced = 0;
  for (const FrameRecord& row : reader.rows()) {
    const auto f = refined.find(row.index);
    if (f == refined.end() || !f->second.Usable()) continue;
    const int bit_depth = reader.header().bit_depth;  // the frame FrameFeatures measured
    replaced += RefineWithBlobFit(
        SceneCleanedFrame(reader.LoadImage(row), bit_depth, feature_options), bit_depth, first,
        &f->second);
  }
  PoolBrackets(reader, &refined);
  *samples = SamplesFromRecording(reader, refined);
  CalibrationModel model = Fit(*samples, feature_options, fit_options);
  model.blur_calibration = first.blur_calibration;  // measured on the frames, unchanged
  out << "  sizes from the blob fit on " << replaced << " frames; models fitted again on them\n";
  return model;
}

// The most frames the defect map is found on (spread over the recording).
constexpr std::size_t kDefectMapFrames = 64;

// The sensor's defect map from up to kDefectMapFrames frames of the recording (estimator/
// defect_map.h), in the camera's ROI of the model's provenance (the full sensor when unknown).
DefectMap RecordingDefectMap(const RecordingReader& reader, const SceneOptions& scene,
                             const ModelProvenance& provenance, std::ostream& out) {
  DefectMapFinder finder(reader.header().bit_depth, scene);
  const std::vector<FrameRecord>& rows = reader.rows();
  const std::size_t stride = std::max<std::size_t>(1, rows.size() / kDefectMapFrames);
  for (std::size_t i = 0; i < rows.size(); i += stride) {
    cv::Mat image = reader.LoadImage(rows[i]);
    if (image.type() != CV_16UC1) image.convertTo(image, CV_16UC1);
    finder.Add(image);
  }
  const DefectMap map = finder.Map(cv::Rect(provenance.roi_offset_x, provenance.roi_offset_y,
                                            provenance.roi_width, provenance.roi_height));
  out << "  defect map: " << map.sensor_px.size() << " pixels flagged on most of "
      << finder.frames() << " frames\n";
  return map;
}

// A model written to model_path supersedes an earlier fit's rejected model beside it: removed, and
// said, so that the folder never shows a rejected model next to the one in use.
void RemoveSupersededRejectedModel(const std::string& model_path, std::ostream& out) {
  const std::string rejected = RejectedModelPath(model_path);
  std::error_code error;
  if (!std::filesystem::is_regular_file(std::filesystem::symlink_status(rejected, error))) return;
  if (std::filesystem::remove(rejected, error)) {
    out << "  removed " << rejected << " (an earlier fit's rejected model, superseded by "
        << model_path << ")\n";
  } else {
    out << "warning: could not remove " << rejected << " (an earlier fit's rejected model): "
        << error.message() << "\n";
  }
}

// A failing fit's warning, and unless kept, FitnessError.
void JudgeFitness(const RecordingReader& reader, const CalibrationFitness& fitness,
                  const std::string& model_path, bool keep_model, std::ostream& out) {
  if (fitness.passed) return;
  const std::string warning =
      "the model misses its own calibration frames beyond their noise (reduced chi-square " +
      FeatureNumber(fitness.reduced_chi2) + " > " + FeatureNumber(fitness.limit) + ", or a pose " +
      "beyond " + FeatureNumber(fitness.pose_limit) + "; worst: " +
      (fitness.worst.empty() ? std::string("none") : PoseText(fitness.worst.front().pose)) +
      "). Probable cause: " + fitness.cause;
  if (keep_model) {
    out << "warning: " << warning << ". Kept as asked (--keep-model): " << model_path << "\n";
    return;
  }
  throw FitnessError(warning + ". The model is written to " + RejectedModelPath(model_path) +
                     ", not to " + model_path + "; to keep it anyway: irdist fit " +
                     reader.dir() + " --out " + model_path + " --keep-model --force");
}

}  // namespace

CalibrationModel FitRecording(const RecordingReader& reader, const FeatureMap& features,
                              const FeatureOptions& feature_options, const std::string& model_path,
                              const CalibrationReportDrawer& draw_report, std::ostream& out,
                              bool keep_model) {
  std::vector<CalibrationSample> samples = SamplesFromRecording(reader, features);
  const int usable = CountUsableSamples(reader, samples);
  out << "Fitting " << samples.size() << " differences (" << usable << " usable) from "
      << reader.dir() << "\n";
  NoteSparseDistances(samples, out);
  FitOptions fit_options;
  fit_options.models = DeterminedModels(reader, samples, usable, fit_options, out);
  CalibrationModel model = Fit(samples, feature_options, fit_options);
  if (feature_options.blob_fit && model.geometric.fitted() && model.blur_calibration.fitted()) {
    CalibratePsfAnisotropy(reader, features, &model, out);
    CalibrateCrosstalk(reader, features, &model, out);
    const CalibrationModel first = model;
    model = RefitOnBlobFitSizes(reader, features, feature_options, fit_options, first, &samples,
                                out);
  }
  model.provenance = ProvenanceOfRecording(reader);
  if (feature_options.scene.enabled && feature_options.scene.detect_defects) {
    model.features.scene.defect_map =
        RecordingDefectMap(reader, model.features.scene, model.provenance, out);
  }
  model.fitness = AssessFitness(model, samples, FitnessPosesOf(reader));
  out << "  " << model.fitness.BriefReport() << "\n";
  const bool rejected = !model.fitness.passed && !keep_model;
  const std::string written_path = rejected ? RejectedModelPath(model_path) : model_path;
  SaveModel(model, written_path);
  if (!rejected) RemoveSupersededRejectedModel(model_path, out);
  PrintFitSummaries(model, written_path, out);
  if (draw_report) out << "Report: " << draw_report(model, samples, written_path) << "\n";
  JudgeFitness(reader, model.fitness, model_path, keep_model, out);
  return model;
}

}  // namespace irdist
