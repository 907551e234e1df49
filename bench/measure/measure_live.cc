// Whole-run timing of `irdist measure` on the virtual rig: calibrates Table 3 (at time scale 10,
// for the model), then measures N brackets live at time scale 1, once with the model as fitted
// (features refined by the blob's likelihood fit, the default) and once with the same model on the
// moments alone (features.blob_fit: false), and sets, side by side,
//   - the bracket rate against its physical bound (sum of exposures + one readout per frame,
//     the camera's own readout_ms): brackets per second / bound >= 0.9 is the goal;
//   - the latency from a bracket's last frame to its estimate (each JSON line's latency_ms):
//     median, p95 and max against 2 ms;
// then tracks (`measure --track`) FRAMES frames at the model's reference exposure, again
// with the blob fit and with the moments, and sets side by side:
//   - estimates per second against the frames per second the camera delivered in the same run
//     (the counters of the last line: received + lost frames over the lines' time span);
//   - the latency from a frame's arrival to its estimate: median, p95, max (goals 1 and 2 ms);
//   - the frames the estimator skipped and the frames lost;
//   - the estimator thread's CPU per frame (each line's cpu_ms): median and p95.
//   bench_measure_live [COUNT] [--rig RIG] [--track FRAMES]   (60 brackets, 300 frames, virtual)
// Run it inside a private network namespace (it starts the virtual rig's camera on 127.0.0.1).
// Not a Google Benchmark: one live run is the unit.
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "app/cli/cli.h"
#include "app/inputs/recipe.h"

namespace {

// Runs the irdist command line in process; returns its exit code, stdout in `*out`.
int Run(const std::vector<std::string>& words, std::string* out) {
  std::vector<const char*> args;
  for (const std::string& w : words) args.push_back(w.c_str());
  std::ostringstream run_out, run_err;
  const int code = irdist::RunIrdist(static_cast<int>(args.size()), args.data(), {run_out, run_err});
  *out = run_out.str();
  if (code != 0) std::cerr << run_err.str();
  return code;
}

double Quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5)];
}

struct LiveRun {
  std::vector<double> time_s, latency_ms;
};

LiveRun ParseJsonLines(const std::string& text) {
  LiveRun run;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] != '{') continue;
    const YAML::Node j = YAML::Load(line);
    run.time_s.push_back(j["time_s"].as<double>());
    run.latency_ms.push_back(j["latency_ms"].as<double>());
  }
  return run;
}

// model.yaml with `features.blob_fit: false` added (the moments path), written beside it.
std::string MomentsModel(const std::string& model_path) {
  std::ifstream in(model_path);
  std::ostringstream text;
  text << in.rdbuf();
  std::string model = text.str();
  const std::size_t at = model.find("\nfeatures:\n");
  if (at == std::string::npos) return "";
  model.insert(at + 11, "  blob_fit: false\n");
  const std::string out = model_path.substr(0, model_path.size() - 5) + "-moments.yaml";
  std::ofstream(out) << model;
  return out;
}

// One live run: its per-bracket period against the bound and its latency.
bool MeasureAndPrint(const std::string& label, const std::string& model, const std::string& rig,
                     int count, double bound_ms) {
  std::string out;
  if (Run({"irdist", "measure", "--model", model, "--rig", rig, "--time-scale", "1", "--at",
           "2000,20,0,490", "--count", std::to_string(count), "--json"},
          &out) != 0) {
    std::cerr << "bench_measure_live: measure failed\n" << out;
    return false;
  }
  const LiveRun run = ParseJsonLines(out);
  if (run.time_s.size() < 3) {
    std::cerr << "bench_measure_live: fewer than 3 JSON lines\n" << out;
    return false;
  }
  const double per_bracket_ms = 1000.0 * (run.time_s.back() - run.time_s.front()) /
                                static_cast<double>(run.time_s.size() - 1);
  std::printf("%-10s bracket period %8.2f ms, bound %7.2f ms, rate / bound %.3f; latency median "
              "%.3f ms, p95 %.3f ms, max %.3f ms, median / 2 ms %.3f\n",
              label.c_str(), per_bracket_ms, bound_ms, bound_ms / per_bracket_ms,
              Quantile(run.latency_ms, 0.5), Quantile(run.latency_ms, 0.95),
              *std::max_element(run.latency_ms.begin(), run.latency_ms.end()),
              Quantile(run.latency_ms, 0.5) / 2.0);
  std::fflush(stdout);
  return true;
}

