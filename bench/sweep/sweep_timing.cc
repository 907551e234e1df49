// Whole-run timing of a sweep: runs `irdist calibrate RECIPE` on its rig (virtual by default) and
// sets the measured sweep time (from the end of homing, read off the station's line log, to the
// last line) beside the plan's estimate and its physical bound (moves + exposures + readout).
//   bench_sweep_timing [RECIPE] [TIME_SCALE]
// Default: recipes/table3-calibration.yaml at the rig's time scale. Prints one line per figure
// and the ratios; not a Google Benchmark: one sweep is the unit.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "app/cli.h"
#include "app/recipe.h"
#include "station/plan.h"

namespace {

// Seconds from the first IDLE reply (homing done) to the last line of the station log.
bool SweepAfterHoming(const std::string& log_path, double* sweep_s, double* homing_s) {
  std::ifstream in(log_path);
  std::string line;
  double first = -1.0, idle = -1.0, last = -1.0;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    double t = 0.0;
    std::string direction;
    if (!(words >> t >> direction)) continue;
    if (first < 0.0) first = t;
    last = t;
    if (idle < 0.0 && direction == "<" && line.find(" OK IDLE,") != std::string::npos) idle = t;
  }
  if (idle < 0.0) return false;
  *homing_s = idle - first;
  *sweep_s = last - idle;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string recipe_path =
      argc > 1 ? argv[1] : std::string(IRDIST_SOURCE_DIR) + "/recipes/table3-calibration.yaml";
  const std::string time_scale = argc > 2 ? argv[2] : "";
  try {
    const irdist::Recipe recipe = irdist::LoadRecipe(recipe_path);
    const irdist::Plan plan = irdist::PlanRecipe(recipe);
    const std::string out =
        (std::filesystem::temp_directory_path() / ("irdist-sweep-timing-" + std::to_string(::getpid())))
            .string();
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
    const double whole_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    double sweep_s = 0.0, homing_s = 0.0;
    if (!SweepAfterHoming(out + "/station.log", &sweep_s, &homing_s)) {
      std::cerr << out << "/station.log: no homing found\n";
      return 1;
    }
    const double scale = time_scale.empty() ? 1.0 : std::stod(time_scale);
    const double plan_s = plan.summary.total_s / scale;
    const double bound_s = plan.summary.physical_bound_s / scale;
    std::printf("recipe            %s (%d poses, %d frames)\n", recipe_path.c_str(),
                plan.summary.pose_count, plan.summary.frame_count);
    std::printf("homing            %8.1f s (not in the plan)\n", homing_s);
    std::printf("sweep measured    %8.1f s\n", sweep_s);
    std::printf("plan estimate     %8.1f s   measured / plan  %.3f\n", plan_s, sweep_s / plan_s);
    std::printf("physical bound    %8.1f s   measured / bound %.3f\n", bound_s, sweep_s / bound_s);
    std::printf("whole command     %8.1f s (camera and station set-up, sweep, fit, report)\n",
                whole_s);
    std::filesystem::remove_all(out);
  } catch (const std::exception& e) {
    std::cerr << "bench_sweep_timing: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
