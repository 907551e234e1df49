#include "app/position.h"

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "app/summary.h"
#include "base/check.h"

namespace irdist {

Position3d PositionFromRange(const CameraIntrinsics& k, int roi_offset_x, int roi_offset_y,
                             double u_px, double v_px, double range_mm, double range_se_mm) {
  IRDIST_CHECK(k.known, "PositionFromRange needs intrinsics");
  const double du = k.in_roi_px ? roi_offset_x : 0.0;
  const double dv = k.in_roi_px ? roi_offset_y : 0.0;
  const cv::Matx33d camera(k.fx_px, 0.0, k.cx_px + du, 0.0, k.fy_px, k.cy_px + dv, 0.0, 0.0, 1.0);
  std::vector<double> distortion = k.distortion;
  distortion.resize(5, 0.0);
  const std::vector<cv::Point2d> image = {{u_px, v_px}};
  std::vector<cv::Point2d> normalised;
  cv::undistortPoints(image, normalised, camera, distortion);
  const double x = normalised.front().x, y = normalised.front().y;
  const double norm = std::sqrt(x * x + y * y + 1.0);
  Position3d p;
  p.x_mm = range_mm * x / norm;
  p.y_mm = range_mm * y / norm;
  p.z_mm = range_mm / norm;
  const double se = range_se_mm >= 0.0 ? range_se_mm : std::nan("");
  p.x_se_mm = se * std::fabs(x) / norm;
  p.y_se_mm = se * std::fabs(y) / norm;
  p.z_se_mm = se / norm;
  return p;
}

CameraGeometry GeometryOfRigText(const std::string& text, const std::string& file) {
  const Rig rig = ParseRig(text, file);
  CameraGeometry g;
  g.intrinsics = rig.camera.intrinsics;
  g.roi_offset_x = rig.camera.roi_offset_x;
  g.roi_offset_y = rig.camera.roi_offset_y;
  g.virtual_rig = rig.kind == RigKind::kVirtual;
  if (!g.virtual_rig) return g;
  // sim/ checked these keys when the rig started; here they are only the ground truth's offsets.
  const YAML::Node emitter = YAML::Load(text)["virtual"]["emitter"];
  if (emitter.IsMap()) {
    if (emitter["offset_x_mm"]) g.emitter_offset_x_mm = emitter["offset_x_mm"].as<double>();
    if (emitter["offset_y_mm"]) g.emitter_offset_y_mm = emitter["offset_y_mm"].as<double>();
  }
  return g;
}

void AddPositions(const CameraGeometry& geometry, double blob_u_px, double blob_v_px,
                  std::vector<EstimateRow>* rows) {
  for (EstimateRow& row : *rows) {
    if (geometry.virtual_rig && std::isfinite(row.true_d_mm)) {
      row.true_x_mm = geometry.emitter_offset_x_mm;
      row.true_y_mm = geometry.emitter_offset_y_mm;
      row.true_z_mm = row.true_d_mm;
    }
    if (!geometry.intrinsics.known || !row.ok || !std::isfinite(blob_u_px)) continue;
    const Position3d p =
        PositionFromRange(geometry.intrinsics, geometry.roi_offset_x, geometry.roi_offset_y,
                          blob_u_px, blob_v_px, row.d_mm, row.d_std_mm);
    row.x_mm = p.x_mm;
    row.y_mm = p.y_mm;
    row.z_mm = p.z_mm;
    row.x_se_mm = p.x_se_mm;
    row.y_se_mm = p.y_se_mm;
    row.z_se_mm = p.z_se_mm;
  }
}

}  // namespace irdist
