#include "app/devices/camera_test.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <functional>
#include <memory>
#include <optional>
#include <sstream>
#include <tuple>

#include "acquisition/aravis_camera.h"
#include "acquisition/bracket.h"
#include "acquisition/linearity.h"
#include "acquisition/pixel_format.h"
#include "acquisition/pixel_pipeline.h"
#include "app/devices/station_setup.h"
#include "app/inputs/camera_settings.h"
#include "app/inputs/rig.h"
#include "app/inputs/rig_lookup.h"

namespace irdist {
namespace {

bool Offers(const FeatureInfo& feature, const std::string& entry) {
  return std::find(feature.entries.begin(), feature.entries.end(), entry) != feature.entries.end();
}

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

std::string Range(const FeatureInfo& feature) {
  if (!feature.min || !feature.max) return "";
  std::ostringstream out;
  out << " [" << *feature.min << ", " << *feature.max << "]";
  return out.str();
}

// The pixel formats irdist reads among those offered, deepest first.
std::vector<std::string> UsableFormats(const FeatureInfo& pixel_format) {
  std::vector<const PixelFormatInfo*> usable;
  for (const std::string& entry : pixel_format.entries) {
    if (const PixelFormatInfo* format = FindPixelFormat(entry)) usable.push_back(format);
  }
  std::stable_sort(usable.begin(), usable.end(), [](const auto* a, const auto* b) {
    return a->bit_depth > b->bit_depth || (a->bit_depth == b->bit_depth && !a->packed && b->packed);
  });
  std::vector<std::string> names;
  for (const PixelFormatInfo* format : usable) names.push_back(format->name);
  return names;
}

CameraCheck PixelFormatCheck(AravisCamera& camera) {
  const FeatureInfo f = camera.Describe("PixelFormat");
  const std::vector<std::string> usable = UsableFormats(f);
  return {"pixel format", !usable.empty(),
          "offers " + Join(f.entries) + (usable.empty() ? "" : "; irdist reads " + Join(usable)),
          "irdist reads " + SupportedPixelFormatNames() +
              ": choose a monochrome camera (12 bits or more for radiometry)"};
}

CameraCheck ExposureTimeCheck(AravisCamera& camera) {
  for (const char* name : {"ExposureTime", "ExposureTimeAbs"}) {
    const FeatureInfo f = camera.Describe(name);
    if (f.present && f.writable) return {"exposure time", true, name + Range(f) + " us", ""};
  }
  return {"exposure time", false, "no writable ExposureTime or ExposureTimeAbs",
          "irdist writes each frame's exposure: the camera needs a writable ExposureTime"};
}

CameraCheck ExposureModeCheck(AravisCamera& camera) {
  const FeatureInfo f = camera.Describe("ExposureMode");
  if (!f.present) return {"timed exposure", true, "no ExposureMode (timed, SFNC)", ""};
  return {"timed exposure", Offers(f, "Timed") && f.writable,
          "ExposureMode offers " + Join(f.entries) + ", now " + f.value,
          "the camera must offer ExposureMode Timed (irdist sets it; a TriggerWidth exposure "
          "would follow the trigger pulse)"};
}

// The frame trigger as irdist picks it (acquisition/aravis_trigger.cc, SFNC): FrameStart, else
// ExposureStart; a read-only selector's own value when it is one of them; "" when none.
std::string FrameTriggerOf(const FeatureInfo& selector) {
  const std::vector<std::string> candidates =
      selector.writable ? selector.entries : std::vector<std::string>{selector.value};
  for (const char* trigger : {"FrameStart", "ExposureStart"}) {
    const auto found = std::find(candidates.begin(), candidates.end(), trigger);
    if (found != candidates.end()) return trigger;
  }
  return "";
}

// The selector entry the trigger's controls are read under ("" for a camera without selector).
std::string FrameSelector(AravisCamera& camera) {
  const FeatureInfo selector = camera.Describe("TriggerSelector");
  return selector.present ? FrameTriggerOf(selector) : "";
}

// The frame trigger: TriggerSelector FrameStart or ExposureStart (a read-only selector taken as
// it is), or a single trigger (SFNC: no selector), with writable mode and source.
CameraCheck FrameTriggerCheck(AravisCamera& camera) {
  const FeatureInfo selector = camera.Describe("TriggerSelector");
  const char* fix =
      "irdist triggers each frame with one timed exposure: the camera needs TriggerSelector "
      "FrameStart or ExposureStart with writable TriggerMode and TriggerSource, or a single "
      "trigger (TriggerMode, TriggerSource)";
  if (selector.present) {
    const std::string trigger = FrameTriggerOf(selector);
    const bool usable = !trigger.empty() && camera.Describe("TriggerMode", trigger).writable &&
                        camera.Describe("TriggerSource", trigger).writable;
    const std::string offered = selector.writable
                                    ? "TriggerSelector offers " + Join(selector.entries)
                                    : "TriggerSelector read-only at " + selector.value;
    return {"frame trigger", usable,
            offered + (trigger.empty() ? "" : "; frame trigger " + trigger), fix};
  }
  const bool single = camera.Describe("TriggerMode").writable &&
                      camera.Describe("TriggerSource").writable;
  return {"frame trigger", single,
          single ? "a single trigger (no TriggerSelector)" : "no TriggerSelector, TriggerMode "
                                                             "or TriggerSource",
          fix};
}

CameraCheck LineInputCheck(AravisCamera& camera) {
  const FeatureInfo source = camera.Describe("TriggerSource", FrameSelector(camera));
  std::vector<std::string> lines;
  for (const std::string& entry : source.entries) {
    if (entry.rfind("Line", 0) == 0) lines.push_back(entry);
  }
  return {"line trigger input", !lines.empty(),
          "TriggerSource offers " + (source.entries.empty() ? "nothing" : Join(source.entries)),
          "the station fires a line input: wire it to one the camera offers and set "
          "camera.trigger_source in the rig file"};
}

CameraCheck AutoOffCheck(AravisCamera& camera) {
  std::vector<std::string> stuck, present;
  for (const char* name : {"ExposureAuto", "GainAuto", "BlackLevelAuto"}) {
    const FeatureInfo f = camera.Describe(name);
    if (!f.present) continue;
    present.push_back(std::string(name) + " " + f.value);
    if (!Offers(f, "Off") || !f.writable) stuck.emplace_back(name);
  }
  return {"automatic controls off", stuck.empty(),
          present.empty() ? "none" : Join(present) + " (irdist turns them Off)",
          "irdist needs fixed exposure, gain and black level: " + Join(stuck) +
              " cannot be Off; choose another camera or firmware"};
}

CameraCheck OtherTriggersCheck(AravisCamera& camera) {
  const FeatureInfo selector = camera.Describe("TriggerSelector");
  if (selector.present && !selector.writable) {
    return {"other triggers off", true,
            "TriggerSelector read-only: no other trigger can be selected", ""};
  }
  const std::string frame = FrameTriggerOf(selector);
  std::vector<std::string> others, stuck;
  for (const std::string& entry : selector.entries) {
    if (entry == frame) continue;
    const FeatureInfo mode = camera.Describe("TriggerMode", entry);
    others.push_back(entry + " " + (mode.present ? mode.value : "-"));
    if (mode.present && (!mode.writable || !Offers(mode, "Off"))) stuck.push_back(entry);
  }
  return {"other triggers off", stuck.empty(),
          others.empty() ? "none" : Join(others) + " (irdist turns them Off)",
          "an AcquisitionStart or burst trigger left on holds frames back: " + Join(stuck) +
              " cannot be Off"};
}

CameraCheck FrameRateLimitCheck(AravisCamera& camera) {
  std::string name = "AcquisitionFrameRateEnable";
  FeatureInfo enable = camera.Describe(name);
  if (!enable.present) enable = camera.Describe(name = "AcquisitionFrameRateEnabled");
  if (!enable.present) return {"frame-rate limit off", true, "no AcquisitionFrameRateEnable", ""};
  return {"frame-rate limit off", enable.writable,
          name + " " + enable.value + " (irdist sets it false when triggered)",
          "a frame-rate limit delays triggered frames: " + name + " must be writable"};
}

CameraCheck PacketResendCheck(AravisCamera& camera) {
  const bool resend = camera.DeclaresPacketResend();
  return {"packet resend", resend,
          resend ? "declared (GVCP PACKETRESEND)" : "not declared: a lost packet loses its frame",
          "a camera without packet resend loses a frame for each lost packet: prefer one with "
          "resend, or give it a direct link (no switch), jumbo frames and a large socket buffer"};
}

// What makes brackets faster (never a failure).
std::vector<CameraCheck> SpeedNotes(AravisCamera& camera) {
  const FeatureInfo chunk = camera.Describe("ChunkExposureTime");
  const FeatureInfo overlap = camera.Describe("TriggerOverlap");
  return {{"exposure chunks", true,
           chunk.present ? "ChunkExposureTime declared: brackets pipelined while frames carry it "
                           "(triggered frames, below)"
                         : "no ChunkExposureTime: each exposure read back before its trigger",
           ""},
          {"trigger in readout", true,
           Offers(overlap, "ReadOut") ? "TriggerOverlap ReadOut (rig: trigger_in_readout: true)"
                                      : "no TriggerOverlap ReadOut: trigger after each frame",
           ""}};
}

// What the setup left for the rows after it.
struct SetupOutcome {
  bool configured = false;
  bool software = false;
  int bit_depth = 12;
};

// A run's settings (`run`: the rig file's camera section, app/inputs/camera_settings.h), or a
// run's defaults without a rig file (the whole sensor, exposure evidence auto) with the deepest
// format the camera offers. The frames are software-triggered when the camera offers it, whatever
// line a run fires (the setup row names it).
CameraSettings TestSettings(AravisCamera& camera, const CameraSettings* run, bool* software) {
  CameraSettings settings = run != nullptr ? *run : CameraSettingsOf(CameraConfig{}, "Line1");
  if (run == nullptr) {
    const std::vector<std::string> formats = UsableFormats(camera.Describe("PixelFormat"));
    if (!formats.empty()) settings.pixel_format = formats.front();
  }
  const FeatureInfo source = camera.Describe("TriggerSource", FrameSelector(camera));
  *software = Offers(source, "Software") && camera.Describe("TriggerSoftware").present;
  if (*software) {
    settings.trigger_source = "Software";
  } else if (run == nullptr) {
    for (const std::string& entry : source.entries) {
      if (entry.rfind("Line", 0) == 0) settings.trigger_source = entry;
    }
  }
  return settings;
}

// The setup row's text: the format, the region and the trigger a run configures.
std::string SetupFound(const CameraSettings& settings, const CameraSettings* run) {
  std::ostringstream out;
  out << settings.pixel_format << ", ";
  if (settings.width == 0) {
    out << "the whole sensor";
  } else {
    out << settings.width << " x " << settings.height << " at (" << settings.offset_x << ", "
        << settings.offset_y << ")";
  }
  out << ", " << settings.trigger_source << " trigger";
  if (run != nullptr && run->trigger_source != settings.trigger_source) {
    out << " (a run fires " << run->trigger_source << ")";
  }
  out << (run != nullptr ? "; the rig file's camera settings" : "; a run's defaults (no rig file)");
  return out.str();
}

// Three software-triggered frames at three exposures, taken as a run takes a bracket (the same
// BracketCapture, exposure_check and fallback): whole, and each with its exposure's evidence.
CameraCheck TriggeredFramesCheck(AravisCamera& camera, double exposure_us) {
  BracketOptions options;
  options.exposures_us = {exposure_us, 1.5 * exposure_us, 2.0 * exposure_us};
  options.trigger_source = "Software";
  options.frame_timeout = std::chrono::milliseconds(3000);
  BracketCapture capture(camera, options);
  const BracketResult result = capture.Capture([&camera](int) { camera.SoftwareTrigger(); });
  camera.StopStream();
  int from_chunk = 0;
  for (const BracketFrame& frame : result.frames) from_chunk += frame.exposure_from_chunk ? 1 : 0;
  std::string found = std::to_string(result.frames.size()) + " of 3 software-triggered";
  if (!result.frames.empty()) {
    found += from_chunk == static_cast<int>(result.frames.size())
                 ? ", each exposure checked by its ChunkExposureTime (brackets pipelined)"
                 : ", exposures read back before each trigger (" +
                       std::string(ExposureCheckName(camera.exposure_check())) + ")";
  }
  if (!capture.stats().exposure_notice.empty()) {
    found += "; a run falls back the same way: " + capture.stats().exposure_notice;
  }
  return {"triggered frames", result.complete, found,
          result.failure.empty() ? "check the network path (cable, MTU, firewall for UDP from "
                                   "the camera)"
                                 : result.failure};
}

// Configures the camera as a run would and takes three software-triggered frames.
std::vector<CameraCheck> SetupAndFrames(AravisCamera& camera, const CameraSettings* run,
                                        SetupOutcome* outcome) {
  bool software = false;
  const CameraSettings settings = TestSettings(camera, run, &software);
  camera.Configure(settings);  // a CameraError becomes the setup row's FAIL (RunCameraChecks)
  outcome->configured = true;
  outcome->software = software;
  outcome->bit_depth = FindPixelFormat(settings.pixel_format)->bit_depth;
  CameraCheck setup{"setup", true, SetupFound(settings, run), ""};
  if (!software) return {setup, {"triggered frames", true, "not taken: no software trigger", ""}};
  return {setup, TriggeredFramesCheck(camera, settings.exposure_us)};
}

// A raw mosaic (PixelColorFilter other than None) fails; a colour camera whose Mono output it
// interpolates itself is named and passes (docs/devices/README.md: what irdist does with each).
CameraCheck ColourCheck(AravisCamera& camera) {
  const std::string colour = camera.ColourSensor();
  const bool raw_mosaic = colour.rfind("PixelColorFilter", 0) == 0;
  return {"monochrome sensor", !raw_mosaic,
          colour.empty() ? "no colour filter (no PixelColorFilter, no Bayer format)"
          : raw_mosaic   ? "raw colour mosaic: " + colour
                         : "colour sensor (" + colour + "): its Mono output is interpolated by the "
                                                        "camera (accepted, linearity measured)",
          "irdist refuses a raw colour mosaic (the filters modulate the blob's gray levels pixel "
          "by pixel; docs/devices/README.md): use a monochrome camera"};
}

// The pixel-shaping features the camera has (acquisition/pixel_pipeline.h), as found -> as set.
CameraCheck PixelPipelineCheck(AravisCamera& camera, const SetupOutcome& setup) {
  if (!setup.configured) {
    return {"neutral pixel pipeline", false, "not checked: the setup failed",
            "fix the setup first"};
  }
  std::vector<std::string> rows;
  for (const PixelFeatureState& state : camera.PixelPipeline()) {
    rows.push_back(state.feature + " " + state.found +
                   (state.found == state.now ? "" : " -> " + state.now));
  }
  const std::string not_neutral = NotNeutralSummary(camera.PixelPipeline());
  return {"neutral pixel pipeline", not_neutral.empty(),
          rows.empty() ? "none of the known pixel-shaping features" : Join(rows),
          "irdist could not set these neutral: " + not_neutral +
              "; switch them off with the vendor's tool (or load its default user set)"};
}

// The exposure series on the scene (acquisition/linearity.h): the shortest exposure as the dark
// frame, software-triggered.
CameraCheck LinearityCheck(AravisCamera& camera, const SetupOutcome& setup) {
  const char* fix =
      "the response is not a straight line: a LUT, a gamma curve, a contrast feature or "
      "saturation bends it; switch it off (or dim the scene) and run again";
  if (!setup.configured) return {"linearity", false, "not measured: the setup failed", fix};
  if (!setup.software) {
    return {"linearity", true, "not measured: no software trigger (a calibration's first pose "
                               "measures it)", ""};
  }
  const auto [min_us, max_us] = camera.ExposureBoundsUs();
  const LinearityResult result =
      MeasureCameraLinearity(camera, [&camera] { camera.SoftwareTrigger(); }, 10000.0, min_us,
                             std::min(max_us, 200000.0), setup.bit_depth, LinearityOptions{});
  if (!result.measured && result.why.rfind("no light", 0) == 0) {
    return {"linearity", false, "not measured: " + result.why,
            "point the camera at a lit scene (the IRED on) and run again"};
  }
  return {"linearity", result.Passed(), result.BriefReport(), fix};
}

// However the rows before it ended (a failed linearity series leaves the stream running), the
// stream is stopped first, then the camera put back.
CameraCheck PutBackCheck(AravisCamera& camera) {
  const std::string outcome = camera.LeaveAsFound(true);
  const bool ok = outcome.find("could not") == std::string::npos;
  return {"camera put back", ok, outcome.empty() ? "nothing changed" : outcome,
          "power-cycle the camera before another application uses it"};
}

}  // namespace

std::vector<CameraCheck> RunCameraChecks(AravisCamera& camera,
                                         const std::vector<CameraCheckStep>& steps) {
  std::vector<CameraCheck> checks;
  for (const CameraCheckStep& step : steps) {
    try {
      for (CameraCheck& check : step.run(camera)) checks.push_back(std::move(check));
    } catch (const std::exception& error) {
      checks.push_back({step.name, false, error.what(), step.fix});
    }
  }
  return checks;
}

std::vector<CameraCheckStep> CameraCheckSteps(const CameraSettings* run) {
  using Rows = std::vector<CameraCheck>;
  auto one = [](CameraCheck (*check)(AravisCamera&)) {
    return [check](AravisCamera& camera) { return Rows{check(camera)}; };
  };
  auto setup = std::make_shared<SetupOutcome>();
  const char* again = "fix what the message names, then run camera-test again";
  return {
      {"pixel format", again, one(PixelFormatCheck)},
      {"monochrome sensor", again, one(ColourCheck)},
      {"exposure time", again, one(ExposureTimeCheck)},
      {"timed exposure", again, one(ExposureModeCheck)},
      {"frame trigger", again, one(FrameTriggerCheck)},
      {"line trigger input", again, one(LineInputCheck)},
      {"automatic controls off", again, one(AutoOffCheck)},
      {"other triggers off", again, one(OtherTriggersCheck)},
      {"frame-rate limit off", again, one(FrameRateLimitCheck)},
      {"packet resend", again, one(PacketResendCheck)},
      {"speed notes", again, SpeedNotes},
      {"setup", "fix the failures above, then run camera-test again",
       [setup, run = run != nullptr ? std::optional<CameraSettings>(*run) : std::nullopt](
           AravisCamera& camera) { return SetupAndFrames(camera, run ? &*run : nullptr,
                                                          setup.get()); }},
      {"neutral pixel pipeline", again,
       [setup](AravisCamera& camera) { return Rows{PixelPipelineCheck(camera, *setup)}; }},
      {"linearity", again,
       [setup](AravisCamera& camera) { return Rows{LinearityCheck(camera, *setup)}; }},
      {"camera put back", "power-cycle the camera before another application uses it",
       one(PutBackCheck)},
  };
}

std::vector<CameraCheck> CheckCamera(AravisCamera& camera, const CameraSettings* run) {
  return RunCameraChecks(camera, CameraCheckSteps(run));
}

std::string CameraCheckTable(const std::vector<CameraCheck>& checks) {
  std::ostringstream out;
  int passed = 0;
  for (const CameraCheck& c : checks) {
    char head[64];
    std::snprintf(head, sizeof(head), "%-4s  %-24s  ", c.passed ? "PASS" : "FAIL", c.name.c_str());
    out << head << c.found << "\n";
    if (!c.passed) out << "      fix: " << c.fix << "\n";
    passed += c.passed ? 1 : 0;
  }
  out << passed << "/" << checks.size() << " checks passed\n";
  return out.str();
}

void RunCameraTest(const CameraTestArgs& args, CommandIo io) {
  std::string name = args.camera;
  const std::string rig_spec = args.rig.empty() ? "virtual" : args.rig;
  if (name.empty()) {
    const std::optional<RunningSim> sim = FindRunningSim(ResolveRig(rig_spec), io.err);
    if (!sim || sim->values.count("camera_address") == 0) {
      throw UsageError("camera-test: give CAMERA (IP address, Aravis id or serial), or start "
                       "`irdist sim " + rig_spec + "` to test the virtual camera");
    }
    name = sim->values.at("camera_address");
  }
  // A run's settings: the rig file's when given (or the sim's), else a run's defaults.
  std::optional<CameraSettings> run;
  if (!args.rig.empty() || args.camera.empty()) {
    const Rig rig = LoadRig(ResolveRig(rig_spec));
    PrintRigNotes(rig, io.err);
    run = CameraSettingsOf(rig.camera, RigTriggerSource(rig));
  }
  std::unique_ptr<AravisCamera> camera = AravisCamera::Open(name);
  io.out << "camera " << camera->Identity().BriefReport() << "\n";
  const std::vector<CameraCheck> checks = CheckCamera(*camera, run ? &*run : nullptr);
  io.out << CameraCheckTable(checks);
  const auto failures = std::count_if(checks.begin(), checks.end(),
                                      [](const CameraCheck& c) { return !c.passed; });
  if (failures > 0) {
    throw CheckFailedError(name + ": " + std::to_string(failures) +
                           " camera check(s) failed (table above, each with its fix)");
  }
}

}  // namespace irdist
