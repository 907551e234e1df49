// Whole-run timing: frames/s that AravisCamera receives from Aravis's fake GigE Vision camera,
// against Aravis's own arv-camera-test-0.8 on the same camera and settings, in one run.
//
//   bench_acquisition_grabber [seconds=4] [rate_hz=1000] [width=512] [height=512]
//
// Both free-run the same fake camera (127.0.0.1, Mono8, width x height, AcquisitionFrameRate
// rate_hz, packet socket disabled) for the same duration; the figure is completed frames per
// second of wall time, and the ratio ours / arv-camera-test.
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <regex>
#include <string>

#include "acquisition/aravis_camera.h"
#include "tests/acquisition/fake_camera_process.h"

namespace {

struct Run {
  double seconds = 0.0;
  long completed = 0;
  long failed = 0;
};

Run RunArvCameraTest(double seconds, double rate_hz, int width, int height) {
  char command[512];
  std::snprintf(command, sizeof(command),
                "arv-camera-test-0.8 -n 127.0.0.1 --no-packet-socket -f %g -w %d -h %d "
                "--duration=%g 2>&1",
                rate_hz, width, height, seconds);
  Run run;
  run.seconds = seconds;
  FILE* pipe = ::popen(command, "r");
  if (pipe == nullptr) return run;
  std::string output;
  char line[512];
  while (std::fgets(line, sizeof(line), pipe) != nullptr) output += line;
  ::pclose(pipe);
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
