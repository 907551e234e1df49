#include "app/inputs/recipe.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "base/bounds.h"
#include "base/pi.h"
#include "base/yaml_fields.h"

#ifndef IRDIST_SOURCE_DIR
#define IRDIST_SOURCE_DIR "."
#endif

namespace irdist {
namespace {

namespace fs = std::filesystem;
using yaml_fields::AsInteger;
using yaml_fields::AsNumber;
using yaml_fields::AsString;
using yaml_fields::Fail;
using yaml_fields::MapReader;

constexpr int kMaxAxisValues = 100000;
// Brackets of one plan: 1e6 is 11 days at 1 s a bracket, and a plan of ~100 MB.
constexpr double kMaxPlanBrackets = 1e6;
constexpr double kMaxPlanDurationS = 1e8;  // three years

std::string Number(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.10g", value);
  return buffer;
}

std::string RangeText(const AxisRange& range) {
  return "[" + Number(range.min) + ", " + Number(range.max) + "]";
}

const char kAxisForms[] =
    "a number, a list of numbers, a range {start, stop, step} or random draws "
    "{mean, sd, count, seed}";

// An axis as read from the file: its values and, for each value, where it was written.
struct ParsedAxis {
  AxisValues values;
  std::vector<YAML::Mark> marks;  // one per value (lists and ranges)
  YAML::Mark mark;                // the axis's node
  YAML::Mark mean_mark;           // random draws: the mean
  YAML::Node random_node;         // random draws: the map
};

// `calibration: {camera_response: linear | recover}` of a recipe's top-level map.
CameraResponse ReadCameraResponse(const MapReader& map, const std::string& file) {
  if (!map.Has("calibration")) return CameraResponse::kLinear;
  const MapReader calibration(map.Get("calibration"), file, "calibration", {"camera_response"});
  const std::string value = calibration.String("camera_response", "linear");
  if (value == "linear") return CameraResponse::kLinear;
  if (value == "recover") return CameraResponse::kRecover;
  Fail(file, calibration.Get("camera_response").Mark(),
       "calibration.camera_response '" + value +
           "' is not known; valid: linear (default), recover (the inverse response from the "
           "brackets)");
  return CameraResponse::kLinear;
}

std::vector<double> ExpandRange(const MapReader& range, const std::string& what,
                                std::vector<YAML::Mark>* marks) {
  const double start = AsNumber(range.Require("start"), range.File(), what + ".start");
  const double stop = AsNumber(range.Require("stop"), range.File(), what + ".stop");
  const double step = AsNumber(range.Require("step"), range.File(), what + ".step");
  const YAML::Mark step_mark = range.Get("step").Mark();
  const YAML::Mark stop_mark = range.Get("stop").Mark();
  if (step == 0.0) {
    Fail(range.File(), step_mark,
         what + ".step must not be 0; for a single value write " + what + ": " + Number(start));
  }
  const double steps = (stop - start) / step;
  if (steps < -1e-9) {
    Fail(range.File(), step_mark,
         what + ".step " + Number(step) + " moves away from stop " + Number(stop) + " (start " +
             Number(start) + "); use step " + Number(-step));
  }
  const double whole = std::round(steps);
  if (std::abs(steps - whole) > 1e-9 * std::max(1.0, std::abs(steps))) {
    const double below = start + std::floor(steps) * step;
    const double above = start + std::ceil(steps) * step;
    Fail(range.File(), stop_mark,
         what + ".stop " + Number(stop) + " is not reached from start " + Number(start) +
             " in whole steps of " + Number(step) + " (ranges include their stop); valid stops: " +
             Number(below) + " or " + Number(above));
  }
  if (whole + 1 > kMaxAxisValues) {
    Fail(range.File(), step_mark,
         what + " has " + Number(whole + 1) + " values; at most " + std::to_string(kMaxAxisValues));
  }
  const int count = static_cast<int>(whole) + 1;
  std::vector<double> values;
  for (int i = 0; i < count; ++i) {
    // start + i*step, never an accumulated sum; the last value is stop exactly.
    values.push_back(i + 1 == count ? stop : start + i * step);
    marks->push_back(i == 0 ? range.Get("start").Mark() : stop_mark);
  }
  return values;
}

ParsedAxis ReadAxis(const YAML::Node& node, const std::string& file, const std::string& what,
                    bool allow_random) {
  ParsedAxis axis;
  axis.mark = node.Mark();
  const std::string forms =
      allow_random ? kAxisForms : "a number, a list of numbers or a range {start, stop, step}";
  if (node.IsScalar()) {
    axis.values.values.push_back(AsNumber(node, file, what));
    axis.marks.push_back(node.Mark());
  } else if (node.IsSequence()) {
    if (node.size() == 0) {
      Fail(file, node.Mark(), what + " is empty; give at least one value (" + forms + ")");
    }
    for (const YAML::Node& element : node) {
      axis.values.values.push_back(AsNumber(element, file, what + " value"));
      axis.marks.push_back(element.Mark());
    }
  } else if (node.IsMap()) {
    const bool range = node["start"] || node["stop"] || node["step"];
    const bool random = node["mean"] || node["sd"] || node["count"] || node["seed"];
    if (range) {
      const MapReader map(node, file, what + " (a range)", {"start", "stop", "step"});
      axis.values.values = ExpandRange(map, what, &axis.marks);
    } else if (random && allow_random) {
      const MapReader map(node, file, what + " (random draws)",
                          {"mean", "sd", "count", "seed", "per_pose", "min", "max"});
      RandomDraws draws;
      draws.mean = AsNumber(map.Require("mean"), file, what + ".mean");
      draws.sd = AsNumber(map.Require("sd"), file, what + ".sd");
      if (draws.sd < 0.0) Fail(file, map.Get("sd").Mark(), what + ".sd must be >= 0");
      draws.count = AsInteger(map.Require("count"), file, what + ".count");
      if (draws.count < 1 || draws.count > kMaxAxisValues) {
        Fail(file, map.Get("count").Mark(),
             what + ".count must be between 1 and " + std::to_string(kMaxAxisValues));
      }
      const int seed = AsInteger(map.Require("seed"), file, what + ".seed");
      if (seed < 0) Fail(file, map.Get("seed").Mark(), what + ".seed must be >= 0");
      draws.seed = static_cast<std::uint64_t>(seed);
      draws.per_pose = map.Boolean("per_pose", draws.per_pose);
      draws.min = map.Number("min", draws.min);
      draws.max = map.Number("max", draws.max);
      axis.values.random = draws;
      axis.mean_mark = map.Get("mean").Mark();
      axis.random_node = node;
    } else {
      Fail(file, node.Mark(),
           what + " must be " + forms + (node.size() == 0 ? " (it is empty)" : ""));
    }
  } else {
    Fail(file, node.Mark(), what + " must be " + forms);
  }
  return axis;
}

// Values against the rig's limits; random draws get their truncation from the limits.
void CheckLimits(ParsedAxis* axis, const AxisRange& limits, const std::string& file,
                 const std::string& what, const std::string& rig_file) {
  const std::string valid =
      " is outside the rig's limits " + RangeText(limits) + " (station.limits in " + rig_file + ")";
  if (axis->values.random.has_value()) {
    RandomDraws& draws = *axis->values.random;
    if (!limits.Contains(draws.mean)) {
      Fail(file, axis->mean_mark, what + ".mean " + Number(draws.mean) + valid);
    }
    for (const char* key : {"min", "max"}) {
      const YAML::Node bound = axis->random_node[key];
      if (bound && !limits.Contains(AsNumber(bound, file, what + "." + key))) {
        Fail(file, bound.Mark(),
             what + "." + key + " " + Number(AsNumber(bound, file, key)) + valid);
      }
    }
    draws.min = std::max(draws.min, limits.min);
    draws.max = std::min(draws.max, limits.max);
    if (!(draws.min < draws.max) || draws.mean < draws.min || draws.mean > draws.max) {
      Fail(file, axis->mark, what + ": need min < mean < max for the random draws");
    }
    std::string why;
    if (!draws.IsValid(&why)) {
      Fail(file, axis->random_node["sd"].Mark(),
           what + ": the random draws N(" + Number(draws.mean) + ", sd " + Number(draws.sd) +
               ") are kept only inside [" + Number(draws.min) + ", " + Number(draws.max) +
               "] (the draws' min/max and the rig's limits): " + why);
    }
    return;
  }
  for (size_t i = 0; i < axis->values.values.size(); ++i) {
    const double v = axis->values.values[i];
    if (!limits.Contains(v)) Fail(file, axis->marks[i], what + " " + Number(v) + valid);
  }
}

SweepAxis AxisByName(const YAML::Node& node, const std::string& file, const std::string& what,
                     AngleMode mode) {
  const std::string name = AsString(node, file, what);
  const std::vector<std::string> names = {
      SweepAxisName(SweepAxis::kSlide, mode), SweepAxisName(SweepAxis::kAngle, mode),
      SweepAxisName(SweepAxis::kTilt, mode), SweepAxisName(SweepAxis::kBias, mode)};
  for (size_t k = 0; k < names.size(); ++k) {
    if (names[k] == name) return static_cast<SweepAxis>(k);
  }
  Fail(file, node.Mark(),
       what + ": '" + name +
           "' is not an axis of this recipe; valid: " + yaml_fields::JoinNames(names));
}

std::vector<SweepAxis> ReadAxisList(const YAML::Node& node, const std::string& file,
                                    const std::string& what, AngleMode mode) {
  if (!node.IsSequence()) Fail(file, node.Mark(), what + " must be a list of axis names");
  std::vector<SweepAxis> axes;
  for (const YAML::Node& element : node) {
    const SweepAxis axis = AxisByName(element, file, what, mode);
    if (std::find(axes.begin(), axes.end(), axis) != axes.end()) {
      Fail(file, element.Mark(), what + " names '" + element.Scalar() + "' twice");
    }
    axes.push_back(axis);
  }
  return axes;
}

double Rad(double deg) { return deg * kPi / 180.0; }

}  // namespace

std::string CameraResponseName(CameraResponse response) {
  return response == CameraResponse::kRecover ? "recover" : "linear";
}

CameraResponse CameraResponseOfRecipeText(const std::string& text, const std::string& file) {
  const YAML::Node root = yaml_fields::Parse(text, file);
  if (!root || !root.IsMap() || !root["calibration"]) return CameraResponse::kLinear;
  YAML::Node only(YAML::NodeType::Map);
  only["calibration"] = root["calibration"];
  return ReadCameraResponse(MapReader(only, file, "the recipe", {"calibration"}), file);
}

std::string AfterRecordingName(AfterRecording after) {
  switch (after) {
    case AfterRecording::kNone:
      return "none";
    case AfterRecording::kFit:
      return "fit";
    case AfterRecording::kEstimate:
      return "estimate";
  }
  return "?";
}

std::string ShippedRecipesDir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);  // the real file, through symlinks
  if (!ec) {
    const fs::path installed = exe.parent_path().parent_path() / "share" / "irdist" / "recipes";
    if (fs::is_directory(installed, ec)) return installed.string();
  }
  return (fs::path(IRDIST_SOURCE_DIR) / "recipes").string();
}

