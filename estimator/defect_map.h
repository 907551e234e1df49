#pragma once
// A sensor's defect map from a calibration recording (SceneOptions::defect_map, model.yaml
// features.defect_map): the pixels the scene pass's per-frame test (estimator/scene.h) finds an
// outlier against their neighbours in most frames. A hot or stuck pixel is one on every frame; a
// pixel that noise pushes over the test once in 1e7 frames never is. The map then masks them on
// every frame, also where a frame alone could not tell (a hot pixel as bright as the plateau).

#include <string>

#include <opencv2/core.hpp>

#include "estimator/scene.h"

namespace irdist {

struct DefectMapOptions {
  // A pixel enters the map when the per-frame test flags it in at least this share of the frames.
  double min_share = 0.5;
  // Fewer frames give no map (the share would not say much).
  int min_frames = 8;
  bool IsValid(std::string* why) const;
};

// Frames added one at a time (a recording is never held in memory), all of one size.
class DefectMapFinder {
 public:
  // scene: the per-frame test's options (SceneOptions::defect_sigmas and the rest).
  DefectMapFinder(int bit_depth, const SceneOptions& scene, const DefectMapOptions& options = {});
  // A CV_16UC1 frame; throws CheckError on another type or size than the first frame's.
  void Add(const cv::Mat& frame);
  int frames() const { return frames_; }
  // The map: frame coordinates plus roi.tl() (the frames' place on the sensor; an empty roi for
  // frames that are the sensor), with roi recorded in it. Empty below min_frames.
  DefectMap Map(const cv::Rect& roi) const;

 private:
  int bit_depth_;
  SceneOptions scene_;
  DefectMapOptions options_;
  cv::Mat counts_;  // CV_32S: the frames each pixel was flagged in
  int frames_ = 0;
};

}  // namespace irdist
