#pragma once
// 3D position of the IRED in the camera frame (x right along the sensor's rows, y down its
// columns, z along the optical axis; mm) from its image position and the estimated range: the
// blob's undistorted ray (cv::undistortPoints with the rig's intrinsics) times the range.

#include <cmath>
#include <initializer_list>
#include <string>
#include <vector>

#include "app/inputs/rig.h"
#include "app/processing/frame_features.h"
#include "estimator/features.h"

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
  // A virtual rig's emitter sits at (offset_x_mm, offset_y_mm, slide_mm) in the camera frame
  // whatever the pan and tilt (sim/scene.h: the disc turns about its own centre).
  bool virtual_rig = false;
  double emitter_offset_x_mm = 0.0, emitter_offset_y_mm = 0.0;
  // A hardware rig's `station.emitter_offset_mm` (app/inputs/rig.h): the emitter's centre from the
  // pan and tilt axes' crossing, in the mount's frame; it turns with the pan and tilt.
  double lever_mm[3] = {0.0, 0.0, 0.0};
};

// The true camera-IRED geometry of a station pose: the emitter's centre in the camera frame,
// its distance from the camera's centre (the pinhole) and the angle between the IRED's axis
// (after pan and tilt) and its line of sight to the camera. The axis is n = (sin(pan) cos(tilt),
// sin(tilt), -cos(pan) cos(tilt)) (pointing at the camera at pan = tilt = 0, as sim/scene.h);
// the mount turns the lever by the same rotation (R (0, 0, -1) = n). NaN when the pose is
// unknown (NaN slide, pan or tilt).
struct TrueGeometry {
  double x_mm = NAN, y_mm = NAN, z_mm = NAN;
  double d_mm = NAN;
  double theta_deg = NAN;
};
TrueGeometry TrueGeometryOf(const CameraGeometry& geometry, double slide_mm, double pan_deg,
                            double tilt_deg);

// From a rig file's text (as a recording stores it): the camera's intrinsics and ROI and, on a
// virtual rig, its `virtual.emitter.offset_x_mm/offset_y_mm`. Throws RecipeError for a rig file
// this build does not read.
CameraGeometry GeometryOfRigText(const std::string& text, const std::string& file);
// The geometry of the rig a recording was made on (its header's rig text).
CameraGeometry GeometryOfRecording(const RecordingReader& reader);

// A frame's features as the camera turned about its centre to look straight at the IRED sees
// them (estimator/line_of_sight.h), at the frame's blob centroid through the rig's intrinsics
// (distortion included): what the on-axis calibration's models read, so that an estimate is the
// range from the camera's centre and theta from the line of sight. Without intrinsics, or
// without a blob, the frame's own. The estimates and the calibration's samples both use it.
Features OnLineOfSight(const CameraGeometry& geometry, const Features& frame);
// The same for every frame of `bracket` found in `features`, each turned once.
FeatureMap BracketOnLineOfSight(const RecordedBracket& bracket, const FeatureMap& features,
                                const CameraGeometry& geometry);

struct EstimateRow;
// With intrinsics, fills x, y, z (and their standard errors) of every ok row of `blocks` (the
// estimates of one bracket, by method: ranges along the blob's ray, from features OnLineOfSight)
// from the blob's centre (sensor px). The rows' true_x/y/z come with their truth
// (TrueGeometryOf). The blob's ray is computed once.
void AddPositions(const CameraGeometry& geometry, const BlobPoint& blob,
                  std::initializer_list<std::vector<EstimateRow>*> blocks);

}  // namespace irdist
