// AravisCamera's trigger, as the SFNC defines it. irdist takes one timed exposure per trigger, so
// the frame trigger is FrameStart (starts a frame) or else ExposureStart (starts one frame's
// exposure: with ExposureMode Timed the same thing); every other trigger is turned off. A camera
// whose TriggerSelector is read-only (derived from another setting) or absent (one trigger, SFNC)
// is used as it is when its trigger is a frame trigger and its own controls are writable.
#include <algorithm>

#include "acquisition/aravis_internal.h"

namespace irdist {

namespace {
const char kNoFrameTrigger[] =
    "irdist triggers each frame with one timed exposure: use a camera with a FrameStart or "
    "ExposureStart trigger (irdist camera-test lists what it lacks).";
}  // namespace

// The exposure is the time irdist writes (not the trigger pulse's width, nor automatic).
void AravisCamera::Impl::SetExposureModeTimed() {
  if (!Has("ExposureMode")) return;  // SFNC: absent means Timed
  SetEnum("ExposureMode", "Timed",
          "irdist sets each frame's exposure time: the camera needs ExposureMode Timed (a "
          "TriggerWidth mode would let the trigger pulse set the exposure).");
}

std::string AravisCamera::Impl::ChooseFrameTrigger(const std::vector<std::string>& offered) const {
  for (const char* trigger : {"FrameStart", "ExposureStart"}) {
    if (std::find(offered.begin(), offered.end(), trigger) != offered.end()) return trigger;
  }
  return "";
}

// Every trigger but the frame trigger off (an AcquisitionStart or FrameBurstStart trigger left On
// by a previous user would hold frames back), then the frame trigger selected.
void AravisCamera::Impl::OtherTriggersOff(const std::string& frame) {
  for (const std::string& selector : EnumEntries("TriggerSelector")) {
    if (selector == frame) continue;
    SetEnum("TriggerSelector", selector, "The camera must let irdist select its triggers.");
    if (!Has("TriggerMode")) continue;  // that trigger has no mode to switch
    SetEnum("TriggerMode", "Off",
            "irdist triggers frames with " + frame + " only: every other trigger must be Off.");
  }
  SetEnum("TriggerSelector", frame, kNoFrameTrigger);
}

// The trigger's own controls (mode, source, and the software command for Software) present and
// writable; `what` names the trigger in the message.
void AravisCamera::Impl::RequireTriggerControls(const CameraSettings& s,
                                                const std::string& what) const {
  std::vector<const char*> needed = {"TriggerMode", "TriggerSource"};
  if (s.triggered && s.trigger_source == "Software") needed.push_back("TriggerSoftware");
  std::vector<std::string> missing, read_only;
  for (const char* feature : needed) {
    ArvGcFeatureNode* node = FeatureNode(feature);
    if (node == nullptr) {
      missing.emplace_back(feature);
      continue;
    }
    const ArvGcAccessMode mode = arv_gc_feature_node_get_actual_access_mode(node);
    if (mode != ARV_GC_ACCESS_MODE_RW && mode != ARV_GC_ACCESS_MODE_WO) {
      read_only.emplace_back(feature);
    }
  }
  if (missing.empty() && read_only.empty()) return;
  std::string lacks;
  if (!missing.empty()) lacks = JoinNames(missing) + " missing";
  if (!read_only.empty())
    lacks += (lacks.empty() ? "" : "; ") + JoinNames(read_only) + " read-only";
  throw CameraError("camera " + Name() + ": " + what + " cannot be used as the frame trigger (" +
                    lacks + "). " + kNoFrameTrigger);
}

// The frame trigger selected (and every other off) where the selector is writable; taken as it is
// where the selector is read-only or absent.
void AravisCamera::Impl::SelectFrameTrigger(const CameraSettings& s) {
  frame_trigger.clear();
  if (!Has("TriggerSelector")) {
    RequireTriggerControls(s, "the camera has no TriggerSelector and its single trigger");
    return;
  }
  if (WritableNode("TriggerSelector") == nullptr) {
    const std::string now = GetString("TriggerSelector");
    if (ChooseFrameTrigger({now}).empty()) {
      throw CameraError("camera " + Name() + ": TriggerSelector is read-only and selects " + now +
                        ", not FrameStart or ExposureStart. Set the camera's mode that selects "
                        "its trigger (its manual names it) to a frame trigger. " +
                        kNoFrameTrigger);
    }
    RequireTriggerControls(s, "its read-only TriggerSelector's " + now);
    frame_trigger = now;
    return;
  }
  const std::vector<std::string> offered = EnumEntries("TriggerSelector");
  frame_trigger = ChooseFrameTrigger(offered);
  if (frame_trigger.empty()) {
    throw CameraError("camera " + Name() + ": TriggerSelector offers " + JoinNames(offered) +
                      ", neither FrameStart nor ExposureStart. " + kNoFrameTrigger);
  }
  OtherTriggersOff(frame_trigger);
}

// The frame-rate limit: off when triggered (each trigger starts a frame), the rig's rate when
// free-running with one, left alone otherwise. Older cameras spell the switch ...Enabled.
void AravisCamera::Impl::ConfigureFrameRate(const CameraSettings& s) {
  const char* enable = Has("AcquisitionFrameRateEnable")    ? "AcquisitionFrameRateEnable"
                       : Has("AcquisitionFrameRateEnabled") ? "AcquisitionFrameRateEnabled"
                                                            : nullptr;
  if (s.triggered) {
    if (enable != nullptr) {
      SetBoolean(enable, false, "A frame-rate limit would hold triggered frames back.");
    }
    return;
  }
  if (!(s.frame_rate_hz > 0.0)) return;
  if (enable != nullptr) SetBoolean(enable, true, "The rig asks for a frame rate.");
  RequireWritable(Has("AcquisitionFrameRate") ? "AcquisitionFrameRate" : "AcquisitionFrameRateAbs",
                  "Set camera.frame_rate_hz to 0 in the rig file to leave the rate as it is.");
  GError* error = nullptr;
  arv_camera_set_frame_rate(camera.get(), s.frame_rate_hz, &error);
  ThrowOnError(error, "setting AcquisitionFrameRate", Name());
  const double rate = arv_camera_get_frame_rate(camera.get(), &error);
  ThrowOnError(error, "reading AcquisitionFrameRate", Name());
  CheckFloat("AcquisitionFrameRate", s.frame_rate_hz, rate);
}

// Continuous acquisition, timed exposure, the frame trigger alone (or the free-running rate).
void AravisCamera::Impl::ConfigureTrigger(const CameraSettings& s) {
  if (Has("AcquisitionMode")) {
    SetEnum("AcquisitionMode", "Continuous", "The camera must support continuous acquisition.");
  }
  SetExposureModeTimed();
  SelectFrameTrigger(s);
  const std::string trigger = frame_trigger.empty() ? "its trigger" : frame_trigger;
  SetEnum("TriggerMode", s.triggered ? "On" : "Off",
          "irdist needs TriggerMode On/Off for " + trigger + ".");
  if (s.triggered) {
    SetEnum("TriggerSource", s.trigger_source,
            "Set camera.trigger_source in the rig file to the input wired to the station.");
    if (s.trigger_source != "Software" && Has("TriggerActivation")) {
      SetEnum("TriggerActivation", s.trigger_activation,
              "Set camera.trigger_activation in the rig file to a value the camera offers.");
    }
    if (s.trigger_in_readout && Has("TriggerOverlap")) {
      SetEnum("TriggerOverlap", "ReadOut",
              "Set camera.trigger_in_readout: false in the rig file: this camera has no "
              "ReadOut overlap.");
    }
  }
  ConfigureFrameRate(s);
}

}  // namespace irdist
