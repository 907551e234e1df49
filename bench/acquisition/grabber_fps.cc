// Whole-run timing: frames/s that AravisCamera receives from Aravis's fake GigE Vision camera,
// against Aravis's own arv-camera-test-0.8 on the same camera and settings, in one run.
//
//   bench_acquisition_grabber [seconds=4] [rate_hz=1000] [width=512] [height=512]
//
// Both free-run the same fake camera (127.0.0.1, Mono8, width x height, AcquisitionFrameRate
// rate_hz, packet socket disabled) for the same duration; the figure is completed frames per
// second of wall time, and the ratio ours / arv-camera-test.
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <regex>
#include <string>
#include <vector>

#include "acquisition/aravis_camera.h"
#include "tests/acquisition/fake_camera_process.h"

namespace {

struct Run {
  double seconds = 0.0;
  long completed = 0;
  long failed = 0;
};

// Runs arv-camera-test-0.8 with an argument vector (no shell); returns its stdout and stderr.
std::string RunArvCameraTestOutput(const std::vector<std::string>& arguments) {
  std::vector<std::string> words = {"arv-camera-test-0.8"};
  words.insert(words.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (std::string& word : words) argv.push_back(word.data());
  argv.push_back(nullptr);
  int fds[2];
  if (::pipe(fds) != 0) return "";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 2);
  posix_spawn_file_actions_addclose(&actions, fds[0]);
  pid_t pid = -1;
  const int spawned = posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[1]);
  std::string output;
  char buffer[4096];
  ssize_t n = 0;
  while ((n = ::read(fds[0], buffer, sizeof(buffer))) > 0) output.append(buffer, static_cast<size_t>(n));
  ::close(fds[0]);
  int status = 0;
  if (spawned == 0) ::waitpid(pid, &status, 0);
  return output;
}

Run RunArvCameraTest(double seconds, double rate_hz, int width, int height) {
  Run run;
  run.seconds = seconds;
  const std::string output = RunArvCameraTestOutput(
      {"-n", "127.0.0.1", "--no-packet-socket", "-f", std::to_string(rate_hz), "-w",
       std::to_string(width), "-h", std::to_string(height), "--duration=" + std::to_string(seconds)});
  std::smatch match;
  if (std::regex_search(output, match, std::regex("n_completed_buffers\\s*=\\s*(\\d+)"))) {
    run.completed = std::stol(match[1]);
  }
  if (std::regex_search(output, match, std::regex("n_failures\\s*=\\s*(\\d+)"))) {
    run.failed = std::stol(match[1]);
  }
  return run;
}

Run RunOurs(double seconds, double rate_hz, int width, int height, const std::string& serial) {
  auto camera = irdist::AravisCamera::Open("127.0.0.1", serial);
  irdist::CameraSettings settings;
  settings.pixel_format = "Mono8";
  settings.triggered = false;
  settings.frame_rate_hz = rate_hz;
  settings.width = width;
  settings.height = height;
  settings.exposure_us = 1000.0;
  settings.warmup_frames = 0;  // count every frame, as arv-camera-test does
  camera->Configure(settings);
  Run run;
  const auto start = std::chrono::steady_clock::now();
  const auto end = start + std::chrono::duration<double>(seconds);
  camera->StartStream();
  while (std::chrono::steady_clock::now() < end) {
    auto frame = camera->WaitFrame(std::chrono::milliseconds(100));
    if (!frame) continue;
    if (frame->status == irdist::FrameStatus::kOk) {
      ++run.completed;
    } else {
      ++run.failed;
    }
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  camera->StopStream();
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 4.0;
  const double rate_hz = argc > 2 ? std::atof(argv[2]) : 1000.0;
  const int width = argc > 3 ? std::atoi(argv[3]) : 512;
  const int height = argc > 4 ? std::atoi(argv[4]) : 512;
  try {
    irdist::testing::FakeCameraProcess fake("IRDBENCH");
    const Run theirs = RunArvCameraTest(seconds, rate_hz, width, height);
    const Run ours = RunOurs(seconds, rate_hz, width, height, fake.serial());
    const double theirs_fps = theirs.completed / theirs.seconds;
    const double ours_fps = ours.completed / ours.seconds;
    std::printf("settings: fake camera 127.0.0.1, Mono8 %dx%d, AcquisitionFrameRate %g Hz, %g s\n",
                width, height, rate_hz, seconds);
    std::printf("arv-camera-test-0.8 : %8.1f frames/s (%ld completed, %ld failed)\n", theirs_fps,
                theirs.completed, theirs.failed);
    std::printf("irdist AravisCamera : %8.1f frames/s (%ld completed, %ld failed)\n", ours_fps,
                ours.completed, ours.failed);
    std::printf("ratio irdist / arv-camera-test = %.3f\n",
                theirs_fps > 0.0 ? ours_fps / theirs_fps : 0.0);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "bench failed: %s\n", error.what());
    return 1;
  }
  return 0;
}