std::string FindRigFile(const std::string& spec, const std::string& base_dir) {
  std::error_code ec;
  const bool is_path = spec.find('/') != std::string::npos ||
                       (spec.size() > 5 && spec.compare(spec.size() - 5, 5, ".yaml") == 0);
  std::vector<fs::path> candidates;
  if (is_path) {
    const fs::path path(spec);
    candidates.push_back(path.is_absolute() ? path : fs::path(base_dir) / path);
  } else {
    candidates.push_back(fs::path(base_dir) / "rigs" / (spec + ".yaml"));
    candidates.push_back(fs::path(ShippedRecipesDir()) / "rigs" / (spec + ".yaml"));
  }
  for (const fs::path& candidate : candidates) {
    if (fs::is_regular_file(candidate, ec)) return candidate.lexically_normal().string();
  }
  return "";
}

namespace {

// name, description, output, after and calibration: what the recipe says about its run.
void ReadRunKeys(const MapReader& map, const std::string& file, Recipe* recipe) {
  recipe->path = file;
  recipe->name = map.String("name", fs::path(file).stem().string());
  recipe->description = map.String("description", "");
  recipe->output_dir = map.String("output", "runs/" + recipe->name);
  if (recipe->output_dir.empty()) Fail(file, map.Get("output").Mark(), "output must not be empty");
  const std::string after = map.String("after", "none");
  if (after == "none") {
    recipe->after = AfterRecording::kNone;
  } else if (after == "fit") {
    recipe->after = AfterRecording::kFit;
  } else if (after == "estimate") {
    recipe->after = AfterRecording::kEstimate;
  } else {
    Fail(file, map.Get("after").Mark(),
         "after '" + after + "' is not known; valid: fit (calibration), estimate (validation), none");
  }
  recipe->camera_response = ReadCameraResponse(map, file);
}

// The rig first: its limits check the axes.
void ReadRigKey(const MapReader& map, const std::string& file, const std::string& base_dir,
                Recipe* recipe) {
  const std::string rig_spec = map.String("rig", "virtual");
  recipe->rig_path = FindRigFile(rig_spec, base_dir);
  if (recipe->rig_path.empty()) {
    const YAML::Node rig_node = map.Get("rig");
    Fail(file, rig_node ? rig_node.Mark() : map.Mark(),
         "rig '" + rig_spec +
             "' not found; give a rig name from " + ShippedRecipesDir() +
             "/rigs/ (e.g. virtual) or the path of a rig file");
  }
  recipe->rig = LoadRig(recipe->rig_path);
  recipe->motion = recipe->rig.station.motion;
}

// theta through pan at each tilt: cos(theta) = cos(pan) cos(tilt), within the pan limits.
void CheckThetaRealisable(const ParsedAxis& angle, const ParsedAxis& tilt,
                          const StationLimits& limits, const std::string& file,
                          const std::string& rig_file) {
  for (size_t i = 0; i < angle.values.values.size(); ++i) {
    const double theta = angle.values.values[i];
    if (!(std::abs(theta) < 90.0)) {
      Fail(file, angle.marks[i], "axes.theta_deg " + Number(theta) + " must lie in (-90, 90)");
    }
    for (double tilt_deg : tilt.values.values) {
      const double c = std::cos(Rad(theta)) / std::cos(Rad(tilt_deg));
      if (c > 1.0 + 1e-12) {
        Fail(file, angle.marks[i],
             "axes.theta_deg " + Number(theta) + " cannot be realised with tilt_deg " +
                 Number(tilt_deg) + ": cos(theta) = cos(pan) cos(tilt) needs |theta| >= |tilt|");
      }
      const double pan = std::acos(std::min(1.0, c)) * 180.0 / kPi;
      if (!limits.pan_deg.Contains(theta < 0 ? -pan : pan)) {
        Fail(file, angle.marks[i],
             "axes.theta_deg " + Number(theta) + " needs pan " + Number(theta < 0 ? -pan : pan) +
                 " deg at tilt " + Number(tilt_deg) + ", outside the rig's pan limits " +
                 RangeText(limits.pan_deg) + " (station.limits in " + rig_file + ")");
      }
    }
  }
}

// A random angle's window (its min and max, or the rig's limits) inside (-90, 90) deg, as listed
// angles are (SweepSpec::IsValid): refused at the axis's line on a rig whose limits reach further.
void CheckRandomAngleWindow(const ParsedAxis& axis, const std::string& file,
                            const std::string& what) {
  if (!axis.values.random.has_value()) return;
  const RandomDraws& draws = *axis.values.random;
  if (draws.min > -90.0 && draws.max < 90.0) return;
  Fail(file, axis.mark,
       what + ": random draws are kept inside [" + Number(draws.min) + ", " + Number(draws.max) +
           "] (their min/max and the rig's limits), which must lie inside (-90, 90) deg; give "
           "min and max inside it");
}

void CheckAngleLimits(ParsedAxis* angle, const ParsedAxis& tilt, AngleMode mode,
                      const StationLimits& limits, const std::string& file,
                      const std::string& rig_file) {
  if (mode == AngleMode::kPan) {
    CheckLimits(angle, limits.pan_deg, file, "axes.pan_deg", rig_file);
  } else if (angle->values.random.has_value() || tilt.values.random.has_value()) {
    const bool tilt_zero = !tilt.values.random.has_value() &&
                           std::all_of(tilt.values.values.begin(), tilt.values.values.end(),
                                       [](double t) { return t == 0.0; });
    if (!tilt_zero) {
      Fail(file, angle->mark,
           "random draws of theta_deg or tilt_deg need tilt_deg 0 (theta realised by pan); "
           "draw pan_deg and tilt_deg instead");
    }
    CheckLimits(angle, limits.pan_deg, file, "axes.theta_deg", rig_file);
  } else {
    CheckThetaRealisable(*angle, tilt, limits, file, rig_file);
  }
}

void ReadAxes(const MapReader& map, const std::string& file, Recipe* recipe) {
  const MapReader axes(map.Require("axes"), file, "axes",
                       {"slide_mm", "theta_deg", "pan_deg", "tilt_deg", "bias_ma"});
  if (axes.Has("theta_deg") && axes.Has("pan_deg")) {
    Fail(file, axes.Get("pan_deg").Mark(),
         "give either theta_deg or pan_deg, not both (theta is realised by pan at the given tilt)");
  }
  if (!axes.Has("theta_deg") && !axes.Has("pan_deg")) {
    Fail(file, axes.Mark(), "axes is missing the key 'theta_deg' (or 'pan_deg')");
  }
  SweepSpec& sweep = recipe->sweep;
  sweep.angle_mode = axes.Has("theta_deg") ? AngleMode::kTheta : AngleMode::kPan;
  const std::string angle_key = sweep.angle_mode == AngleMode::kTheta ? "theta_deg" : "pan_deg";
  ParsedAxis slide = ReadAxis(axes.Require("slide_mm"), file, "axes.slide_mm", true);
  ParsedAxis angle = ReadAxis(axes.Require(angle_key), file, "axes." + angle_key, true);
  ParsedAxis bias = ReadAxis(axes.Require("bias_ma"), file, "axes.bias_ma", true);
  // tilt_deg is optional: 0 when absent.
  ParsedAxis tilt = axes.Has("tilt_deg")
                        ? ReadAxis(axes.Get("tilt_deg"), file, "axes.tilt_deg", true)
                        : ReadAxis(YAML::Node(0.0), file, "axes.tilt_deg", true);
  if (!axes.Has("tilt_deg")) tilt.marks = {axes.Mark()};  // errors about the default point at axes
  const StationLimits& limits = recipe->rig.station.limits;
  const std::string& rig_file = recipe->rig_path;
  CheckLimits(&slide, limits.slide_mm, file, "axes.slide_mm", rig_file);
  CheckLimits(&tilt, limits.tilt_deg, file, "axes.tilt_deg", rig_file);
  CheckLimits(&bias, limits.bias_ma, file, "axes.bias_ma", rig_file);
  CheckAngleLimits(&angle, tilt, sweep.angle_mode, limits, file, rig_file);
  CheckRandomAngleWindow(angle, file, "axes." + SweepAxisName(SweepAxis::kAngle, sweep.angle_mode));
  CheckRandomAngleWindow(tilt, file, "axes.tilt_deg");
  sweep.slide_mm = slide.values;
  sweep.angle_deg = angle.values;
  sweep.tilt_deg = tilt.values;
  sweep.bias_ma = bias.values;
}

void ReadBracket(const MapReader& map, const std::string& file, BracketSpec* spec) {
  const MapReader bracket(map.Require("bracket"), file, "bracket",
                          {"t_ref_ms", "t_meas_ms", "repeats", "retake_reference"});
  spec->t_ref_ms = yaml_fields::AsBounded(bracket.Require("t_ref_ms"), file, "bracket.t_ref_ms",
                                          bounds::kExposureMs);
  const ParsedAxis t_meas =
      ReadAxis(bracket.Require("t_meas_ms"), file, "bracket.t_meas_ms", false);
  spec->t_meas_ms = t_meas.values.values;
  for (size_t i = 0; i < spec->t_meas_ms.size(); ++i) {
    if (!(spec->t_meas_ms[i] > spec->t_ref_ms)) {
      Fail(file, t_meas.marks[i],
           "bracket.t_meas_ms " + Number(spec->t_meas_ms[i]) + " must be longer than t_ref_ms " +
               Number(spec->t_ref_ms) + " (the method differences t_n - t_r > 0)");
    }
    const std::string refusal = bounds::kExposureMs.Refusal(
        "bracket.t_meas_ms " + Number(spec->t_meas_ms[i]), spec->t_meas_ms[i],
        "give exposures in (t_ref_ms, " + Number(bounds::kExposureMs.max) + "] ms");
    if (!refusal.empty()) Fail(file, t_meas.marks[i], refusal);
  }
  spec->repeats = bracket.Integer("repeats", 1);
  if (spec->repeats < 1) Fail(file, bracket.Get("repeats").Mark(), "bracket.repeats must be >= 1");
  spec->retake_reference = bracket.Boolean("retake_reference", false);
}

void ReadSettle(const MapReader& map, const std::string& file, SettleSpec* spec) {
  if (!map.Has("settle")) return;
  const MapReader settle(map.Get("settle"), file, "settle", {"after_move_ms", "after_current_ms"});
  spec->after_move_ms = settle.Number("after_move_ms", spec->after_move_ms);
  spec->after_current_ms = settle.Number("after_current_ms", spec->after_current_ms);
  for (const char* key : {"after_move_ms", "after_current_ms"}) {
    const double ms = settle.Number(key, 0.0);
    if (settle.Has(key) && !(ms >= 0.0 && ms <= kMaxSettleMs)) {
      Fail(file, settle.Get(key).Mark(),
           std::string("settle.") + key + " " + Number(ms) + " must lie in [0, " +
               Number(kMaxSettleMs) + "] ms (at most an hour a wait)");
    }
  }
}

// Serpentine: true (default axes), false (none) or a list of axes. Order: the listed axes
// outermost, in that order; the others after them by step cost.
void ReadSerpentineAndOrder(const MapReader& map, const std::string& file, const MotionModel& motion,
                            SweepSpec* sweep) {
  if (map.Has("serpentine")) {
    const YAML::Node node = map.Get("serpentine");
    bool flag = false;
    if (node.IsScalar() && YAML::convert<bool>::decode(node, flag)) {
      if (!flag) sweep->serpentine.clear();
    } else if (node.IsSequence()) {
      sweep->serpentine = ReadAxisList(node, file, "serpentine", sweep->angle_mode);
    } else {
      Fail(file, node.Mark(), "serpentine must be true, false or a list of axis names");
    }
  }
  std::vector<SweepAxis> order;
  if (map.Has("order")) {
    order = ReadAxisList(map.Get("order"), file, "order", sweep->angle_mode);
    if (order.empty()) Fail(file, map.Get("order").Mark(), "order is empty; list axis names");
  }
  for (SweepAxis axis : ChooseAxisOrder(*sweep, motion)) {
    if (std::find(order.begin(), order.end(), axis) == order.end()) order.push_back(axis);
  }
  sweep->order = order;
}

// A plan that would not fit in memory (or in a lab's year) is refused before it is made.
void CheckPlanSize(const MapReader& map, const std::string& file, const SweepSpec& sweep) {
  const BracketSpec& b = sweep.bracket;
  const double poses = static_cast<double>(sweep.slide_mm.Count()) * sweep.angle_deg.Count() *
                       sweep.tilt_deg.Count() * sweep.bias_ma.Count() * b.repeats;
  const double per_bracket = 1.0 + static_cast<double>(b.t_meas_ms.size()) *
                                       (b.retake_reference ? 2.0 : 1.0);
  if (poses > kMaxPlanBrackets || poses * per_bracket > kMaxPlanFrames) {
    Fail(file, map.Mark(),
         "the recipe asks for " + Number(poses) + " brackets (slide " +
             std::to_string(sweep.slide_mm.Count()) + " x angle " +
             std::to_string(sweep.angle_deg.Count()) + " x tilt " +
             std::to_string(sweep.tilt_deg.Count()) + " x bias " +
             std::to_string(sweep.bias_ma.Count()) + " x repeats " + std::to_string(b.repeats) +
             ", " + Number(poses * per_bracket) + " frames); at most " +
             Number(kMaxPlanBrackets) + " brackets and " + Number(kMaxPlanFrames) +
             " frames: use fewer values, repeats or exposures");
  }
}

}  // namespace

