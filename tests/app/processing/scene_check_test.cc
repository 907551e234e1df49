// What `irdist check` says of a recording's scene (app/processing/scene_check.h): which brackets
// are suspect, the table of those with findings, and each bracket's frames measured.
#include "app/processing/scene_check.h"

#include <gtest/gtest.h>

#include <string>

#include "acquisition/recording_reader.h"
#include "tests/app/small_recording.h"

namespace irdist {
namespace {

using testing::SmallRecordingTest;

BracketScene Scene(std::int64_t bracket, int frames) {
  BracketScene b;
  b.bracket = bracket;
  b.figures.frames = frames;
  return b;
}

TEST(SceneCheck, ASecondSourceOcclusionSaturationOrNoBlobIsSuspectDefectsAreNot) {
  BracketScene b = Scene(0, 4);
  EXPECT_FALSE(b.Suspect());
  b.figures.defect_pixels = 3;
  b.figures.other_blobs = 1;
  EXPECT_FALSE(b.Suspect());  // measured through
  BracketScene no_blob = Scene(1, 4), second = Scene(2, 4), occluded = Scene(3, 4),
               saturated = Scene(4, 4);
  no_blob.figures.no_blob = 1;
  second.figures.second_source = 2;
  occluded.figures.occluded = 1;
  saturated.figures.saturated_frames = 1;
  for (const BracketScene& s : {no_blob, second, occluded, saturated}) {
    EXPECT_TRUE(s.Suspect()) << s.bracket;
  }
}

TEST(SceneCheck, TheTableListsOnlyTheBracketsWithFindings) {
  SceneCheck clean;
  clean.brackets = {Scene(0, 4), Scene(1, 4)};
  clean.brackets[1].figures.background_max = 0.0125;
  const std::string quiet = clean.BriefReport();
  EXPECT_NE(quiet.find("2 brackets; 0 with a second source"), std::string::npos) << quiet;
  EXPECT_NE(quiet.find("up to 1.25% of full scale"), std::string::npos) << quiet;
  EXPECT_EQ(quiet.find("bracket frames"), std::string::npos) << quiet;  // no table

  SceneCheck found = clean;
  found.brackets[0].figures.second_source = 1;
  found.brackets[0].figures.second_source_gap_px = 7.5;
  found.brackets[1].figures.defect_pixels = 2;
  found.brackets.push_back(Scene(2, 4));
  const std::string report = found.BriefReport();
  EXPECT_NE(report.find("3 brackets; 1 with a second source"), std::string::npos) << report;
  EXPECT_NE(report.find("1 with defect pixels"), std::string::npos) << report;
  EXPECT_NE(report.find("second source 7.5 px away"), std::string::npos) << report;
  EXPECT_NE(report.find("move the source, mask the reflection"), std::string::npos) << report;
  // Two rows in the table: brackets 0 and 1, not the clean bracket 2.
  const std::string table = report.substr(report.find("bracket frames"));
  EXPECT_NE(table.find("\n        0      4"), std::string::npos) << table;
  EXPECT_NE(table.find("\n        1      4"), std::string::npos) << table;
  EXPECT_EQ(table.find("\n        2      4"), std::string::npos) << table;
}

TEST_F(SmallRecordingTest, EveryFrameOfEachBracketIsMeasured) {
  const RecordingReader reader((dir_ / "recording").string());
  const SceneCheck check = CheckScene(reader);
  ASSERT_EQ(check.brackets.size(), reader.Brackets().size());
  ASSERT_FALSE(check.brackets.empty());
  EXPECT_EQ(check.brackets[0].bracket, 0);
  EXPECT_EQ(check.brackets[0].figures.frames, 4);
  EXPECT_EQ(check.brackets[0].figures.no_blob, 0);  // the spot is found in every frame
}

}  // namespace
}  // namespace irdist
