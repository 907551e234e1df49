// What measure prints of each bracket, against docs/measure.md: every key of the JSON schema's
// table with its documented type, unknown quantities as null, the causes and the trusted verdict,
// the figures' text, the sample made from a bracket's frames, and the summary's flag counts.
// The older checks of the same output (health, motion, clocks, the live line's width) are in
// measure_test.cc.
#include "app/live/measure_output.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "acquisition/recording_types.h"
#include "app/processing/position.h"

namespace irdist {
namespace {

MeasureSample Estimated() {
  MeasureSample s;
  s.bracket = 3;
  s.time_s = 0.75;
  s.latency_ms = 1.5;
  s.utc_ns = 1796191923123456789;
  s.host_monotonic_ns = 5000000000;
  s.have_estimate = true;
  s.estimate.ok = true;
  s.estimate.d_mm = 1750.5;
  s.estimate.d_std_mm = 1.25;
  s.estimate.theta_deg = 22.5;
  s.estimate.theta_std_deg = 0.125;
  s.blob_found = true;
  s.blob_x_px = 600.5;
  s.blob_y_px = 480.25;
  s.has_position = true;
  s.x_mm = 12.0;
  s.y_mm = -3.0;
  s.z_mm = 1750.0;
  return s;
}

// The rows of docs/measure.md's table under "## JSON schema": each row's keys (the backticked
// names of its first cell) and its type cell.
struct DocumentedKey {
  std::string key, type;
};
std::vector<DocumentedKey> SchemaTable() {
  std::ifstream in(std::string(IRDIST_SOURCE_DIR) + "/docs/measure.md");
  std::vector<DocumentedKey> keys;
  bool in_section = false;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("## ", 0) == 0) in_section = line.rfind("## JSON schema", 0) == 0;
    if (!in_section || line.rfind("| `", 0) != 0) continue;
    const std::size_t first_bar = line.find('|', 1), second_bar = line.find('|', first_bar + 1);
    const std::string names = line.substr(1, first_bar - 1);
    const std::string type = line.substr(first_bar + 1, second_bar - first_bar - 1);
    const std::regex backticked("`([a-z_]+)`");
    for (std::sregex_iterator m(names.begin(), names.end(), backticked), end; m != end; ++m) {
      keys.push_back({(*m)[1].str(), type});
    }
  }
  return keys;
}

// Whether a parsed JSON value has the documented type ("number or null", "integer", ...).
bool HasType(const YAML::Node& value, const std::string& type) {
  if (value.IsNull()) return type.find("null") != std::string::npos;
  if (type.find("object") != std::string::npos && value.IsMap()) return true;
  if (type.find("array") != std::string::npos && value.IsSequence()) return true;
  if (!value.IsScalar()) return false;
  const std::string text = value.Scalar();
  const bool quoted = value.Tag() == "!";  // yaml-cpp tags a quoted scalar "!"
  if (type.find("string") != std::string::npos && quoted) return true;
  if (quoted) return false;
  if (type.find("bool") != std::string::npos) return text == "true" || text == "false";
  if (type.find("integer") != std::string::npos) {
    return std::regex_match(text, std::regex("-?\\d+"));
  }
  if (type.find("number") != std::string::npos) {
    return std::regex_match(text, std::regex("-?\\d+(\\.\\d+)?([eE][-+]?\\d+)?"));
  }
  return false;
}

TEST(MeasureJson, HoldsEveryKeyOfTheDocumentedSchemaWithItsType) {
  const std::vector<DocumentedKey> keys = SchemaTable();
  ASSERT_GE(keys.size(), 20u) << "docs/measure.md's schema table not found";
  MeasureSample s = Estimated();
  s.health.assessed = true;
  s.motion.assessed = true;
  s.estimate.flags = {{"defect_pixels", "2"}};
  const std::string json = MeasureJson(s);
  EXPECT_EQ(json.find('\n'), std::string::npos);  // one object per line
  const YAML::Node j = YAML::Load(json);
  for (const DocumentedKey& k : keys) {
    ASSERT_TRUE(j[k.key]) << "no key " << k.key << " in " << json;
    EXPECT_TRUE(HasType(j[k.key], k.type)) << k.key << " is not " << k.type << " in " << json;
  }
  // The flags the table lists, each a bool.
  for (const char* flag : {"no_blob", "saturated", "touches_border", "clipped", "outside_range",
                           "unhealthy", "refocused", "moving", "second_source", "occluded"}) {
    ASSERT_TRUE(j["flags"][flag]) << flag;
    EXPECT_TRUE(HasType(j["flags"][flag], "bool")) << flag;
  }
  for (const char* key : {"x_mm", "y_mm", "z_mm", "x_se_mm", "y_se_mm", "z_se_mm"}) {
    EXPECT_TRUE(j["position"][key]) << key;
  }
  EXPECT_EQ(j["mode"].as<std::string>(), "bracket");
}

