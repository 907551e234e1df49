#include "app/devices/camera_test.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>

#include "acquisition/aravis_camera.h"
#include "acquisition/pixel_format.h"
#include "app/devices/tools.h"

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

CameraCheck ExposureCheck(AravisCamera& camera) {
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

// The frame trigger: TriggerSelector FrameStart, or a single trigger (SFNC: no selector).
CameraCheck FrameTriggerCheck(AravisCamera& camera) {
  const FeatureInfo selector = camera.Describe("TriggerSelector");
  const char* fix =
      "irdist triggers each frame: the camera needs TriggerSelector FrameStart with TriggerMode "
      "and TriggerSource, or a single trigger (TriggerMode, TriggerSource)";
  if (selector.present) {
    const FeatureInfo mode = camera.Describe("TriggerMode", "FrameStart");
    return {"frame trigger", Offers(selector, "FrameStart") && mode.writable,
            "TriggerSelector offers " + Join(selector.entries), fix};
  }
  const bool single = camera.Describe("TriggerMode").writable &&
                      camera.Describe("TriggerSource").writable;
  return {"frame trigger", single,
          single ? "a single trigger (no TriggerSelector)" : "no TriggerSelector, TriggerMode "
                                                             "or TriggerSource",
          fix};
}

CameraCheck LineInputCheck(AravisCamera& camera) {
  const bool selector = camera.Describe("TriggerSelector").present;
  const FeatureInfo source = camera.Describe("TriggerSource", selector ? "FrameStart" : "");
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
  std::vector<std::string> others, stuck;
  for (const std::string& entry : selector.entries) {
    if (entry == "FrameStart") continue;
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
  const FeatureInfo enable = camera.Describe("AcquisitionFrameRateEnable");
  if (!enable.present) return {"frame-rate limit off", true, "no AcquisitionFrameRateEnable", ""};
  return {"frame-rate limit off", enable.writable,
          "AcquisitionFrameRateEnable " + enable.value + " (irdist sets it false when triggered)",
          "a frame-rate limit delays triggered frames: AcquisitionFrameRateEnable must be writable"};
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
           chunk.present ? "ChunkExposureTime: brackets pipelined"
                         : "no ChunkExposureTime: each exposure read back before its trigger",
           ""},
          {"trigger in readout", true,
           Offers(overlap, "ReadOut") ? "TriggerOverlap ReadOut (rig: trigger_overlap: readout)"
                                      : "no TriggerOverlap ReadOut: trigger after each frame",
           ""}};
}

// Configures the camera as a run would (Software trigger when offered) and takes three frames.
std::vector<CameraCheck> SetupAndFrames(AravisCamera& camera) {
  const std::vector<std::string> formats = UsableFormats(camera.Describe("PixelFormat"));
  const bool selector = camera.Describe("TriggerSelector").present;
  const FeatureInfo source = camera.Describe("TriggerSource", selector ? "FrameStart" : "");
  CameraSettings settings;
  settings.pixel_format = formats.empty() ? "Mono12" : formats.front();
  // A 512 x 512 region (or the whole sensor when smaller): the features, not the link's capacity.
  for (const auto& [feature, side] : {std::pair{"Width", &settings.width},
                                      std::pair{"Height", &settings.height}}) {
    const FeatureInfo f = camera.Describe(feature);
    *side = f.max ? std::min(512, static_cast<int>(*f.max)) : 0;
  }
  const bool software = Offers(source, "Software") && camera.Describe("TriggerSoftware").present;
  settings.trigger_source = software ? "Software" : "Line1";
  for (const std::string& entry : source.entries) {
    if (!software && entry.rfind("Line", 0) == 0) settings.trigger_source = entry;
  }
  try {
    camera.Configure(settings);
  } catch (const CameraError& error) {
    return {{"setup", false, error.what(), "fix the failures above, then run camera-test again"}};
  }
  CameraCheck setup{"setup", true, settings.pixel_format + ", " + settings.trigger_source + " trigger",
                    ""};
  if (!software) return {setup, {"triggered frames", true, "not taken: no software trigger", ""}};
  camera.StartStream();
  int whole = 0;
  for (int i = 0; i < 3; ++i) {
    camera.SoftwareTrigger();
    const auto frame = camera.WaitFrame(std::chrono::milliseconds(3000));
    if (frame && frame->status == FrameStatus::kOk) ++whole;
  }
  camera.StopStream();
  return {setup,
          {"triggered frames", whole == 3, std::to_string(whole) + " of 3 software-triggered",
           "check the network path (cable, MTU, firewall for UDP from the camera)"}};
}

}  // namespace

std::vector<CameraCheck> CheckCamera(AravisCamera& camera) {
  std::vector<CameraCheck> checks = {
      PixelFormatCheck(camera),  ExposureCheck(camera),       ExposureModeCheck(camera),
      FrameTriggerCheck(camera), LineInputCheck(camera),      AutoOffCheck(camera),
      OtherTriggersCheck(camera), FrameRateLimitCheck(camera), PacketResendCheck(camera)};
  for (CameraCheck& note : SpeedNotes(camera)) checks.push_back(std::move(note));
  for (CameraCheck& check : SetupAndFrames(camera)) checks.push_back(std::move(check));
  return checks;
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
  if (name.empty()) {
    const std::optional<RunningSim> sim = FindRunningSim(ResolveRig(args.rig), io.err);
    if (!sim || sim->values.count("camera_address") == 0) {
      throw UsageError("camera-test: give CAMERA (IP address, Aravis id or serial), or start "
                       "`irdist sim " + args.rig + "` to test the virtual camera");
    }
    name = sim->values.at("camera_address");
  }
  std::unique_ptr<AravisCamera> camera = AravisCamera::Open(name);
  io.out << "camera " << camera->Identity().BriefReport() << "\n";
  const std::vector<CameraCheck> checks = CheckCamera(*camera);
  io.out << CameraCheckTable(checks);
  const auto failures = std::count_if(checks.begin(), checks.end(),
                                      [](const CameraCheck& c) { return !c.passed; });
  if (failures > 0) {
    throw CheckFailedError(name + ": " + std::to_string(failures) +
                           " camera check(s) failed (table above, each with its fix)");
  }
}

}  // namespace irdist
