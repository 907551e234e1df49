#include "app/runs/run_suggest.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <ostream>
#include <vector>

#include "acquisition/recording_reader.h"
#include "app/inputs/stop_signal.h"
#include "app/inputs/recipe.h"
#include "app/processing/frame_features.h"
#include "app/reports/summary.h"
#include "app/runs/run.h"
#include "app/runs/run_folder.h"
#include "app/runs/suggest.h"
#include "base/safe_file.h"
#include "station/plan.h"

namespace irdist {

namespace fs = std::filesystem;

namespace {

// The probe recipe of `plan --suggest`: the recipe's two ends (nearest distance at the smallest
// angle and the highest current; farthest at the largest angle and the lowest current) crossed,
// each taken at the recipe's t_r and its longest t_n. Written as YAML so that the probe run is
// recorded like any other (its recipe text stands in its recording.yaml).
struct RecipeEnds {
  double d_min = 1e300, d_max = -1e300;    // mm
  double th_min = 1e300, th_max = -1e300;  // |theta|, deg
  double i_min = 1e300, i_max = -1e300;    // mA
  // The bright end (nearest, smallest angle, highest current) or the faint end (farthest,
  // largest angle, lowest current), compared at the station's resolution (0.01 unit).
  bool Nearest(double d, double theta, double ma) const {
    return Same(d, d_min) && Same(std::abs(theta), th_min) && Same(ma, i_max);
  }
  bool Farthest(double d, double theta, double ma) const {
    return Same(d, d_max) && Same(std::abs(theta), th_max) && Same(ma, i_min);
  }
  static bool Same(double a, double b) {
    return std::llround(a * 100.0) == std::llround(b * 100.0);
  }
};

RecipeEnds EndsOf(const Plan& plan) {
  RecipeEnds e;
  for (const Pose& p : plan.poses) {
    e.d_min = std::min(e.d_min, p.slide_mm);
    e.d_max = std::max(e.d_max, p.slide_mm);
    e.th_min = std::min(e.th_min, std::abs(p.theta_deg));
    e.th_max = std::max(e.th_max, std::abs(p.theta_deg));
    e.i_min = std::min(e.i_min, p.bias_ma);
    e.i_max = std::max(e.i_max, p.bias_ma);
  }
  return e;
}

std::string ProbeRecipeText(const Recipe& recipe, const RecipeEnds& e) {
  // [lo, hi], or [lo] when the recipe has one value on the axis.
  const auto pair = [](YAML::Emitter& out, double lo, double hi) {
    out << YAML::Flow << YAML::BeginSeq << lo;
    if (hi != lo) out << hi;
    out << YAML::EndSeq;
  };
  const BracketSpec& b = recipe.sweep.bracket;
  const double t_long = *std::max_element(b.t_meas_ms.begin(), b.t_meas_ms.end());
  YAML::Emitter y;  // every path and name quoted as it needs ('#', ':', quotes, spaces)
  y.SetDoublePrecision(10);
  y << YAML::Comment("Probe frames for 'irdist plan --suggest " + recipe.path + "'");
  y << YAML::BeginMap;
  y << YAML::Key << "name" << YAML::Value << YAML::DoubleQuoted << recipe.name + "-probe";
  y << YAML::Key << "rig" << YAML::Value << YAML::DoubleQuoted
    << fs::absolute(recipe.rig_path).string();
  y << YAML::Key << "after" << YAML::Value << "none";
  y << YAML::Key << "axes" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "slide_mm" << YAML::Value;
  pair(y, e.d_min, e.d_max);
  y << YAML::Key << "theta_deg" << YAML::Value;
  pair(y, e.th_min, e.th_max);
  y << YAML::Key << "bias_ma" << YAML::Value;
  pair(y, e.i_min, e.i_max);
  y << YAML::EndMap;
  y << YAML::Key << "bracket" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "t_ref_ms" << YAML::Value << b.t_ref_ms;
  y << YAML::Key << "t_meas_ms" << YAML::Value << YAML::Flow << YAML::BeginSeq << t_long
    << YAML::EndSeq;
  y << YAML::EndMap << YAML::EndMap;
  return std::string(y.c_str()) + "\n";
}

}  // namespace

std::string SuggestProbeRecipe(const Recipe& recipe, const Plan& plan) {
  return ProbeRecipeText(recipe, EndsOf(plan));
}

namespace {

// The suggestion's options, with --from's best dt; checked before the probe sweep (a bad value
// must not cost a sweep).
SuggestOptions SuggestOptionsOf(const PlanArgs& args, std::ostream& err) {
  SuggestOptions options;
  if (!args.from_summary.empty()) {
    const std::optional<double> best = ReadBestDtMs(args.from_summary);
    if (best) {
      options.best_dt_ms = *best;
    } else {
      err << args.from_summary << " has no best_dt_ms (a validation with one t_n?); "
          << "suggesting without it.\n";
    }
  }
  std::string why;
  if (!options.IsValid(&why)) throw SuggestError(args.from_summary + ": " + why);
  return options;
}

}  // namespace

void RunSuggest(const PlanArgs& args, CommandIo io) {
  const Recipe recipe = LoadRecipe(args.recipe);
  PrintRigNotes(recipe.rig, io.err);
  const Plan plan = PlanRecipe(recipe);
  const RecipeEnds ends = EndsOf(plan);
  const SuggestOptions options = SuggestOptionsOf(args, io.err);
  const std::string dir =
      args.out_dir.empty() ? recipe.output_dir + "-suggest-" + Timestamp() : args.out_dir;
  fs::create_directories(dir);
  const std::string probe_path = dir + "/probe-recipe.yaml";
  std::string why;
  if (!WriteFileAtomically(probe_path, SuggestProbeRecipe(recipe, plan), 0644, &why)) {
    throw RunFolderError(probe_path + " " + why + "; check the folder.");
  }
  RunRequest request;
  request.kind = RunKind::kCalibrate;
  request.recipe_path = probe_path;
  request.out_dir = dir;
  request.time_scale = args.time_scale;
  request.quiet = args.quiet;
  const Recipe probe_recipe = LoadRecipe(probe_path);
  const Plan probe_plan = PlanRecipe(probe_recipe);
  io.out << "Probing " << recipe.path << " at its ends: " << probe_plan.summary.pose_count
         << " poses, t " << recipe.sweep.bracket.t_ref_ms << " and "
         << probe_recipe.sweep.bracket.t_meas_ms.front() << " ms\n";
  Recorded recorded;
  {
    SignalGuard guard;
    recorded = Record(request, probe_recipe, probe_plan, FeatureOptions{}, nullptr, io);
  }
  if (recorded.cut) throw InterruptedError("probe stopped; nothing suggested.");
  const RecordingReader reader(dir + "/recording");
  const FeatureMap features = RecordingFeatures(reader, FeatureOptions{}, recorded.cache);
  std::vector<ProbeFrame> probes;
  for (const FrameRecord& row : reader.rows()) {
    const bool nearest = ends.Nearest(row.slide_mm, row.theta_deg, row.bias_ma_set);
    const bool farthest = ends.Farthest(row.slide_mm, row.theta_deg, row.bias_ma_set);
    if (!nearest && !farthest) continue;
    const auto f = features.find(row.index);
    if (f == features.end() || !f->second.blob_found) {
      throw RunFolderError(reader.dir() + ": no IRED image in frame " + row.file +
                           "; is the IRED in view and on? (see " + dir + "/features.csv)");
    }
    probes.push_back({nearest, row.requested_exposure_us / 1000.0, row.bias_ma_set, f->second.peak,
                      f->second.background});
  }
  const Suggestion s = SuggestExposures(probes, options);
  io.out << "Suggested bracket for " << recipe.path << " (probe run in " << dir << "):\n"
         << s.BriefReport();
  if (!s.feasible) throw SuggestError("no feasible exposures: " + s.reason);
}

}  // namespace irdist
