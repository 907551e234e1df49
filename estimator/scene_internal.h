#pragma once
// The scene pass's parts (estimator/scene.h), shared by scene.cc, scene_defects.cc,
// scene_segments.cc and scene_occlusion.cc. Estimator-internal: included by those files only.

#include <vector>

#include <opencv2/core.hpp>

// The public types, declared only: scene.h's unit includes this header (no cycle of units).
namespace irdist {
struct DefectMap;
struct SceneContext;
struct SceneOptions;
struct SceneReport;
}  // namespace irdist

namespace irdist::scene {

// The sensor's noise on this frame (EMVA 1288): var(g) = read_sd^2 + shot_gain (g - background),
// gray levels (DN).
struct NoiseModel {
  double background = 0.0;  // the frame's median
  double read_sd = 0.0;     // robust, from neighbouring pixels' differences
  double shot_gain = 0.0;   // DN of variance per DN of signal
  double Sd(double level) const;
};

// The background and the read noise, from every other row of the frame (histograms: O(pixels)).
NoiseModel MeasureBackgroundNoise(const cv::Mat& image, int bit_depth);
// The shot noise's gain from the brightest plateau's interior pixels (their departures from their
// 4 neighbours' mean); `fallback_dn` (at 12 bits, scaled to bit_depth) when there are too few.
void MeasureShotGain(const cv::Mat& image, const cv::Mat& median3, int bit_depth,
                     double fallback_dn, NoiseModel* noise);

// Pixels (255 in a CV_8U mask) that are outliers against their 8 neighbours (scene.h).
cv::Mat DetectDefects(const cv::Mat& image, const cv::Mat& median3, const NoiseModel& noise,
                      const SceneOptions& options);
// The known map's pixels that fall in the frame, set in *mask.
void AddKnownDefects(const DefectMap& map, cv::Point roi_origin, cv::Mat* mask);
// Each masked pixel of *image replaced by the median of its unmasked 8 neighbours (of all 8 when
// every one is masked); their coordinates appended to *where.
void ReplaceDefects(const cv::Mat& mask, cv::Mat* image, std::vector<cv::Point>* where);

// One connected component of the thresholded frame.
struct Blob {
  int label = 0;
  cv::Rect rect;
  int area = 0;
  double flux = 0.0;  // sum of (g - background), DN
  cv::Point2d centroid;
};
struct Segments {
  cv::Mat labels;  // CV_32S, 0 = background
  std::vector<Blob> blobs;
  int ired = -1;  // index into blobs; -1 when there is no blob
  double threshold = 0.0;
  double background = 0.0;  // the frame's (NoiseModel::background)
};
Segments Segment(const cv::Mat& image, const NoiseModel& noise, const SceneOptions& options,
                 const SceneContext& context);
// The segments after the defects were replaced in `cleaned`: a replaced pixel no longer above the
// threshold leaves its component, a component left empty (a hot pixel alone) is gone, and the
// IRED is picked again (cheaper than segmenting the frame again).
void ForgetDefects(const cv::Mat& cleaned, const std::vector<cv::Point>& defects,
                   const SceneOptions& options, const SceneContext& context, Segments* segments);
// A mask on a box of the frame (255 = set).
struct LocalMask {
  cv::Rect box;  // frame coordinates
  cv::Mat mask;  // CV_8U, box.size()
  bool Has(cv::Point p) const { return box.contains(p) && mask.at<uint8_t>(p - box.tl()) != 0; }
};
// The pixels of blob `b` grown by `reach_px` (on its box grown by as much, within the frame).
LocalMask GrownMask(const Segments& segments, const Blob& b, double reach_px, cv::Size frame);
// Every blob but the IRED replaced by its local background beyond the IRED's reach; the report's
// other_blobs, other_blob_rects, second_source and second_source_gap_px.
void MaskOtherBlobs(const Segments& segments, const SceneOptions& options,
                    const SceneContext& context, cv::Mat* image, SceneReport* report);

// The IRED's shape: a second source merged beyond its half-maximum ellipse (second_source, gap
// 0), and occlusion (occluded, occluded_edge_fraction).
void AssessShape(const cv::Mat& image, const Segments& segments, const NoiseModel& noise,
                 const SceneOptions& options, SceneReport* report);

}  // namespace irdist::scene