// One tracking run: the estimates' rate against the camera's, latency, frames dropped, CPU.
bool TrackAndPrint(const std::string& label, const std::string& model, const std::string& rig,
                   int frames) {
  std::string out;
  if (Run({"irdist", "measure", "--model", model, "--rig", rig, "--time-scale", "1", "--at",
           "2000,20,0,490", "--track", "--count", std::to_string(frames), "--json"},
          &out) != 0) {
    std::cerr << "bench_measure_live: measure --track failed\n" << out;
    return false;
  }
  std::vector<double> time_s, latency_ms, cpu_ms, camera_frames, skipped, lost;
  std::istringstream in(out);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] != '{') continue;
    const YAML::Node j = YAML::Load(line);
    time_s.push_back(j["time_s"].as<double>());
    latency_ms.push_back(j["latency_ms"].as<double>());
    cpu_ms.push_back(j["cpu_ms"].as<double>());
    const YAML::Node c = j["counters"];
    camera_frames.push_back(c["received"].as<double>() + c["lost"].as<double>());
    skipped.push_back(c["skipped"].as<double>());
    lost.push_back(c["lost"].as<double>());
  }
  if (time_s.size() < 3) {
    std::cerr << "bench_measure_live: fewer than 3 track lines\n" << out;
    return false;
  }
  const double span_s = time_s.back() - time_s.front();
  const double estimates_per_s = static_cast<double>(time_s.size() - 1) / span_s;
  const double camera_per_s = (camera_frames.back() - camera_frames.front()) / span_s;
  std::printf("%-10s track %6.1f estimates/s, camera %6.1f frames/s, ratio %.3f; latency median "
              "%.3f ms, p95 %.3f ms, max %.3f ms; skipped %.0f, lost %.0f; CPU per frame median "
              "%.3f ms, p95 %.3f ms\n",
              label.c_str(), estimates_per_s, camera_per_s, estimates_per_s / camera_per_s,
              Quantile(latency_ms, 0.5), Quantile(latency_ms, 0.95),
              *std::max_element(latency_ms.begin(), latency_ms.end()), skipped.back(),
              lost.back(), Quantile(cpu_ms, 0.5), Quantile(cpu_ms, 0.95));
  std::fflush(stdout);  // each run's line kept, whatever follows
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  int count = 60, frames = 300;
  std::string rig = "virtual";
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word == "--rig" && i + 1 < argc) {
      rig = argv[++i];
    } else if (word == "--track" && i + 1 < argc) {
      frames = std::max(3, std::stoi(argv[++i]));
    } else {
      count = std::max(3, std::stoi(word));
    }
  }
  const std::string dir = (std::filesystem::temp_directory_path() /
                           ("irdist-measure-live-" + std::to_string(::getpid())))
                              .string();
  const std::string recipe = std::string(IRDIST_SOURCE_DIR) + "/recipes/table3-calibration.yaml";
  std::string out;
  if (Run({"irdist", "calibrate", recipe, "--out", dir + "/cal", "--time-scale", "10", "--quiet"},
          &out) != 0) {
    std::cerr << "bench_measure_live: the calibration failed\n" << out;
    return 1;
  }
  const irdist::Recipe r = irdist::LoadRecipe(recipe);
  double bound_ms = r.sweep.bracket.t_ref_ms;
  for (double t : r.sweep.bracket.t_meas_ms) bound_ms += t;
  bound_ms += static_cast<double>(1 + r.sweep.bracket.t_meas_ms.size()) * r.rig.camera.readout_ms;
  const std::string model = dir + "/cal/model.yaml";
  const std::string moments = MomentsModel(model);
  std::printf("rig %s, %d brackets of %zu frames at time scale 1, 256 x 256 ROI\n", rig.c_str(),
              count, 1 + r.sweep.bracket.t_meas_ms.size());
  if (moments.empty() || !MeasureAndPrint("blob fit", model, rig, count, bound_ms) ||
      !MeasureAndPrint("moments", moments, rig, count, bound_ms)) {
    return 1;
  }
  std::printf("tracking %d frames at t_ref %.1f ms, time scale 1, camera bound %.1f frames/s\n",
              frames, r.sweep.bracket.t_ref_ms,
              1000.0 / (r.sweep.bracket.t_ref_ms + r.rig.camera.readout_ms));
  if (!TrackAndPrint("blob fit", model, rig, frames) ||
      !TrackAndPrint("moments", moments, rig, frames)) {
    return 1;
  }
  std::filesystem::remove_all(dir);
  return 0;
}
