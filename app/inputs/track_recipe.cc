#include "app/inputs/track_recipe.h"

#include <cstdio>
#include <filesystem>

#include "app/inputs/recipe.h"
#include "base/bounds.h"
#include "base/yaml_fields.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using yaml_fields::Fail;
using yaml_fields::MapReader;

// A profile longer than this is a sweep's job, not a track's.
constexpr int kMaxSegments = 1000;
std::string Number(double value) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.10g", value);
  return text;
}

// `value` of `what` at `node` inside the rig's station.limits `range`, else refused there.
void CheckWithin(const std::string& file, const YAML::Node& node, const std::string& what,
                 double value, const AxisRange& range, const std::string& rig_path) {
  if (range.Contains(value)) return;
  Fail(file, node.Mark(),
       what + " " + Number(value) + " lies outside station.limits [" + Number(range.min) + ", " +
           Number(range.max) + "] of " + rig_path + "; give a position inside them");
}

// `key: [from, to]` (a move) or `key: x` (standing at x): two positions inside `range`.
void ReadFromTo(const MapReader& map, const std::string& key, const std::string& what,
                const Bound& bound, const AxisRange& range, const std::string& rig_path,
                double* from, double* to) {
  const YAML::Node node = map.Get(key);
  const std::string& file = map.File();
  if (node.IsScalar()) {
    *from = *to = yaml_fields::AsBounded(node, file, what, bound);
    CheckWithin(file, node, what, *from, range, rig_path);
    return;
  }
  if (!node.IsSequence() || node.size() != 2) {
    Fail(file, node.Mark(), what + " must be [from, to] (two positions) or one position");
  }
  *from = yaml_fields::AsBounded(node[0], file, what + " (from)", bound);
  *to = yaml_fields::AsBounded(node[1], file, what + " (to)", bound);
  CheckWithin(file, node[0], what + " (from)", *from, range, rig_path);
  CheckWithin(file, node[1], what + " (to)", *to, range, rig_path);
}

TrackSegment ReadSegment(const YAML::Node& node, const std::string& file, int index,
                         const TrackRecipe& recipe, double pan_deg) {
  const std::string where = "track.segments[" + std::to_string(index) + "]";
  const MapReader map(node, file, where, {"slide_mm", "speed_mm_s", "pan_deg", "pan_speed_deg_s"});
  const StationLimits& limits = recipe.rig.station.limits;
  TrackSegment s;
  s.line = static_cast<int>(node.Mark().line) + 1;
  map.Require("slide_mm");
  ReadFromTo(map, "slide_mm", where + ".slide_mm", bounds::kSlideMm, limits.slide_mm,
             recipe.rig_path, &s.slide_from_mm, &s.slide_to_mm);
  s.pan_from_deg = s.pan_to_deg = pan_deg;
  if (map.Has("pan_deg")) {
    ReadFromTo(map, "pan_deg", where + ".pan_deg", bounds::kAngleDeg, limits.pan_deg,
               recipe.rig_path, &s.pan_from_deg, &s.pan_to_deg);
  }
  const bool slide_moves = s.slide_from_mm != s.slide_to_mm;
  const bool pan_moves = s.pan_from_deg != s.pan_to_deg;
  if (!slide_moves && !pan_moves) {
    Fail(file, node.Mark(),
         where + " moves nothing (slide_mm " + Number(s.slide_from_mm) +
             " and pan_deg stand still); give slide_mm: [from, to] with from != to, or a pan move");
  }
  const std::string fix_speed = "give the cruise speed of the move";
  if (slide_moves) {
    map.Require("speed_mm_s");
    s.speed_mm_s = map.Bounded("speed_mm_s", 0.0, bounds::kSlideSpeedMmS, fix_speed);
  } else if (map.Has("speed_mm_s")) {
    Fail(file, map.Get("speed_mm_s").Mark(),
         where + ".speed_mm_s is given but the slide stands; remove it or give slide_mm a move");
  }
  if (pan_moves) {
    map.Require("pan_speed_deg_s");
    s.pan_speed_deg_s = map.Bounded("pan_speed_deg_s", 0.0, bounds::kAngularSpeedDegS, fix_speed);
  } else if (map.Has("pan_speed_deg_s")) {
    Fail(file, map.Get("pan_speed_deg_s").Mark(),
         where + ".pan_speed_deg_s is given but the pan stands; remove it or give pan_deg a move");
  }
  return s;
}

