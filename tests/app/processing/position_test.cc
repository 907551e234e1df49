// PositionFromRange: the blob's undistorted ray times the range, against pinhole geometry.
#include "app/processing/position.h"

#include <gtest/gtest.h>

#include <cmath>

namespace irdist {
namespace {

CameraIntrinsics Pinhole() {
  CameraIntrinsics k;
  k.known = true;
  k.fx_px = 3000.0;
  k.fy_px = 3000.0;
  k.cx_px = 639.5;
  k.cy_px = 511.5;
  return k;
}

TEST(PositionFromRange, OnTheAxisIsStraightAhead) {
  const Position3d p = PositionFromRange(Pinhole(), 0, 0, {639.5, 511.5, 0.02, 0.03}, 2000.0, 4.0);
  EXPECT_NEAR(p.x_mm, 0.0, 1e-9);
  EXPECT_NEAR(p.y_mm, 0.0, 1e-9);
  EXPECT_NEAR(p.z_mm, 2000.0, 1e-9);
  EXPECT_NEAR(p.z_se_mm, 4.0, 1e-9);
  // Across the ray on the axis only the centre's noise counts: range x se / f.
  EXPECT_NEAR(p.x_se_mm, 2000.0 * 0.02 / 3000.0, 1e-6);
  EXPECT_NEAR(p.y_se_mm, 2000.0 * 0.03 / 3000.0, 1e-6);
}

// Off the axis the range's error has a lateral share; a centre of unknown noise (one measurement
// frame) leaves x and y without a standard error rather than with the range's share alone.
TEST(PositionFromRange, StandardErrorsPropagateTheRangeAndTheCentre) {
  const double u = 639.5 + 300.0, v = 511.5;  // x / z = 0.1
  const Position3d range_only = PositionFromRange(Pinhole(), 0, 0, {u, v, 0.0, 0.0}, 2000.0, 4.0);
  EXPECT_NEAR(range_only.x_se_mm, 4.0 * 0.1 / std::sqrt(1.01), 1e-6);
  EXPECT_NEAR(range_only.z_se_mm, 4.0 / std::sqrt(1.01), 1e-6);
  const Position3d both = PositionFromRange(Pinhole(), 0, 0, {u, v, 0.05, 0.05}, 2000.0, 4.0);
  EXPECT_GT(both.x_se_mm, range_only.x_se_mm);
  EXPECT_NEAR(both.y_se_mm, 2000.0 * 0.05 / 3000.0 / std::sqrt(1.01), 1e-6);
  const Position3d unknown =
      PositionFromRange(Pinhole(), 0, 0, {u, v, std::nan(""), std::nan("")}, 2000.0, 4.0);
  EXPECT_TRUE(std::isnan(unknown.x_se_mm));
  EXPECT_TRUE(std::isnan(unknown.y_se_mm));
  EXPECT_NEAR(unknown.z_se_mm, range_only.z_se_mm, 1e-9);
}

TEST(PositionFromRange, OffAxisPointComesBackFromItsProjection) {
  // A point at (100, -60, 1800) mm projects to u = cx + f x / z, v = cy + f y / z.
  const double x = 100.0, y = -60.0, z = 1800.0;
  const double range = std::sqrt(x * x + y * y + z * z);
  const Position3d p =
      PositionFromRange(Pinhole(), 0, 0, {639.5 + 3000.0 * x / z, 511.5 + 3000.0 * y / z, 0.1, 0.1},
                        range, -1.0);
  EXPECT_NEAR(p.x_mm, x, 1e-6);
  EXPECT_NEAR(p.y_mm, y, 1e-6);
  EXPECT_NEAR(p.z_mm, z, 1e-6);
  EXPECT_TRUE(std::isnan(p.x_se_mm));
}

TEST(PositionFromRange, RoiPixelsAreShiftedByTheRegionsOffset) {
  CameraIntrinsics roi = Pinhole();
  roi.in_roi_px = true;
  roi.cx_px = 639.5 - 512.0;
  roi.cy_px = 511.5 - 384.0;
  const Position3d a = PositionFromRange(Pinhole(), 512, 384, {700.0, 450.0}, 2000.0, 1.0);
  const Position3d b = PositionFromRange(roi, 512, 384, {700.0, 450.0}, 2000.0, 1.0);
  EXPECT_NEAR(a.x_mm, b.x_mm, 1e-9);
  EXPECT_NEAR(a.y_mm, b.y_mm, 1e-9);
  EXPECT_GT(a.x_mm, 0.0);
  EXPECT_LT(a.y_mm, 0.0);
}

TEST(PositionFromRange, DistortionMovesTheRay) {
  CameraIntrinsics k = Pinhole();
  k.distortion = {-0.2, 0.0, 0.0, 0.0, 0.0};  // barrel: image points pulled in
  const Position3d plain = PositionFromRange(Pinhole(), 0, 0, {1000.0, 511.5}, 2000.0, 1.0);
  const Position3d barrel = PositionFromRange(k, 0, 0, {1000.0, 511.5}, 2000.0, 1.0);
  EXPECT_GT(barrel.x_mm, plain.x_mm);
}

// Ground truth from the geometry, by hand. The virtual offset rig: the emitter at (40, -30, 1500)
// mm, turned 10 deg in pan about its own centre. Distance sqrt(1500^2 + 40^2 + 30^2) =
// 1500.8331 mm; axis n = (sin 10, 0, -cos 10), line of sight -c / |c|: cos(theta) = (1500 cos 10 -
// 40 sin 10) / 1500.8331, theta = 11.5835 deg (not the station's 10: the line of sight is 1.9 deg
// off the optical axis).
TEST(TrueGeometryOf, VirtualOffsetEmitterTurnsAboutItsCentre) {
  CameraGeometry g;
  g.virtual_rig = true;
  g.emitter_offset_x_mm = 40.0;
  g.emitter_offset_y_mm = -30.0;
  const TrueGeometry t = TrueGeometryOf(g, 1500.0, 10.0, 0.0);
  EXPECT_NEAR(t.d_mm, 1500.8331, 1e-4);
  EXPECT_NEAR(t.theta_deg, 11.5835, 1e-4);
  EXPECT_DOUBLE_EQ(t.x_mm, 40.0);
  EXPECT_DOUBLE_EQ(t.y_mm, -30.0);
  EXPECT_DOUBLE_EQ(t.z_mm, 1500.0);
  // Centred: the station's own figures (slide, acos(cos pan cos tilt)).
  const TrueGeometry centred = TrueGeometryOf(CameraGeometry{}, 2000.0, 20.0, 10.0);
  EXPECT_NEAR(centred.d_mm, 2000.0, 1e-9);
  const double kDeg = 3.14159265358979323846 / 180.0;
  EXPECT_NEAR(centred.theta_deg, std::acos(std::cos(20 * kDeg) * std::cos(10 * kDeg)) / kDeg,
              1e-9);
}

// A hardware mount whose emitter sits 100 mm in front of the pan axis (towards the camera,
// station.emitter_offset_mm [0, 0, -100]), pan 30 deg at slide 2000: the emitter swings to
// (100 sin 30, 0, 2000 - 100 cos 30) = (50, 0, 1913.3975) mm, distance 1914.0506 mm, and its axis
// is 30 deg from -z towards +x while the line of sight is atan(50 / 1913.3975) = 1.4969 deg from
// -z towards -x: theta = 31.4969 deg.
TEST(TrueGeometryOf, HardwareLeverTurnsWithThePan) {
  CameraGeometry g;
  g.lever_mm[2] = -100.0;
  const TrueGeometry t = TrueGeometryOf(g, 2000.0, 30.0, 0.0);
  EXPECT_NEAR(t.x_mm, 50.0, 1e-9);
  EXPECT_NEAR(t.y_mm, 0.0, 1e-9);
  EXPECT_NEAR(t.z_mm, 1913.3975, 1e-4);
  EXPECT_NEAR(t.d_mm, 1914.0506, 1e-4);
  EXPECT_NEAR(t.theta_deg, 31.4969, 1e-4);
  EXPECT_TRUE(std::isnan(TrueGeometryOf(g, 2000.0, NAN, 0.0).d_mm));  // unknown pose
}

// The rig file's key reaches the geometry.
TEST(GeometryOfRigText, HardwareEmitterOffsetKey) {
  const CameraGeometry g = GeometryOfRigText(
      "name: r\nkind: hardware\nstation:\n  port: /dev/ttyUSB0\n  emitter_offset_mm: [1, 2, "
      "-3]\ncamera:\n  id: 10.0.0.2\n",
      "r.yaml");
  EXPECT_EQ(g.lever_mm[0], 1.0);
  EXPECT_EQ(g.lever_mm[1], 2.0);
  EXPECT_EQ(g.lever_mm[2], -3.0);
}

}  // namespace
}  // namespace irdist