// A quantity that does not exist is null: a standard error the solver did not give (negative),
// a time not measured; a track line says so in its mode.
TEST(MeasureJson, UnknownQuantitiesAreNullAndATrackLineSaysItsMode) {
  MeasureSample s = Estimated();
  s.estimate.d_std_mm = -1.0;
  s.estimate.theta_std_deg = -1.0;
  s.latency_ms = NAN;
  s.mode = "track";
  const std::string json = MeasureJson(s);
  EXPECT_EQ(json.find("nan"), std::string::npos) << json;  // JSON has no NaN
  const YAML::Node j = YAML::Load(json);
  EXPECT_EQ(j["mode"].as<std::string>(), "track");
  EXPECT_DOUBLE_EQ(j["d_mm"].as<double>(), 1750.5);
  EXPECT_TRUE(j["d_se_mm"].IsNull());
  EXPECT_TRUE(j["theta_se_deg"].IsNull());
  EXPECT_TRUE(j["latency_ms"].IsNull());
}

// `causes` lists every flag with its figure; a note (defect pixels replaced) leaves the estimate
// trusted, a suspect flag (occluded) does not, and raises its own bool in `flags`.
TEST(MeasureJson, CausesNameEachFlagAndOnlySuspectOnesMakeItUntrusted) {
  MeasureSample s = Estimated();
  s.estimate.flags = {{"defect_pixels", "2"}};
  YAML::Node j = YAML::Load(MeasureJson(s));
  EXPECT_TRUE(j["trusted"].as<bool>());
  ASSERT_EQ(j["causes"].size(), 1u);
  EXPECT_EQ(j["causes"][0]["name"].as<std::string>(), "defect_pixels");
  EXPECT_EQ(j["causes"][0]["figure"].as<std::string>(), "2");
  EXPECT_FALSE(j["causes"][0]["suspect"].as<bool>());

  s.estimate.flags.push_back({"occluded", "12%"});
  j = YAML::Load(MeasureJson(s));
  EXPECT_FALSE(j["trusted"].as<bool>());
  ASSERT_EQ(j["causes"].size(), 2u);
  EXPECT_EQ(j["causes"][1]["name"].as<std::string>(), "occluded");
  EXPECT_EQ(j["causes"][1]["figure"].as<std::string>(), "12%");
  EXPECT_TRUE(j["causes"][1]["suspect"].as<bool>());
  EXPECT_TRUE(j["flags"]["occluded"].as<bool>());
  EXPECT_FALSE(j["flags"]["second_source"].as<bool>());

  s.have_estimate = false;  // no estimate: nothing to trust, no causes
  j = YAML::Load(MeasureJson(s));
  EXPECT_FALSE(j["trusted"].as<bool>());
  EXPECT_EQ(j["causes"].size(), 0u);
}

TEST(FixedTextAndJsonNumber, ShowTheFigureOrSayItIsMissing) {
  EXPECT_EQ(FixedText(2001.256, 1), "2001.3");
  EXPECT_EQ(FixedText(-0.125, 2), "-0.12");  // round half to even, as printf
  EXPECT_EQ(FixedText(NAN, 1), "-");
  EXPECT_EQ(FixedText(INFINITY, 1), "-");
  EXPECT_EQ(JsonNumber(NAN), "null");
  EXPECT_EQ(JsonNumber(-INFINITY), "null");
  // Ten significant digits: a distance to the micrometre, and a tiny figure not rounded to 0.
  EXPECT_NEAR(std::stod(JsonNumber(2001.123456789)), 2001.123456789, 1e-6);
  EXPECT_DOUBLE_EQ(std::stod(JsonNumber(1.5e-12)), 1.5e-12);
}

