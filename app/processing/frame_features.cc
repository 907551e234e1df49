#include "app/processing/frame_features.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "acquisition/pixel_format.h"
#include "acquisition/recording_reader.h"
#include "base/safe_file.h"
#include "estimator/blob_fit.h"
#include "estimator/refocus.h"

namespace irdist {

std::string FeatureNumber(double value) {
  if (!std::isfinite(value)) return "nan";
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.10g", value);
  return buffer;
}

std::vector<DifferencePair> DifferencePairsOf(const RecordedBracket& bracket) {
  std::vector<DifferencePair> pairs;
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

int BitDepthOfPixelFormat(const std::string& pixel_format) {
  const PixelFormatInfo* format = FindPixelFormat(pixel_format);  // packed ones too (Mono12p)
  return format == nullptr ? 16 : format->bit_depth;
}

void CheckFrameHoldsWindow(const cv::Mat& image, const FeatureOptions& options) {
  const int side_px = options.window_side_px;
  if (image.cols >= side_px && image.rows >= side_px) return;
  throw FeatureWindowError(
      "a frame of " + std::to_string(image.cols) + " x " + std::to_string(image.rows) +
      " px (width x height) is smaller than the features' window, features.window_side_px " +
      std::to_string(side_px) + " (" + std::to_string(side_px) + " x " + std::to_string(side_px) +
      " px): use the model on frames of the ROI it was calibrated on, or calibrate one on this "
      "ROI with features.window_side_px at most " +
      std::to_string(std::min(image.cols, image.rows)) + " (docs/recipes.md, Bounds)");
}

namespace {

// The scene pass, on a frame that holds the window (refused before it otherwise).
SceneFrame SceneOf(const cv::Mat& image, int bit_depth, const FeatureOptions& options,
                   const SceneContext* scene) {
  CheckFrameHoldsWindow(image, options);
  SceneContext context = scene != nullptr ? *scene : SceneContext();
  context.window_side_px = options.window_side_px;
  return CleanScene(image, bit_depth, options.scene, context);
}

}  // namespace

Features FrameFeatures(const cv::Mat& image, int bit_depth, const FeatureOptions& options,
                       const CalibrationModel* blob_fit_model, const SceneContext* scene,
                       PendingOwnBlur* later) {
  const SceneFrame cleaned = SceneOf(image, bit_depth, options, scene);
  Features features = ComputeFeatures(cleaned.image, bit_depth, options);
  if (later != nullptr) *later = PendingOwnBlur();
  if (blob_fit_model != nullptr) {
    const Features moments = features;
    if (RefineWithBlobFit(cleaned.image, bit_depth, *blob_fit_model, &features)) {
      if (later != nullptr) {
        *later = {cleaned.image, bit_depth, moments, blob_fit_model};
      } else {
        MeasureOwnBlur(cleaned.image, bit_depth, *blob_fit_model, moments, &features);
      }
    }
  }
  features.scene = cleaned.report;
  return features;
}

bool MeasurePendingOwnBlur(PendingOwnBlur* pending, Features* features) {
  const CalibrationModel* model = pending->model;
  const bool measured = model != nullptr && MeasureOwnBlur(pending->cleaned, pending->bit_depth,
                                                           *model, pending->moments, features);
  *pending = PendingOwnBlur();
  return measured;
}

cv::Mat SceneCleanedFrame(const cv::Mat& image, int bit_depth, const FeatureOptions& options,
                          const SceneContext* scene) {
  return SceneOf(image, bit_depth, options, scene).image;
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
        << ',' << FrameRoleName(row.role) << ',' << FeatureNumber(row.requested_exposure_us) << ','
        << FeatureNumber(row.bias_ma_set) << ',' << FeatureNumber(row.slide_mm) << ','
        << FeatureNumber(row.theta_deg) << ',' << (f.blob_found ? 1 : 0) << ','
        << (f.Usable() ? 1 : 0) << ',' << f.saturated_pixels << ',' << (f.touches_border ? 1 : 0)
        << ',' << (f.blob_clipped_by_roi ? 1 : 0) << ',' << f.roi.x << ',' << f.roi.y << ','
        << f.roi.width << ',' << f.roi.height << ',' << f.roi_area_px << ','
        << FeatureNumber(f.background) << ',' << FeatureNumber(f.peak) << ','
        << FeatureNumber(f.e_rel) << ',' << FeatureNumber(f.f00) << ',' << FeatureNumber(f.sigma)
        << ',' << FeatureNumber(f.centroid_px.x) << ',' << FeatureNumber(f.centroid_px.y) << ','
        << FeatureNumber(e.major_px) << ',' << FeatureNumber(e.minor_px) << ','
        << FeatureNumber(e.angle_deg) << ',' << FeatureNumber(f.theta0_deg) << '\n';
  }
  // Whole or not at all: a features.csv cut by a full disk would read as a finished result.
  std::string why;
  if (!WriteFileAtomically(path, out.str(), 0644, &why)) {
    throw RecordingError(path + ": " + why + "; free space or check the folder is writable.");
  }
}

}  // namespace irdist
