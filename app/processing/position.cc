#include "app/processing/position.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <optional>
#include <string>
#include <utility>
#include <opencv2/calib3d.hpp>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "acquisition/recording_reader.h"
#include "app/processing/estimates_csv.h"
#include "base/pi.h"
#include "estimator/line_of_sight.h"
#include "base/check.h"
#include "base/yaml_fields.h"

namespace irdist {

namespace {

// The unit ray of the image point (u, v) (sensor px): its undistorted normalised coordinates
// (x, y, 1), normalised.
cv::Vec3d RayOf(const cv::Matx33d& camera, const std::vector<double>& distortion, double u,
                double v) {
  const std::vector<cv::Point2d> image = {{u, v}};
  std::vector<cv::Point2d> normalised;
  cv::undistortPoints(image, normalised, camera, distortion);
  const cv::Vec3d ray(normalised.front().x, normalised.front().y, 1.0);
  return ray / cv::norm(ray);
}

// The camera matrix of `k` in the sensor's pixels (intrinsics in ROI pixels moved by its offset).
cv::Matx33d SensorCameraMatrix(const CameraIntrinsics& k, int roi_offset_x, int roi_offset_y) {
  const double du = k.in_roi_px ? roi_offset_x : 0.0;
  const double dv = k.in_roi_px ? roi_offset_y : 0.0;
  return cv::Matx33d(k.fx_px, 0.0, k.cx_px + du, 0.0, k.fy_px, k.cy_px + dv, 0.0, 0.0, 1.0);
}

std::vector<double> DistortionOf(const CameraIntrinsics& k) {
  std::vector<double> distortion = k.distortion;
  distortion.resize(5, 0.0);
  return distortion;
}

// What a position needs from the image: the blob's unit ray, its derivatives along u and v, and
// the centre's standard errors. One per bracket, whatever the number of estimates along it.
struct BlobRay {
  cv::Vec3d ray, ray_du, ray_dv;
  double u_se_px = NAN, v_se_px = NAN;
};

BlobRay RayOfBlob(const CameraIntrinsics& k, int roi_offset_x, int roi_offset_y,
                  const BlobPoint& blob) {
  IRDIST_CHECK(k.known, "PositionFromRange needs intrinsics");
  const cv::Matx33d camera = SensorCameraMatrix(k, roi_offset_x, roi_offset_y);
  const std::vector<double> distortion = DistortionOf(k);
  BlobRay r;
  r.ray = RayOf(camera, distortion, blob.u_px, blob.v_px);
  // Central differences of the ray along u and v (0.5 px: the distortion is smooth at that scale).
  constexpr double kStepPx = 0.5;
  r.ray_du = (RayOf(camera, distortion, blob.u_px + kStepPx, blob.v_px) -
              RayOf(camera, distortion, blob.u_px - kStepPx, blob.v_px)) /
             (2.0 * kStepPx);
  r.ray_dv = (RayOf(camera, distortion, blob.u_px, blob.v_px + kStepPx) -
              RayOf(camera, distortion, blob.u_px, blob.v_px - kStepPx)) /
             (2.0 * kStepPx);
  r.u_se_px = blob.u_se_px;
  r.v_se_px = blob.v_se_px;
  return r;
}

Position3d AlongRay(const BlobRay& r, double range_mm, double range_se_mm) {
  Position3d p;
  p.x_mm = range_mm * r.ray[0];
  p.y_mm = range_mm * r.ray[1];
  p.z_mm = range_mm * r.ray[2];
  const double se = range_se_mm >= 0.0 ? range_se_mm : std::nan("");
  const bool centre_known = std::isfinite(r.u_se_px) && std::isfinite(r.v_se_px);
  double* const out[3] = {&p.x_se_mm, &p.y_se_mm, &p.z_se_mm};
  for (int i = 0; i < 3; ++i) {
    const double along = r.ray[i] * se;
    const double across_u = range_mm * r.ray_du[i] * r.u_se_px;
    const double across_v = range_mm * r.ray_dv[i] * r.v_se_px;
    if (centre_known) {
      *out[i] = std::sqrt(along * along + across_u * across_u + across_v * across_v);
    } else {
      *out[i] = i == 2 ? std::fabs(along) : std::nan("");
    }
  }
  return p;
}

}  // namespace

Features OnLineOfSight(const CameraGeometry& g, const Features& frame) {
  if (!g.intrinsics.known || !frame.blob_found) return frame;
  const cv::Matx33d camera = SensorCameraMatrix(g.intrinsics, g.roi_offset_x, g.roi_offset_y);
  const std::vector<double> distortion = DistortionOf(g.intrinsics);
  const cv::Point2d to_sensor(g.roi_offset_x, g.roi_offset_y);
  const RayOfPixel ray_of = [&](const cv::Point2d& frame_px) {
    const cv::Point2d p = frame_px + to_sensor;
    return RayOf(camera, distortion, p.x, p.y);
  };
  const LineOfSight view =
      LineOfSightAt(ray_of, frame.centroid_px, g.intrinsics.fx_px, g.intrinsics.fy_px);
  return ToLineOfSight(frame, view);
}

FeatureMap BracketOnLineOfSight(const RecordedBracket& bracket, const FeatureMap& features,
                                const CameraGeometry& geometry) {
  FeatureMap turned;
  for (const FrameRecord& row : bracket.frames) {
    const auto f = features.find(row.index);
    if (f != features.end()) turned[row.index] = OnLineOfSight(geometry, f->second);
  }
  return turned;
}

CameraGeometry GeometryOfRecording(const RecordingReader& reader) {
  const RecordingHeader& h = reader.header();
  if (h.rig_text.empty()) return CameraGeometry{};
  return GeometryOfRigText(h.rig_text, h.rig_path.empty() ? reader.dir() + " (rig)" : h.rig_path);
}

Position3d PositionFromRange(const CameraIntrinsics& k, int roi_offset_x, int roi_offset_y,
                             const BlobPoint& blob, double range_mm, double range_se_mm) {
  return AlongRay(RayOfBlob(k, roi_offset_x, roi_offset_y, blob), range_mm, range_se_mm);
}

CameraGeometry GeometryOfRigText(const std::string& text, const std::string& file) {
  const Rig rig = ParseRig(text, file);
  CameraGeometry g;
  g.intrinsics = rig.camera.intrinsics;
  g.roi_offset_x = rig.camera.roi_offset_x;
  g.roi_offset_y = rig.camera.roi_offset_y;
  g.virtual_rig = rig.kind == RigKind::kVirtual;
  for (int i = 0; i < 3; ++i) g.lever_mm[i] = rig.station.emitter_offset_mm[i];
  if (!g.virtual_rig) return g;
  // sim/ checked these keys when the rig started; here they are only the ground truth's offsets.
  const YAML::Node root = yaml_fields::Parse(text, file);  // a map: ParseRig read it
  const YAML::Node virt = root["virtual"];
  const YAML::Node emitter = virt.IsMap() ? virt["emitter"] : YAML::Node();
  if (emitter.IsMap()) {
    for (const auto& [key, offset_mm] : {std::pair{"offset_x_mm", &g.emitter_offset_x_mm},
                                         std::pair{"offset_y_mm", &g.emitter_offset_y_mm}}) {
      const YAML::Node value = emitter[key];
      const std::string what = std::string("virtual.emitter.") + key;
      if (value) *offset_mm = yaml_fields::AsNumber(value, file, what);
    }
  }
  return g;
}

TrueGeometry TrueGeometryOf(const CameraGeometry& g, double slide_mm, double pan_deg,
                            double tilt_deg) {
  TrueGeometry t;
  if (!std::isfinite(slide_mm) || !std::isfinite(pan_deg) || !std::isfinite(tilt_deg)) return t;
  constexpr double kDeg = kPi / 180.0;
  const cv::Matx33d tilt_about_x(1, 0, 0, 0, std::cos(tilt_deg * kDeg), -std::sin(tilt_deg * kDeg),
                                 0, std::sin(tilt_deg * kDeg), std::cos(tilt_deg * kDeg));
  const double p = -pan_deg * kDeg;
  const cv::Matx33d pan_about_y(std::cos(p), 0, std::sin(p), 0, 1, 0, -std::sin(p), 0,
                                std::cos(p));
  const cv::Matx33d mount = pan_about_y * tilt_about_x;  // mount * (0, 0, -1) = the IRED's axis
  const cv::Vec3d centre = cv::Vec3d(g.emitter_offset_x_mm, g.emitter_offset_y_mm, slide_mm) +
                           mount * cv::Vec3d(g.lever_mm[0], g.lever_mm[1], g.lever_mm[2]);
  const cv::Vec3d axis = mount * cv::Vec3d(0.0, 0.0, -1.0);
  t.x_mm = centre[0];
  t.y_mm = centre[1];
  t.z_mm = centre[2];
  t.d_mm = cv::norm(centre);
  const double cos_theta = -axis.dot(centre) / t.d_mm;  // the line of sight is -centre
  t.theta_deg = std::acos(std::max(-1.0, std::min(1.0, cos_theta))) / kDeg;
  return t;
}

void AddPositions(const CameraGeometry& geometry, const BlobPoint& blob,
                  std::initializer_list<std::vector<EstimateRow>*> blocks) {
  std::optional<BlobRay> ray;  // once, at the first row that needs it
  for (std::vector<EstimateRow>* rows : blocks) {
    for (EstimateRow& row : *rows) {
      if (!geometry.intrinsics.known || !row.ok || !std::isfinite(blob.u_px)) continue;
      if (!ray) {
        ray = RayOfBlob(geometry.intrinsics, geometry.roi_offset_x, geometry.roi_offset_y, blob);
      }
      // The estimate is the range along the blob's ray: its features were those of the camera
      // turned onto the ray (OnLineOfSight), where the calibration's on-axis geometry holds.
      const Position3d p = AlongRay(*ray, row.d_mm, row.d_std_mm);
      row.x_mm = p.x_mm;
      row.y_mm = p.y_mm;
      row.z_mm = p.z_mm;
      row.x_se_mm = p.x_se_mm;
      row.y_se_mm = p.y_se_mm;
      row.z_se_mm = p.z_se_mm;
    }
  }
}

}  // namespace irdist
