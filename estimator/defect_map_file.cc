#include "estimator/defect_map_file.h"

#include <cmath>

namespace irdist::model_file {
namespace {

// The largest sensor coordinate a map may hold (checked before the cast to int).
constexpr double kMaxSensorPx = 1 << 20;

bool WholeInRange(double v) { return v == std::floor(v) && v >= 0.0 && v <= kMaxSensorPx; }

// One coordinate of a pixel: a whole sensor pixel.
int Coordinate(const Reader& rd, const YAML::Node& node, const std::string& at) {
  double v = -1.0;
  try {
    v = node.as<double>();
  } catch (const YAML::Exception&) {
    rd.Fail(node, at, "cannot read '" + node.Scalar() + "' as a number");
  }
  if (!WholeInRange(v)) rd.Fail(node, at, "expected whole sensor pixels >= 0");
  return static_cast<int>(v);
}

}  // namespace

void EmitDefectMap(YAML::Emitter& out, const DefectMap& map) {
  out << YAML::Key << "defect_map" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "roi_px" << YAML::Value << YAML::Flow << YAML::BeginSeq << map.roi.x
      << map.roi.y << map.roi.width << map.roi.height << YAML::EndSeq;
  out << YAML::Key << "pixels" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const cv::Point& p : map.sensor_px) {
    out << YAML::Flow << YAML::BeginSeq << p.x << p.y << YAML::EndSeq;
  }
  out << YAML::EndSeq << YAML::EndMap;
}

DefectMap ReadDefectMap(const Reader& rd, const YAML::Node& parent, const std::string& parent_key) {
  const std::string key = parent_key + ".defect_map";
  const YAML::Node node = rd.Child(parent, parent_key, "defect_map");
  rd.Keys(node, key, {"roi_px", "pixels"});
  DefectMap map;
  const std::vector<double> roi = rd.Doubles(node, key, "roi_px", false);
  if (roi.size() != 4 || !WholeInRange(roi[0]) || !WholeInRange(roi[1]) || !WholeInRange(roi[2]) ||
      !WholeInRange(roi[3])) {
    rd.Fail(node["roi_px"], key + ".roi_px", "expected [x, y, width, height], whole pixels >= 0");
  }
  map.roi = cv::Rect(static_cast<int>(roi[0]), static_cast<int>(roi[1]), static_cast<int>(roi[2]),
                     static_cast<int>(roi[3]));
  const YAML::Node pixels = rd.Child(node, key, "pixels");
  if (!pixels.IsSequence()) rd.Fail(pixels, key + ".pixels", "expected a sequence of [x, y]");
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const std::string at = key + ".pixels[" + std::to_string(i) + "]";
    const YAML::Node xy = pixels[i];
    if (!xy.IsSequence() || xy.size() != 2) rd.Fail(xy, at, "expected [x, y]");
    map.sensor_px.emplace_back(Coordinate(rd, xy[0], at), Coordinate(rd, xy[1], at));
  }
  return map;
}

}  // namespace irdist::model_file