// The sample of a 3-frame bracket: the blob where the last frame saw it, on the whole sensor;
// a problem of any frame is the bracket's; theta's se from the calibrated correction's scatter
// when the solver gave none (sqrt(pi/2) x mean |residual| 0.4 deg = 0.501 deg).
TEST(MeasureSampleOf, TakesTheLastFramesBlobAndEveryFramesProblems) {
  RecordedBracket bracket;
  bracket.bracket_id = 41;
  FeatureMap features;
  for (int i = 0; i < 3; ++i) {
    FrameRecord row;
    row.index = 100 + i;
    row.frame_in_bracket = i;
    bracket.frames.push_back(row);
    Features f;
    f.blob_found = true;
    f.centroid_px = {10.0 + i, 20.0 + i};
    features[row.index] = f;
  }
  features[100].saturated_pixels = 4;
  features[101].touches_border = true;
  BracketEstimateRows rows;
  EstimateRow row;
  row.ok = true;
  row.d_mm = 2500.0;
  row.theta_std_deg = -1.0;  // theta from the correction, not solved
  row.x_mm = 5.0;
  row.y_mm = 6.0;
  row.z_mm = 2499.0;
  rows.i0_free = {row};
  CalibrationModel model;
  model.theta_correction.coefficients = {0.0, 1.0, 0.0};
  model.theta_correction.summary.mean_relative_error = 0.4;
  CameraGeometry geometry;
  geometry.roi_offset_x = 512;
  geometry.roi_offset_y = 384;

  MeasureSample s = MeasureSampleOf(bracket, features, rows, model, geometry);
  EXPECT_EQ(s.bracket, 41);
  ASSERT_TRUE(s.have_estimate);
  EXPECT_DOUBLE_EQ(s.estimate.d_mm, 2500.0);
  EXPECT_NEAR(s.estimate.theta_std_deg, 0.5013, 1e-4);
  EXPECT_DOUBLE_EQ(s.blob_x_px, 524.0);  // 12 + 512
  EXPECT_DOUBLE_EQ(s.blob_y_px, 406.0);  // 22 + 384
  EXPECT_TRUE(s.blob_found);
  EXPECT_TRUE(s.saturated);
  EXPECT_TRUE(s.touches_border);
  EXPECT_FALSE(s.clipped);
  EXPECT_TRUE(s.has_position);
  EXPECT_DOUBLE_EQ(s.z_mm, 2499.0);

  features[101].blob_found = false;  // one frame without a blob: the bracket has none
  rows.i0_free.clear();              // and no estimate
  s = MeasureSampleOf(bracket, features, rows, model, geometry);
  EXPECT_FALSE(s.blob_found);
  EXPECT_FALSE(s.have_estimate);
  EXPECT_FALSE(s.has_position);
  EXPECT_NE(QualityFlags(s).find("no_blob"), std::string::npos) << QualityFlags(s);
  EXPECT_NE(QualityFlags(s).find("no_estimate"), std::string::npos) << QualityFlags(s);
}

// The summary counts the suspect brackets and each flag, a note marked as one.
TEST(MeasureStats, CountsSuspectBracketsAndEachFlagWithNotesMarked) {
  MeasureStats stats;
  MeasureSample noted = Estimated();
  noted.estimate.flags = {{"defect_pixels", "2"}};
  stats.Add(noted);
  MeasureSample occluded = Estimated();
  occluded.estimate.flags = {{"defect_pixels", "1"}, {"occluded", "12%"}};
  stats.Add(occluded);
  stats.Add(Estimated());
  const std::string report = stats.Report(1.5);
  EXPECT_NE(report.find("Measured 3 brackets in 1.50 s (2.00 brackets/s), 3 with an estimate"),
            std::string::npos) << report;
  EXPECT_NE(report.find("suspect: 1 of 3 brackets (flags: defect_pixels 2 (note), occluded 1)"),
            std::string::npos) << report;
  EXPECT_NE(report.find("latency (last frame to estimate): mean 1.500 ms"), std::string::npos)
      << report;
}

}  // namespace
}  // namespace irdist
