#include "app/processing/scene_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "acquisition/recording_reader.h"
#include "app/processing/frame_features.h"

namespace irdist {

namespace {

std::string Row(const BracketScene& b) {
  const SceneFigures& f = b.figures;
  char line[200];
  std::snprintf(line, sizeof(line), "  %7lld %6d %7d %7d %7d %7d %9d %8.2f%%",
                static_cast<long long>(b.bracket), f.frames, f.no_blob, f.defect_pixels,
                f.other_blobs, f.second_source, f.occluded, 100.0 * f.background_max);
  std::string out = line;
  if (f.second_source > 0 && std::isfinite(f.second_source_gap_px)) {
    std::snprintf(line, sizeof(line), "  second source %.1f px away", f.second_source_gap_px);
    out += line;
  }
  if (f.occluded > 0) {
    std::snprintf(line, sizeof(line), "  occluded %.0f%% of the edge",
                  100.0 * f.occluded_edge_fraction);
    out += line;
  }
  if (f.saturated_frames > 0) {
    out += "  saturated in " + std::to_string(f.saturated_frames) + " frame(s)";
  }
  return out;
}

}  // namespace

bool BracketScene::Suspect() const {
  const SceneFigures& f = figures;
  return f.no_blob > 0 || f.second_source > 0 || f.occluded > 0 || f.saturated_frames > 0;
}

SceneCheck CheckScene(const RecordingReader& reader) {
  SceneCheck check;
  const int bit_depth = reader.header().bit_depth;
  const FeatureOptions options;
  for (const RecordedBracket& bracket : reader.Brackets()) {
    BracketScene b;
    b.bracket = bracket.bracket_id;
    for (const FrameRecord& row : bracket.frames) {
      const Features f = FrameFeatures(reader.LoadImage(row), bit_depth, options);
      b.figures.Add(&f);
    }
    check.brackets.push_back(b);
  }
  return check;
}

std::string SceneCheck::BriefReport() const {
  std::ostringstream out;
  int suspect = 0, with_defects = 0, with_others = 0;
  double ambient_max = 0.0;
  std::string rows;
  for (const BracketScene& b : brackets) {
    suspect += b.Suspect() ? 1 : 0;
    with_defects += b.figures.defect_pixels > 0 ? 1 : 0;
    with_others += b.figures.other_blobs > 0 ? 1 : 0;
    ambient_max = std::max(ambient_max, 100.0 * b.figures.background_max);
    if (b.Suspect() || b.figures.defect_pixels > 0 || b.figures.other_blobs > 0) {
      rows += Row(b) + "\n";
    }
  }
  char ambient[32];
  std::snprintf(ambient, sizeof(ambient), "%.2f%%", ambient_max);
  out << "scene (the images, a report): " << brackets.size() << " brackets; " << suspect
      << " with a second source, an occluded disc, saturation or no blob; " << with_defects
      << " with defect pixels and " << with_others
      << " with other blobs (both measured through); background (black level and ambient) up to "
      << ambient
      << " of full scale";
  if (!rows.empty()) {
    out << "\n  bracket frames no_blob defects others 2nd_src occluded background\n" << rows;
    out << "  (docs/reports.md, \"Flags\": a second source or an occluded disc makes the "
           "estimates suspect; move the source, mask the reflection or clear the disc)";
  }
  return out.str();
}

}  // namespace irdist
