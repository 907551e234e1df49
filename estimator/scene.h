#pragma once
// The scene around the IRED's blob, measured through or named (docs/estimator.md, "The scene
// pass"). A real bench frame is not one disc on a dark sensor: hot and stuck pixels, a reflection
// of the IRED off the table, a second LED, a cable across the disc. The scene pass runs on each
// frame before the features and the blob fit (app/processing/frame_features.h FrameFeatures), so
// both read one cleaned frame, and says what it found (SceneReport, Features::scene):
//  1. Defect pixels: outliers against their 8 neighbours beyond what the sensor's noise (EMVA
//     1288: read noise + shot noise growing with the level, both measured on the frame) and a
//     blurred edge allow, plus a known defect map; each replaced by the median of its non-defect
//     neighbours (for every feature and the blob fit alike).
//  2. Other blobs: the frame thresholded above its background, connected components; the IRED is
//     the component of most flux (or the one nearest an expected centre); every other component,
//     grown by its halo's reach, is replaced by its local background (measured through) unless
//     its light reaches the IRED's (second_source: not measured through).
//  3. Occlusion: the IRED's half-maximum edge, found along rays from its centre, against an
//     ellipse fitted to it robustly: a disc whose edge departs from the ellipse is occluded.
// Plain types only: the lead's flags, estimates.csv, measure's JSON, Python, check and view read
// SceneReport as it is.

#include <limits>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace irdist {

// Defect pixels known before the frame (a calibration's map, estimator/defect_map_file.h): always
// replaced. Coordinates on the full sensor; `roi` is the sensor region the map was found in
// (empty: unknown, the map holds for any frame).
struct DefectMap {
  std::vector<cv::Point> sensor_px;
  cv::Rect roi;
  bool empty() const { return sensor_px.empty(); }
};

struct SceneOptions {
  // false: the frame goes to the features untouched (SceneReport::assessed = false).
  bool enabled = true;
  // Defects: a pixel departs from its neighbours by more than defect_sigmas noise sd (at the
  // neighbours' level) beyond what an edge allows. 5.5 sd: a clean frame's false alarms stay
  // well below 1e-4 per pixel (tests/estimator/scene_test.cc measures them).
  bool detect_defects = true;
  double defect_sigmas = 5.5;
  // The share of the neighbours' range (second brightest - second darkest) a pixel may depart
  // from their 3x3 median on a blurred edge: the curvature of a sharp disc's edge (blur 0.5 px
  // plus the pixel's area) moves an edge pixel ~0.1 of the edge's height from the median.
  double defect_edge_allowance = 0.15;
  // The shot noise's gain (variance in DN per DN above the background, at 12 bits) when the frame
  // has too few plateau pixels to measure it (0.39 DN/e-: a 10 ke- well on 12 bits).
  double fallback_shot_gain_dn = 0.39;
  // Segmentation: pixels above background + max(segment_sigmas x read noise sd,
  // segment_peak_fraction x (peak - background)) form the blobs (8-connected).
  bool segment = true;
  double segment_sigmas = 6.0;
  double segment_peak_fraction = 0.02;
  int min_blob_area_px = 2;  // smaller components are noise left after the defects (masked too)
  // How far a blob's light reaches beyond its thresholded pixels (px): a few blur sigmas. Another
  // blob grown by it is masked; two blobs whose reaches meet are one another's second source.
  double halo_reach_px = 2.0;
  // The IRED's light beyond its half-maximum ellipse (px, the blur's reach): component pixels
  // farther out belong to a second source merged with it.
  double merged_reach_px = 4.0;
  // Occlusion: the half-maximum edge sampled on occlusion_rays rays; an edge point departs when
  // its radial residual against the robust ellipse exceeds occlusion_residual_px (or the ray finds
  // no edge); occluded when at least occluded_min_fraction of the rays depart (in runs of at
  // least occlusion_min_run rays: noise departs one ray at a time).
  bool detect_occlusion = true;
  int occlusion_rays = 90;
  double occlusion_residual_px = 0.4;
  double occluded_min_fraction = 0.03;
  int occlusion_min_run = 3;
  double occlusion_min_radius_px = 3.0;  // smaller blobs: too few edge pixels to tell
  // Known defect pixels, always replaced: the calibration's map (estimator/defect_map.h
  // FindDefectMap; model.yaml features.defect_map), so it travels with the model's feature
  // options to every frame measured with them. Applied where the frame is its ROI (same size) or
  // the whole sensor (empty roi); elsewhere SceneContext::roi_origin places it.
  DefectMap defect_map;
  bool IsValid(std::string* why) const;
};

// Where the frame sits and what is known about it before it is seen.
struct SceneContext {
  const DefectMap* known_defects = nullptr;  // not owned; null: none (besides the options' map)
  bool roi_origin_known = false;             // roi_origin given (else taken from the map's roi)
  cv::Point roi_origin{0, 0};                // the frame's (0, 0) on the sensor
  bool has_expected_center = false;          // pick the component nearest expected_center_px
  cv::Point2d expected_center_px;            // frame coordinates
  int window_side_px = 64;                   // the features' window (FeatureOptions)
};

struct SceneReport {
  bool assessed = false;  // the pass ran (SceneOptions::enabled and a frame)
  // Defect pixels replaced inside the feature window (the detected and the known map's).
  int defect_pixels = 0;
  // Of them, within the blob fit's reach: the IRED's thresholded pixels grown by halo_reach_px
  // plus the blob fit's 2 px margin.
  int defect_pixels_near_blob = 0;
  // Every replaced defect pixel of the frame, frame coordinates (for display).
  std::vector<cv::Point> defect_px;
  // Other blobs masked out whose reach meets the feature window (measured through), and their
  // bounding boxes in the frame (for display).
  int other_blobs = 0;
  std::vector<cv::Rect> other_blob_rects;
  // Another blob's light reaches the IRED's (their reaches meet, or a dimmer blob merged into
  // the IRED's component beyond its half-maximum ellipse): the estimate is not trustworthy.
  bool second_source = false;
  // Edge-to-edge gap (px, between thresholded pixels) to the nearest other blob; 0 when merged;
  // NaN when there is none.
  double second_source_gap_px = std::numeric_limits<double>::quiet_NaN();
  // The disc's half-maximum edge departs from an ellipse on occluded_edge_fraction of its rays.
  bool occluded = false;
  double occluded_edge_fraction = 0.0;
  // The frame's background (median), normalised gray level (Features::background's measure).
  double ambient_level = 0.0;
  // The noise model measured on the frame (DN): read noise sd, shot gain (var per DN of signal).
  double read_noise_dn = 0.0;
  double shot_gain_dn = 0.0;
  // The IRED's component: intensity centroid (frame px); (-1, -1) when no blob was found.
  cv::Point2d blob_center_px{-1.0, -1.0};
  std::string BriefReport() const;
};

// A frame after the scene pass and what the pass found.
struct SceneFrame {
  cv::Mat image;  // CV_16UC1: the input itself when nothing was replaced or the pass is off
  SceneReport report;
};

// The scene pass on one frame. image: CV_16UC1 with bit_depth significant bits. Throws CheckError
// on a wrong type or invalid options.
SceneFrame CleanScene(const cv::Mat& image, int bit_depth, const SceneOptions& options,
                      const SceneContext& context = {});

}  // namespace irdist
