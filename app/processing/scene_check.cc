#include "app/processing/scene_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "acquisition/recording_reader.h"
#include "app/processing/frame_features.h"

namespace irdist {

namespace {

void AddFrame(const Features& f, BracketScene* b) {
  ++b->frames;
  b->ambient_pct = std::max(b->ambient_pct, 100.0 * f.background);
  if (!f.blob_found) {
    ++b->no_blob;
    return;
  }
  const SceneReport& s = f.scene;
  b->defect_pixels = std::max(b->defect_pixels, s.defect_pixels);
  b->other_blobs = std::max(b->other_blobs, s.other_blobs);
  b->saturated += f.saturated_pixels > 0 ? 1 : 0;
  if (s.second_source) {
    ++b->second_source;
    if (!(b->second_source_gap_px <= s.second_source_gap_px)) {
      b->second_source_gap_px = s.second_source_gap_px;
    }
  }
  if (s.occluded) {
    ++b->occluded;
    b->occluded_edge_pct = std::max(b->occluded_edge_pct, 100.0 * s.occluded_edge_fraction);
  }
}

std::string Row(const BracketScene& b) {
  char line[200];
  std::snprintf(line, sizeof(line), "  %7lld %6d %7d %7d %7d %7d %9d %8.2f%%",
                static_cast<long long>(b.bracket), b.frames, b.no_blob, b.defect_pixels,
                b.other_blobs, b.second_source, b.occluded, b.ambient_pct);
  std::string out = line;
  if (b.second_source > 0 && std::isfinite(b.second_source_gap_px)) {
    std::snprintf(line, sizeof(line), "  second source %.1f px away", b.second_source_gap_px);
    out += line;
  }
  if (b.occluded > 0) {
    std::snprintf(line, sizeof(line), "  occluded %.0f%% of the edge", b.occluded_edge_pct);
    out += line;
  }
  if (b.saturated > 0) out += "  saturated in " + std::to_string(b.saturated) + " frame(s)";
  return out;
}

}  // namespace

bool BracketScene::Suspect() const {
  return no_blob > 0 || second_source > 0 || occluded > 0 || saturated > 0;
}

SceneCheck CheckScene(const RecordingReader& reader) {
  SceneCheck check;
  const int bit_depth = reader.header().bit_depth;
  const FeatureOptions options;
  for (const RecordedBracket& bracket : reader.Brackets()) {
    BracketScene b;
    b.bracket = bracket.bracket_id;
    for (const FrameRecord& row : bracket.frames) {
      AddFrame(FrameFeatures(reader.LoadImage(row), bit_depth, options), &b);
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
    with_defects += b.defect_pixels > 0 ? 1 : 0;
    with_others += b.other_blobs > 0 ? 1 : 0;
    ambient_max = std::max(ambient_max, b.ambient_pct);
    if (b.Suspect() || b.defect_pixels > 0 || b.other_blobs > 0) rows += Row(b) + "\n";
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
