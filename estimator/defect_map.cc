#include "estimator/defect_map.h"

#include <opencv2/imgproc.hpp>

#include "base/check.h"
#include "estimator/scene_internal.h"

namespace irdist {

bool DefectMapOptions::IsValid(std::string* why) const {
  if (!(min_share > 0.0 && min_share <= 1.0)) {
    if (why != nullptr) *why = "defect map min_share must be in (0, 1]";
    return false;
  }
  if (min_frames < 1) {
    if (why != nullptr) *why = "defect map min_frames must be >= 1";
    return false;
  }
  return true;
}

DefectMapFinder::DefectMapFinder(int bit_depth, const SceneOptions& scene,
                                 const DefectMapOptions& options)
    : bit_depth_(bit_depth), scene_(scene), options_(options) {
  std::string why;
  IRDIST_CHECK(scene.IsValid(&why), why);
  IRDIST_CHECK(options.IsValid(&why), why);
  IRDIST_CHECK(bit_depth >= 8 && bit_depth <= 16, "bit_depth must be in [8,16], got ", bit_depth);
}

void DefectMapFinder::Add(const cv::Mat& frame) {
  IRDIST_CHECK(frame.type() == CV_16UC1 && frame.rows >= 3 && frame.cols >= 3,
               "DefectMapFinder needs CV_16UC1 frames of 3 x 3 px or more");
  if (counts_.empty()) counts_ = cv::Mat::zeros(frame.size(), CV_32S);
  IRDIST_CHECK(frame.size() == counts_.size(), "DefectMapFinder: frames of different sizes");
  scene::NoiseModel noise = scene::MeasureBackgroundNoise(frame, bit_depth_);
  cv::Mat median3;
  cv::medianBlur(frame, median3, 3);
  scene::MeasureShotGain(frame, median3, bit_depth_, scene_.fallback_shot_gain_dn, &noise);
  const cv::Mat flagged = scene::DetectDefects(frame, median3, noise, scene_);
  cv::add(counts_, cv::Scalar(1), counts_, flagged);
  ++frames_;
}

DefectMap DefectMapFinder::Map(const cv::Rect& roi) const {
  DefectMap map;
  map.roi = roi;
  if (frames_ < options_.min_frames) return map;
  const double needed = options_.min_share * frames_;
  for (int y = 0; y < counts_.rows; ++y) {
    const int* row = counts_.ptr<int>(y);
    for (int x = 0; x < counts_.cols; ++x) {
      if (row[x] >= needed) map.sensor_px.emplace_back(x + roi.x, y + roi.y);
    }
  }
  return map;
}

}  // namespace irdist
