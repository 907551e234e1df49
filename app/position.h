#pragma once
// 3D position of the IRED in the camera frame (x right along the sensor's rows, y down its
// columns, z along the optical axis; mm) from its image position and the estimated range: the
// blob's undistorted ray (cv::undistortPoints with the rig's intrinsics) times the range.

#include <cmath>
#include <initializer_list>
#include <string>
#include <vector>

#include "app/rig.h"

namespace irdist {

struct Position3d {
  double x_mm = 0.0, y_mm = 0.0, z_mm = 0.0;
  // The range's standard error and the blob centre's, propagated (first order, through the
  // distortion). Along the ray the range dominates; across it, on the axis, only the centre's
  // counts (x_se = range x centre se / f).
  double x_se_mm = 0.0, y_se_mm = 0.0, z_se_mm = 0.0;
};

// The blob's centre in the full sensor's pixels (OpenCV convention: pixel centres at whole
// coordinates) and each coordinate's standard error (NaN: unknown, e.g. a bracket with a single
// measurement frame).
struct BlobPoint {
  double u_px = 0.0, v_px = 0.0;
  double u_se_px = NAN, v_se_px = NAN;
};

// `roi_offset_*`: the region's offset, used when the intrinsics are in ROI pixels. A negative or
// NaN `range_se_mm` gives NaN standard errors; an unknown centre se gives NaN x and y standard
// errors and z's from the range alone.
Position3d PositionFromRange(const CameraIntrinsics& intrinsics, int roi_offset_x,
                             int roi_offset_y, const BlobPoint& blob, double range_mm,
                             double range_se_mm);

// What turns a bracket's blob and range into a 3D position, and the position's ground truth.
struct CameraGeometry {
  CameraIntrinsics intrinsics;  // known == false: no 3D
  int roi_offset_x = 0, roi_offset_y = 0;
  // A virtual rig's emitter sits at (offset_x_mm, offset_y_mm, slide_mm) in the camera frame.
  bool virtual_rig = false;
  double emitter_offset_x_mm = 0.0, emitter_offset_y_mm = 0.0;
};

// From a rig file's text (as a recording stores it): the camera's intrinsics and ROI and, on a
// virtual rig, its `virtual.emitter.offset_x_mm/offset_y_mm`. Throws RecipeError for a rig file
// this build does not read.
CameraGeometry GeometryOfRigText(const std::string& text, const std::string& file);

struct EstimateRow;
// Fills x, y, z (and their standard errors) of every ok row of `blocks` (the estimates of one
// bracket, by method) from the blob's centre (sensor px) when the geometry has intrinsics, and
// true_x/y/z from the rows' true_d_mm on a virtual rig. The blob's ray is computed once.
void AddPositions(const CameraGeometry& geometry, const BlobPoint& blob,
                  std::initializer_list<std::vector<EstimateRow>*> blocks);

}  // namespace irdist
