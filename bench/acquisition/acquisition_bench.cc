// Acquisition benches (Google Benchmark; whole-run timings, each figure set against its bound or
// its peer measured in the same run). Run in a private network namespace (they serve 127.0.0.1):
//   unshare -n bash -c 'ip link set lo up && build/bench/acquisition/bench_acquisition'
//
// BM_BracketRate/pipelined:{1,0}: 5-exposure brackets (8, 24, 12, 36, 16 ms) on the virtual rig's
//   camera in real time (time scale 1), 256 x 256 Mono12, Software trigger. Counters:
//   rate_over_bound = brackets per second / (1 / sum of exposures + readouts), and
//   overhead_ms_per_frame = (seconds per bracket - bound) / frames. pipelined:1 writes the next
//   exposure during readout (the camera sends ChunkExposureTime), pipelined:0 is the serial path
//   (write, read back, trigger, wait).
// BM_GrabberVsArvCameraTest: frames per second that AravisCamera completes from the virtual camera
//   free-running (256 x 256 Mono8, AcquisitionFrameRate 500 Hz, time scale 100), against Aravis's
//   arv-camera-test-0.8 on the same camera and settings in the same run; counter ratio = ours /
//   theirs.
// BM_FullSensorVsArvCameraTest/camera:{0,1,2}: the same comparison like for like at full sensor:
//   0 = Aravis's fake camera (arv-fake-gv-camera-0.8) 2048 x 2048 Mono8, 1 = the same in Mono16,
//   2 = the virtual camera 1280 x 1024 Mono12 (time scale 1). Both free-run at the same
//   AcquisitionFrameRate for the same duration, alternated twice, each with a socket buffer sized
//   for the frame (arv-camera-test -a: its automatic buffer; irdist: 2 payloads, at least 4 MB);
//   counters ratio = ours / theirs (goal >= 1.0) and the frames each failed.
#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numeric>
#include <regex>
#include <string>
#include <vector>

#include "acquisition/aravis_camera.h"
#include "acquisition/bracket.h"
#include "sim/camera_server.h"
#include "sim/virtual_rig.h"
#include "tests/acquisition/fake_camera_process.h"

extern char** environ;