void ReadTrackSection(const MapReader& top, TrackRecipe* recipe) {
  const std::string& file = top.File();
  const MapReader track(top.Require("track"), file, "track",
                        {"bias_ma", "tilt_deg", "pan_deg", "exposure_ms", "accel_psd_mm2_per_s3",
                         "settle_ms", "after_ms", "truth_sd_mm", "segments"});
  const StationLimits& limits = recipe->rig.station.limits;
  track.Require("bias_ma");
  recipe->bias_ma = track.Bounded("bias_ma", 0.0, bounds::kCurrentMa);
  CheckWithin(file, track.Get("bias_ma"), "track.bias_ma", recipe->bias_ma, limits.bias_ma,
              recipe->rig_path);
  recipe->tilt_deg = track.Bounded("tilt_deg", 0.0, bounds::kAngleDeg);
  if (track.Has("tilt_deg")) {
    CheckWithin(file, track.Get("tilt_deg"), "track.tilt_deg", recipe->tilt_deg, limits.tilt_deg,
                recipe->rig_path);
  }
  const double pan_deg = track.Bounded("pan_deg", 0.0, bounds::kAngleDeg);
  if (track.Has("pan_deg")) {
    CheckWithin(file, track.Get("pan_deg"), "track.pan_deg", pan_deg, limits.pan_deg,
                recipe->rig_path);
  }
  recipe->exposure_ms = track.Bounded("exposure_ms", 0.0, bounds::kExposureMs);
  recipe->accel_psd_mm2_per_s3 = track.Bounded("accel_psd_mm2_per_s3", 0.0, bounds::kAccelPsd);
  recipe->settle_ms = track.Bounded("settle_ms", recipe->settle_ms, bounds::kDelayMs);
  recipe->after_ms = track.Bounded("after_ms", recipe->after_ms, bounds::kDelayMs);
  recipe->truth_sd_mm = track.Bounded("truth_sd_mm", recipe->truth_sd_mm, bounds::kPositionSdMm);
  const YAML::Node segments = track.Require("segments");
  if (!segments.IsSequence() || segments.size() == 0) {
    Fail(file, segments.Mark(),
         "track.segments must be a list of moves, e.g. - {slide_mm: [1500, 3000], speed_mm_s: "
         "500}");
  }
  if (segments.size() > static_cast<std::size_t>(kMaxSegments)) {
    Fail(file, segments.Mark(),
         "track.segments has " + std::to_string(segments.size()) + " moves; at most " +
             std::to_string(kMaxSegments) + ": split the profile into several recipes");
  }
  for (std::size_t i = 0; i < segments.size(); ++i) {
    recipe->segments.push_back(
        ReadSegment(segments[i], file, static_cast<int>(i), *recipe, pan_deg));
  }
}

}  // namespace

std::string RecipeKindOfText(const std::string& text, const std::string& file) {
  const YAML::Node root = yaml_fields::Parse(text, file);
  if (!root || !root.IsMap() || !root["kind"]) return "sweep";
  const std::string kind = yaml_fields::AsString(root["kind"], file, "kind");
  if (kind != "sweep" && kind != "track") {
    Fail(file, root["kind"].Mark(),
         "kind '" + kind + "' is not known; valid: sweep (the default: calibration and "
         "validation sweeps) or track (a moving profile, tracked frame by frame)");
  }
  return kind;
}

std::string RecipeKindOf(const std::string& path) {
  return RecipeKindOfText(yaml_fields::ReadFile(path), path);
}

TrackRecipe ParseTrackRecipe(const std::string& text, const std::string& file,
                             const std::string& base_dir) {
  const YAML::Node root = yaml_fields::Parse(text, file);
  if (!root || root.IsNull()) {
    throw RecipeError(file, 1, 1, "the recipe is empty; a track recipe needs kind: track and "
                                  "track: with its segments");
  }
  const MapReader map(root, file, "the track recipe",
                      {"kind", "name", "description", "rig", "output", "track"});
  if (RecipeKindOfText(text, file) != "track") {
    Fail(file, map.Mark(), "this is not a track recipe: add kind: track");
  }
  TrackRecipe recipe;
  recipe.path = file;
  recipe.name = map.String("name", fs::path(file).stem().string());
  recipe.description = map.String("description", "");
  recipe.output_dir = map.String("output", "runs/" + recipe.name);
  if (recipe.output_dir.empty()) Fail(file, map.Get("output").Mark(), "output must not be empty");
  const std::string rig_spec = map.String("rig", "virtual");
  recipe.rig_path = FindRigFile(rig_spec, base_dir);
  if (recipe.rig_path.empty()) {
    Fail(file, map.Has("rig") ? map.Get("rig").Mark() : map.Mark(),
         "rig '" + rig_spec + "' not found; give a rig name from " + ShippedRecipesDir() +
             "/rigs/ (e.g. virtual) or the path of a rig file");
  }
  recipe.rig = LoadRig(recipe.rig_path);
  ReadTrackSection(map, &recipe);
  return recipe;
}

TrackRecipe LoadTrackRecipe(const std::string& path) {
  const std::string text = yaml_fields::ReadFile(path);
  std::string base_dir = fs::path(path).parent_path().string();
  if (base_dir.empty()) base_dir = ".";
  return ParseTrackRecipe(text, path, base_dir);
}

}  // namespace irdist
