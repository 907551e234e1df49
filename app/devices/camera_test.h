#pragma once
// `irdist camera-test [CAMERA]`: a camera's GenICam features against what irdist needs, as a
// PASS/FAIL table with the fix for each failure (like station-test), for a lab choosing or setting
// up a camera. Needed: a monochrome pixel format irdist reads, a writable exposure time with timed
// exposure, a frame trigger (TriggerSelector FrameStart, or a single trigger) on a line input,
// automatic controls that can be Off, the other triggers and the frame-rate limit that can be
// turned off, GigE Vision packet resend, a monochrome sensor, a setup and triggered frames that
// work, the pixel-shaping features neutral and a linear response (EMVA 1288 linearity error
// within 1%). Exposure chunks and TriggerOverlap ReadOut are reported as what they make faster.

#include <functional>
#include <string>
#include <vector>

#include "app/inputs/command_args.h"
#include "app/inputs/errors.h"

namespace irdist {

class AravisCamera;

// One line of the table.
struct CameraCheck {
  std::string name;    // e.g. "frame trigger"
  bool passed = false;
  std::string found;   // what the camera has
  std::string fix;     // what to do (failures)
};

// One step of the table: `run` gives its rows; a step that throws gives one FAIL row named `name`
// with the error's message and `fix`, and every other step still runs.
struct CameraCheckStep {
  std::string name;
  std::string fix;
  std::function<std::vector<CameraCheck>(AravisCamera&)> run;
};

// The steps of camera-test, in order: the features, the setup and triggered frames, the neutral
// pixel pipeline, the linearity series, and the camera put back as it was found. The setup is a
// run's Configure: `run`, the rig file's camera settings (app/inputs/camera_settings.h: region,
// pixel format, exposure evidence, black level, packet size), or without one (nullptr) a run's
// defaults (the whole sensor) with the deepest pixel format offered; its frames are
// software-triggered when the camera offers it.
struct CameraSettings;
std::vector<CameraCheckStep> CameraCheckSteps(const CameraSettings* run = nullptr);
std::vector<CameraCheck> RunCameraChecks(AravisCamera& camera,
                                         const std::vector<CameraCheckStep>& steps);

// Every check on an opened camera (RunCameraChecks of CameraCheckSteps). The last checks
// configure it (Software trigger when it has one), take frames and the linearity series, then put
// it back as it was found.
std::vector<CameraCheck> CheckCamera(AravisCamera& camera, const CameraSettings* run = nullptr);
// The table: one line per check, the fix under each failure, the count of checks passed.
std::string CameraCheckTable(const std::vector<CameraCheck>& checks);

// The command: CAMERA (IP address, Aravis id or serial), or the camera of a running `irdist sim`
// of --rig (default virtual); configured with --rig's camera settings when given (or the sim's). Throws CheckFailedError (exit 1) when a check fails.
void RunCameraTest(const CameraTestArgs& args, CommandIo io);

}  // namespace irdist
