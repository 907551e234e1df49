#pragma once
// PROVISIONAL (the lead's placeholder until the scene pass lands; replaced by scene-detect).
#include <cmath>
#include <vector>

#include <opencv2/core.hpp>

namespace irdist {

struct SceneReport {
  bool assessed = false;
  int defect_pixels = 0;
  int defect_pixels_near_blob = 0;
  std::vector<cv::Point> defect_px;
  int other_blobs = 0;
  std::vector<cv::Rect> other_blob_rects;
  bool second_source = false;
  double second_source_gap_px = NAN;
  bool occluded = false;
  double occluded_edge_fraction = 0.0;
};

}  // namespace irdist
