// Each frame's features, the same from the PNG as from memory (a live run's cache), and
// features.csv, on a small hand-made recording.
#include "app/processing/frame_features.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "acquisition/recording_reader.h"
#include "tests/app/small_recording.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::ReadAll;
using testing::SmallRecordingTest;

TEST(OfflineBitDepth, FollowsThePixelFormat) {
  EXPECT_EQ(BitDepthOfPixelFormat("Mono8"), 8);
  EXPECT_EQ(BitDepthOfPixelFormat("Mono10"), 10);
  EXPECT_EQ(BitDepthOfPixelFormat("Mono12"), 12);
  EXPECT_EQ(BitDepthOfPixelFormat("Mono16"), 16);
}

TEST_F(SmallRecordingTest, FeaturesFromPngEqualFeaturesFromMemory) {
  const RecordingReader reader((dir_ / "recording").string());
  const FeatureOptions options;
  const FeatureMap from_png = RecordingFeatures(reader, options);
  ASSERT_EQ(from_png.size(), 5u);
  FeatureMap cache;
  for (size_t i = 0; i < images_.size(); ++i) {
    cache[static_cast<std::int64_t>(i)] = FrameFeatures(images_[i], 12, options);
    EXPECT_EQ(cache[static_cast<std::int64_t>(i)].e_rel,
              from_png.at(static_cast<std::int64_t>(i)).e_rel);
    EXPECT_EQ(cache[static_cast<std::int64_t>(i)].sigma,
              from_png.at(static_cast<std::int64_t>(i)).sigma);
  }
  // A cached entry is taken as is (the live run's in-memory frames).
  cache[2].e_rel = 42.0;
  cache.erase(4);
  const FeatureMap mixed = RecordingFeatures(reader, options, cache);
  EXPECT_EQ(mixed.at(2).e_rel, 42.0);
  EXPECT_EQ(mixed.at(4).e_rel, from_png.at(4).e_rel);

  const std::string a = (dir_ / "a.csv").string(), b = (dir_ / "b.csv").string();
  WriteFeaturesCsv(a, reader.rows(), from_png);
  WriteFeaturesCsv(b, reader.rows(), RecordingFeatures(reader, options, FeatureMap{{0, cache[0]}}));
  EXPECT_EQ(ReadAll(a), ReadAll(b));
  std::istringstream lines(ReadAll(a));
  std::string header, first;
  std::getline(lines, header);
  std::getline(lines, first);
  EXPECT_EQ(header.rfind("index,file,bracket,frame_in_bracket,role,exposure_us", 0), 0u);
  EXPECT_EQ(first.rfind("0,frames/000000.png,0,0,ref,8000,", 0), 0u) << first;
  int rows = 0;
  for (std::string line; std::getline(lines, line);) ++rows;
  EXPECT_EQ(rows, 4);  // plus the first: 5 frames
}

}  // namespace
}  // namespace irdist
