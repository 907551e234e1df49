#include "estimator/defect_map_file.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "estimator/model_file_error.h"

namespace irdist::model_file {
namespace {

// model.yaml's features section holding only the map, as the model file writes it.
std::string Emitted(const DefectMap& map) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  EmitDefectMap(out, map);
  out << YAML::EndMap;
  return out.c_str();
}

DefectMap Read(const std::string& features_yaml) {
  const Reader rd("m.yaml");
  return ReadDefectMap(rd, YAML::Load(features_yaml), "features");
}

// The error Read throws on `features_yaml` (an empty error when it throws none).
ModelFileError Refusal(const std::string& features_yaml) {
  try {
    Read(features_yaml);
  } catch (const ModelFileError& e) {
    return e;
  }
  ADD_FAILURE() << "accepted: " << features_yaml;
  return ModelFileError("", "", 0, "");
}

void ExpectRefused(const std::string& features_yaml, const std::string& key,
                   const std::string& problem) {
  const ModelFileError e = Refusal(features_yaml);
  EXPECT_EQ(e.key(), key) << features_yaml;
  EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
  EXPECT_NE(std::string(e.what()).find("m.yaml"), std::string::npos) << e.what();
}

// The file's layout (defect_map_file.h): roi_px as [x, y, width, height], pixels as [x, y] pairs
// in sensor coordinates, in the map's order.
TEST(DefectMapFile, WritesTheDocumentedLayout) {
  DefectMap map;
  map.roi = cv::Rect(320, 256, 640, 512);
  map.sensor_px = {{330, 300}, {331, 300}, {900, 700}};
  const YAML::Node node = YAML::Load(Emitted(map))["defect_map"];
  ASSERT_TRUE(node.IsMap());
  EXPECT_EQ(node.size(), 2u);
  EXPECT_EQ(node["roi_px"].as<std::vector<int>>(), (std::vector<int>{320, 256, 640, 512}));
  const YAML::Node pixels = node["pixels"];
  ASSERT_EQ(pixels.size(), 3u);
  EXPECT_EQ(pixels[0].as<std::vector<int>>(), (std::vector<int>{330, 300}));
  EXPECT_EQ(pixels[1].as<std::vector<int>>(), (std::vector<int>{331, 300}));
  EXPECT_EQ(pixels[2].as<std::vector<int>>(), (std::vector<int>{900, 700}));
}

TEST(DefectMapFile, ReadsAHandWrittenMap) {
  const DefectMap map = Read(
      "defect_map:\n"
      "  roi_px: [8, 16, 1280, 1024]\n"
      "  pixels: [[0, 0], [1279, 5], [17, 1023.0]]\n");
  EXPECT_EQ(map.roi, cv::Rect(8, 16, 1280, 1024));
  EXPECT_EQ(map.sensor_px, (std::vector<cv::Point>{{0, 0}, {1279, 5}, {17, 1023}}));
}

// A map found on frames of unknown place (an empty roi) and one with no pixels survive the trip.
TEST(DefectMapFile, RoundTripsEmptyRoiAndEmptyMap) {
  DefectMap whole;
  whole.sensor_px = {{5, 7}, {1 << 20, 0}};  // the largest coordinate the reader takes
  const DefectMap back = Read(Emitted(whole));
  EXPECT_EQ(back.sensor_px, whole.sensor_px);
  EXPECT_TRUE(back.roi.empty());
  const DefectMap none = Read(Emitted(DefectMap()));
  EXPECT_TRUE(none.empty());
  EXPECT_EQ(none.roi, cv::Rect());
}

// Every pixel coordinate is a whole sensor pixel >= 0, within 2^20; the error names its pixel.
TEST(DefectMapFile, RefusesPixelsThatAreNotWholeSensorPixels) {
  const std::string head = "defect_map:\n  roi_px: [0, 0, 64, 64]\n";
  ExpectRefused(head + "  pixels: [[1, 2], [3, -1]]\n", "features.defect_map.pixels[1]",
                "expected whole sensor pixels >= 0");
  ExpectRefused(head + "  pixels: [[1.5, 2]]\n", "features.defect_map.pixels[0]",
                "whole sensor pixels");
  ExpectRefused(head + "  pixels: [[1048577, 2]]\n", "features.defect_map.pixels[0]",
                "whole sensor pixels");
  ExpectRefused(head + "  pixels: [[1, 2], [4, 5], [x, 2]]\n", "features.defect_map.pixels[2]",
                "cannot read 'x' as a number");
  ExpectRefused(head + "  pixels: [[1, 2, 3]]\n", "features.defect_map.pixels[0]",
                "expected [x, y]");
  ExpectRefused(head + "  pixels: 7\n", "features.defect_map.pixels",
                "expected a sequence of [x, y]");
}

TEST(DefectMapFile, RefusesABadRoiAndUnknownOrMissingKeys) {
  const std::string pixels = "  pixels: [[1, 2]]\n";
  ExpectRefused("defect_map:\n  roi_px: [0, 0, 64]\n" + pixels, "features.defect_map.roi_px",
                "expected [x, y, width, height], whole pixels >= 0");
  ExpectRefused("defect_map:\n  roi_px: [0, -8, 64, 64]\n" + pixels,
                "features.defect_map.roi_px", "whole pixels >= 0");
  ExpectRefused("defect_map:\n  roi_px: [0, 0, 64.5, 64]\n" + pixels,
                "features.defect_map.roi_px", "whole pixels >= 0");
  ExpectRefused("defect_map:\n  roi_px: [0, 0, 64, 64]\n  pixel: [[1, 2]]\n",
                "features.defect_map.pixel", "unknown key");
  ExpectRefused("defect_map:\n  roi_px: [0, 0, 64, 64]\n", "features.defect_map.pixels",
                "missing");
  ExpectRefused("other: 1\n", "features.defect_map", "missing");
}

// The error's line is the offending node's line in the file (1-based).
TEST(DefectMapFile, ErrorsGiveTheLine) {
  const ModelFileError e = Refusal(
      "defect_map:\n"
      "  roi_px: [0, 0, 64, 64]\n"
      "  pixels:\n"
      "    - [1, 2]\n"
      "    - [3, 4.25]\n");
  EXPECT_EQ(e.key(), "features.defect_map.pixels[1]");
  EXPECT_EQ(e.line(), 5);
}

}  // namespace
}  // namespace irdist::model_file