Recipe ParseRecipe(const std::string& text, const std::string& file, const std::string& base_dir) {
  const YAML::Node root = yaml_fields::Parse(text, file);
  if (!root || root.IsNull()) {
    throw RecipeError(file, 1, 1, "the recipe is empty; it needs at least axes: and bracket:");
  }
  if (root.IsMap() && root["kind"] && root["kind"].IsScalar() &&
      root["kind"].Scalar() != "sweep") {  // track_recipe.h reads the other kinds
    Fail(file, root["kind"].Mark(),
         "kind '" + root["kind"].Scalar() + "' is not a sweep: a track recipe (kind: track) is "
         "run by 'irdist validate " + file + " --model MODEL' (docs/recipes.md \"Track "
         "recipes\"); a sweep has no kind: or kind: sweep");
  }
  const MapReader map(root, file, "the recipe",
                      {"name", "description", "rig", "output", "after", "calibration", "axes",
                       "order", "serpentine", "bracket", "settle", "kind"});
  Recipe recipe;
  ReadRunKeys(map, file, &recipe);
  ReadRigKey(map, file, base_dir, &recipe);
  ReadAxes(map, file, &recipe);
  ReadBracket(map, file, &recipe.sweep.bracket);
  CheckPlanSize(map, file, recipe.sweep);
  ReadSettle(map, file, &recipe.sweep.settle);
  ReadSerpentineAndOrder(map, file, recipe.motion, &recipe.sweep);
  std::string why;
  if (!recipe.sweep.IsValid(&why)) Fail(file, map.Mark(), why);
  return recipe;
}

Recipe LoadRecipe(const std::string& path) {
  const std::string text = yaml_fields::ReadFile(path);
  std::string base_dir = fs::path(path).parent_path().string();
  if (base_dir.empty()) base_dir = ".";
  return ParseRecipe(text, path, base_dir);
}

Plan PlanRecipe(const Recipe& recipe) {
  Plan plan = MakePlan(recipe.sweep, recipe.motion);
  // Every term is bounded by the recipe's checks except the rig's motion (a speed of 1e-300
  // mm/s): a plan that would last beyond any lab's patience is the rig file's to fix.
  if (!(plan.summary.total_s <= kMaxPlanDurationS)) {
    throw RecipeError(recipe.path, 0, 0,
                      "the sweep would last " + FormatDuration(plan.summary.total_s) +
                          " (at most " + FormatDuration(kMaxPlanDurationS) +
                          "); check station.motion (speed, acceleration, settle_ms) and "
                          "station.limits in " + recipe.rig_path +
                          ", and the recipe's settle and exposures");
  }
  return plan;
}

}  // namespace irdist