namespace irdist {
namespace {

using Clock = std::chrono::steady_clock;

std::unique_ptr<sim::VirtualRig> StartRig(double time_scale) {
  sim::VirtualRigOverrides overrides;
  overrides.serial = "IRDBENCH1";
  overrides.time_scale = time_scale;
  auto rig = sim::VirtualRig::Start(IRDIST_SOURCE_DIR "/recipes/rigs/virtual.yaml", overrides);
  rig->world().SetPose(1500.0, 0.0, 0.0, false);
  rig->world().SetCurrent(500.0);
  return rig;
}

void BM_BracketRate(benchmark::State& state) {
  auto rig = StartRig(1.0);
  auto camera = AravisCamera::Open(rig->Info().camera_address, rig->Info().serial);
  CameraSettings settings;
  settings.pixel_format = "Mono12";
  settings.trigger_source = "Software";
  settings.width = 256;
  settings.height = 256;
  camera->Configure(settings);
  BracketOptions options;
  options.exposures_us = {8000.0, 24000.0, 12000.0, 36000.0, 16000.0};
  options.trigger_source = "Software";
  options.pipelined = state.range(0) != 0;
  BracketCapture capture(*camera, options);
  const auto trigger = [&](int) { camera->SoftwareTrigger(); };
  capture.Capture(trigger);  // stream started, first frames out of the way
  const double readout_s = rig->physics().camera.readout_ms * 1e-3;
  const double bound_s =
      std::accumulate(options.exposures_us.begin(), options.exposures_us.end(), 0.0) * 1e-6 +
      readout_s * static_cast<double>(options.exposures_us.size());
  std::int64_t brackets = 0, incomplete = 0;
  const auto start = Clock::now();
  for (auto _ : state) {
    if (!capture.Capture(trigger).complete) ++incomplete;
    ++brackets;
  }
  const double per_bracket_s =
      std::chrono::duration<double>(Clock::now() - start).count() / static_cast<double>(brackets);
  state.counters["bound_ms"] = bound_s * 1e3;
  state.counters["bracket_ms"] = per_bracket_s * 1e3;
  state.counters["rate_over_bound"] = bound_s / per_bracket_s;
  state.counters["overhead_ms_per_frame"] =
      (per_bracket_s - bound_s) * 1e3 / static_cast<double>(options.exposures_us.size());
  state.counters["incomplete"] = static_cast<double>(incomplete);
  state.counters["retried"] = static_cast<double>(capture.stats().retried);
  camera->StopStream();
}
BENCHMARK(BM_BracketRate)->ArgName("pipelined")->Arg(1)->Arg(0)->Iterations(20)->UseRealTime()
    ->Unit(benchmark::kMillisecond);

struct FrameRun {
  double seconds = 0.0;
  long completed = 0;
  long failed = 0;
};

// arv-camera-test-0.8 (argv, no shell) with `words` after its name, its report read from a pipe.
FrameRun RunArvCameraTest(double seconds, std::vector<std::string> words) {
  int pipe_fd[2];
  FrameRun run;
  if (::pipe(pipe_fd) != 0) return run;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, pipe_fd[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, pipe_fd[1], STDERR_FILENO);
  posix_spawn_file_actions_addclose(&actions, pipe_fd[0]);
  words.insert(words.begin(), "arv-camera-test-0.8");
  words.push_back("--duration=" + std::to_string(std::lround(seconds)));
  std::vector<char*> argv;
  for (auto& word : words) argv.push_back(word.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(pipe_fd[1]);
  std::string output;
  char chunk[4096];
  for (ssize_t n; spawned == 0 && (n = ::read(pipe_fd[0], chunk, sizeof(chunk))) > 0;) {
    output.append(chunk, static_cast<size_t>(n));
  }
  ::close(pipe_fd[0]);
  if (spawned != 0) return run;
  int status = 0;
  ::waitpid(pid, &status, 0);
  run.seconds = seconds;
  std::smatch match;
  if (std::regex_search(output, match, std::regex(R"(n_completed_buffers\s*=\s*(\d+))"))) {
    run.completed = std::stol(match[1]);
  }
  if (std::regex_search(output, match, std::regex(R"(n_failures\s*=\s*(\d+))"))) {
    run.failed = std::stol(match[1]);
  }
  if (run.completed == 0) std::fprintf(stderr, "arv-camera-test-0.8 said:\n%s\n", output.c_str());
  return run;
}

// Free-running frames, as arv-camera-test takes them (no warm-up frames discarded).
CameraSettings FreeRun(const std::string& pixel_format, int width, int height, double rate_hz) {
  CameraSettings settings;
  settings.pixel_format = pixel_format;
  settings.triggered = false;
  settings.frame_rate_hz = rate_hz;
  settings.width = width;
  settings.height = height;
  settings.exposure_us = 1000.0;
  settings.warmup_frames = 0;  // count every frame, as arv-camera-test does
  return settings;
}

FrameRun RunOurs(const std::string& serial, double seconds, const CameraSettings& settings) {
  auto camera = AravisCamera::Open("127.0.0.1", serial);
  camera->Configure(settings);
  FrameRun run;
  const auto start = Clock::now();
  const auto end = start + std::chrono::duration<double>(seconds);
  camera->StartStream();
  while (Clock::now() < end) {
    auto frame = camera->WaitFrame(std::chrono::milliseconds(100));
    if (!frame) continue;
    (frame->status == FrameStatus::kOk ? run.completed : run.failed) += 1;
  }
  run.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  camera->StopStream();
  return run;
}

// arv-camera-test-0.8 with `theirs_args` and AravisCamera with `ours` on the camera `serial`,
// alternated twice each (so that the host's load drifts over both alike), `seconds` per run; the
// counters: frames per second each, ratio = ours / theirs, incomplete frames each.
void CompareWithArvCameraTest(benchmark::State& state, const std::vector<std::string>& theirs_args,
                              const std::string& serial, const CameraSettings& ours_settings,
                              double seconds) {
  FrameRun theirs, ours;
  for (auto _ : state) {
    for (int round = 0; round < 2; ++round) {
      for (const bool mine : {false, true}) {
        const FrameRun run = mine ? RunOurs(serial, seconds, ours_settings)
                                  : RunArvCameraTest(seconds, theirs_args);
        FrameRun& total = mine ? ours : theirs;
        total.seconds += run.seconds;
        total.completed += run.completed;
        total.failed += run.failed;
      }
    }
  }
  const double theirs_fps = theirs.completed / std::max(theirs.seconds, 1e-9);
  const double ours_fps = ours.completed / std::max(ours.seconds, 1e-9);
  state.counters["arv_camera_test_fps"] = theirs_fps;
  state.counters["irdist_fps"] = ours_fps;
  state.counters["ratio"] = theirs_fps > 0.0 ? ours_fps / theirs_fps : 0.0;
  state.counters["irdist_failed"] = static_cast<double>(ours.failed);
  state.counters["arv_failed"] = static_cast<double>(theirs.failed);
}

void BM_GrabberVsArvCameraTest(benchmark::State& state) {
  auto rig = StartRig(100.0);
  CompareWithArvCameraTest(
      state, {"-n", "127.0.0.1", "--no-packet-socket", "-f", "500", "-w", "256", "-h", "256"},
      rig->Info().serial, FreeRun("Mono8", 256, 256, 500.0), 3.0);
}
BENCHMARK(BM_GrabberVsArvCameraTest)->Iterations(1)->UseRealTime()->Unit(benchmark::kSecond);

struct FullSensorCase {
  const char* pixel_format;
  int width;
  int height;
  double rate_hz;
};

void BM_FullSensorVsArvCameraTest(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  const FullSensorCase cases[] = {
      {"Mono8", 2048, 2048, 25.0}, {"Mono16", 2048, 2048, 25.0}, {"Mono12", 1280, 1024, 25.0}};
  const FullSensorCase& c = cases[which];
  std::unique_ptr<testing::FakeCameraProcess> fake;
  std::unique_ptr<sim::VirtualRig> rig;
  std::string serial;
  if (which < 2) {
    fake = std::make_unique<testing::FakeCameraProcess>("IRDBENCH2");
    serial = fake->serial();
  } else {
    rig = StartRig(1.0);
    serial = rig->Info().serial;
  }
  const std::vector<std::string> theirs_args = {
      "-n", "127.0.0.1", "--no-packet-socket", "-a", "-f", std::to_string(c.rate_hz), "-w",
      std::to_string(c.width), "-h", std::to_string(c.height), "-e", "1000",
      "--features", std::string("PixelFormat=") + c.pixel_format};
  CompareWithArvCameraTest(state, theirs_args, serial,
                           FreeRun(c.pixel_format, c.width, c.height, c.rate_hz), 5.0);
  state.SetLabel(std::string(which < 2 ? "fake " : "virtual ") + std::to_string(c.width) + "x" +
                 std::to_string(c.height) + " " + c.pixel_format);
  state.counters["set_fps"] = c.rate_hz;  // each side's frames lost = (set_fps - fps) x seconds
}
BENCHMARK(BM_FullSensorVsArvCameraTest)->ArgName("camera")->Arg(0)->Arg(1)->Arg(2)
    ->Iterations(1)->UseRealTime()->Unit(benchmark::kSecond);

}  // namespace
}  // namespace irdist

BENCHMARK_MAIN();
