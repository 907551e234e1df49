// Whole-run timing of a sweep: runs `irdist calibrate RECIPE` on its rig (or on --rig RIG) and sets
// the measured sweep time (from the end of homing to the end of parking, as the run reports it on
// its "Timing:" line) beside the plan's estimate and its physical bound (moves + exposures +
// readout), with the run's own breakdown of where the time went.
//   bench_sweep_timing [RECIPE] [TIME_SCALE] [--rig RIG]
// Default: recipes/table3-calibration.yaml on its own rig at the rig's time scale. Prints one line
// per figure and the ratios; not a Google Benchmark: one sweep is the unit.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "app/cli/cli.h"
#include "app/inputs/recipe.h"
#include "station/plan.h"

namespace {

struct BenchArgs {
  std::string recipe_path = std::string(IRDIST_SOURCE_DIR) + "/recipes/table3-calibration.yaml";
  std::string time_scale;
  std::string rig;
};

BenchArgs ParseArgs(int argc, char** argv) {
  BenchArgs args;
  std::vector<std::string> positional;
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word == "--rig" && i + 1 < argc) {
      args.rig = argv[++i];
    } else {
      positional.push_back(word);
    }
  }
  if (!positional.empty()) args.recipe_path = positional[0];
  if (positional.size() > 1) args.time_scale = positional[1];
  return args;
}

// The recipe with its `rig:` line replaced by `rig: RIG`, written to `dir`; the path to run.
std::string RecipeOnRig(const std::string& recipe_path, const std::string& rig,
                        const std::string& dir) {
  if (rig.empty()) return recipe_path;
  std::ifstream in(recipe_path);
  std::ostringstream text;
  text << in.rdbuf();
  const std::string replaced =
      std::regex_replace(text.str(), std::regex("^rig:[^\n]*", std::regex::multiline),
                         "rig: " + rig);
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/" + std::filesystem::path(recipe_path).filename().string();
  std::ofstream(path) << replaced;
  return path;
}

// The run's "Timing:" line (homing and sweep after homing, s); false when absent.
bool SweepTiming(const std::string& run_out, double* sweep_s, double* homing_s,
                 std::string* line) {
  std::istringstream in(run_out);
  std::string text;
  while (std::getline(in, text)) {
    if (std::sscanf(text.c_str(), "Timing: homing %lf s; sweep %lf s", homing_s, sweep_s) == 2) {
      *line = text;
      return true;
    }
  }
  return false;
}

std::string RunCalibrate(const std::string& recipe_path, const std::string& out,
                         const std::string& time_scale, double* whole_s) {
  std::vector<std::string> words = {"irdist", "calibrate", recipe_path, "--out", out, "--quiet"};
  if (!time_scale.empty()) {
    words.push_back("--time-scale");
    words.push_back(time_scale);
  }
  std::vector<const char*> args;
  for (const std::string& w : words) args.push_back(w.c_str());
  std::ostringstream run_out, run_err;
  const auto t0 = std::chrono::steady_clock::now();
  irdist::RunIrdist(static_cast<int>(args.size()), args.data(), {run_out, run_err});
  *whole_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (run_out.str().find("Timing:") == std::string::npos) std::cerr << run_err.str();
  return run_out.str();
}

}  // namespace

int main(int argc, char** argv) {
  const BenchArgs args = ParseArgs(argc, argv);
  const std::string out =
      (std::filesystem::temp_directory_path() / ("irdist-sweep-timing-" + std::to_string(::getpid())))
          .string();
  try {
    const std::string recipe_path = RecipeOnRig(args.recipe_path, args.rig, out + "-recipe");
    const irdist::Recipe recipe = irdist::LoadRecipe(recipe_path);
    const irdist::Plan plan = irdist::PlanRecipe(recipe);
    double whole_s = 0.0, sweep_s = 0.0, homing_s = 0.0;
    const std::string run_out = RunCalibrate(recipe_path, out, args.time_scale, &whole_s);
    std::string timing;
    if (!SweepTiming(run_out, &sweep_s, &homing_s, &timing)) {
      std::cerr << "bench_sweep_timing: the run printed no Timing: line\n" << run_out;
      return 1;
    }
    // The time scale the run used (the rig's own unless given), from its "Wall time" line.
    const std::size_t at = run_out.find("at time scale ");
    const double scale = at == std::string::npos ? 1.0 : std::stod(run_out.substr(at + 14));
    // The run's own plan and bound (a composed rig's on its devices' speeds), else the recipe's.
    double plan_s = plan.summary.total_s / scale;
    double bound_s = plan.summary.physical_bound_s / scale;
    const std::size_t bound_at = run_out.find("Bound: physical ");
    if (bound_at != std::string::npos) {
      std::sscanf(run_out.c_str() + bound_at, "Bound: physical %lf s, plan %lf s", &bound_s,
                  &plan_s);
    }
    std::printf("recipe            %s on rig %s (%d poses, %d frames, time scale %g)\n",
                args.recipe_path.c_str(), recipe.rig.name.c_str(), plan.summary.pose_count,
                plan.summary.frame_count, scale);
    std::printf("homing            %8.2f s (not in the plan)\n", homing_s);
    std::printf("sweep measured    %8.2f s\n", sweep_s);
    std::printf("plan estimate     %8.2f s   measured / plan  %.3f\n", plan_s, sweep_s / plan_s);
    std::printf("physical bound    %8.2f s   measured / bound %.3f\n", bound_s, sweep_s / bound_s);
    std::printf("whole command     %8.2f s (camera and station set-up, sweep, fit, report)\n",
                whole_s);
    std::printf("%s\n", timing.c_str());
    std::filesystem::remove_all(out);
    std::filesystem::remove_all(out + "-recipe");
  } catch (const std::exception& e) {
    std::cerr << "bench_sweep_timing: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
