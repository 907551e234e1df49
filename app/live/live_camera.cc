#include "app/live/live_camera.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <ostream>

#include "acquisition/aravis_camera.h"
#include "app/inputs/errors.h"
#include "app/inputs/camera_settings.h"
#include "app/inputs/recipe.h"
#include "app/inputs/rig_lookup.h"
#include "app/processing/frame_features.h"
#include "sim/virtual_rig.h"
#include "station/serial_transport.h"
#include "station/station_client.h"

namespace irdist {

namespace fs = std::filesystem;

struct LiveCamera::Impl {
  std::string rig_path;
  Rig rig;
  // Declared first: the camera and the station link close before the rig stops.
  std::unique_ptr<sim::VirtualRig> virtual_rig;
  std::unique_ptr<AravisCamera> camera;
  std::string trigger_source;
  double time_scale = 1.0;
  int frame_timeout_ms = 1000;
  LiveCameraOptions options;  // as opened, for configuring the camera again
  bool whole_sensor = false;
  std::ostream* err = nullptr;  // the command's, for the camera's state when it closes
};

namespace {

// Places the IRED through the virtual station: home, move, current (the sweep's calls), with a
// progress line per step on `progress` (null: silent), so a user at time scale 1 is not left
// waiting without a word.
void PlaceThroughStation(const std::string& port, const std::vector<double>& at,
                         std::ostream* progress) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto say = [&](const std::string& step) {
    if (progress == nullptr) return;
    const double elapsed_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    char stamp[32];
    std::snprintf(stamp, sizeof(stamp), "[%5.1f s] ", elapsed_s);
    *progress << "--at: " << stamp << step << std::endl;
  };
  SerialTransport transport(port);
  StationClient client(transport);
  client.Identify();
  say("homing the station");
  client.Home();
  char step[160];
  std::snprintf(step, sizeof(step), "setting the IRED current to %.1f mA (settling)", at[3]);
  say(step);
  client.SetCurrent(at[3]);
  std::snprintf(step, sizeof(step), "moving to slide %.1f mm, pan %.2f deg, tilt %.2f deg", at[0],
                at[1], at[2]);
  say(step);
  client.MoveTo({at[0], at[1], at[2]});
  say("at the pose, settled");
}

CameraSettings SettingsOf(const CameraConfig& c, const std::string& trigger_source,
                          const LiveCameraOptions& options) {
  CameraSettings s = CameraSettingsOf(c, trigger_source);
  s.exposure_us = options.first_exposure_us;
  s.buffer_count = std::max(s.buffer_count, options.buffer_count);
  return s;
}

// Where the camera is (its name for Aravis: address or id, and the serial expected there), how
// its frames are fired, and the virtual rig's time scale (1 on hardware).
struct CameraRoute {
  std::string name;
  std::string serial;
  std::string trigger_source;
  double time_scale = 1.0;
};

// A virtual rig of this command's own (stopped with it); --at places the IRED through its station.
CameraRoute StartOwnVirtualRig(const std::string& rig_path, const LiveCameraOptions& options,
                               std::ostream& err, std::unique_ptr<sim::VirtualRig>* virtual_rig) {
  sim::VirtualRigOverrides overrides;
  if (options.time_scale > 0.0) overrides.time_scale = options.time_scale;
  *virtual_rig = sim::VirtualRig::Start(rig_path, overrides);
  const sim::VirtualRigInfo& info = (*virtual_rig)->Info();
  if (!options.quiet) {
    err << "Virtual rig (time scale " << info.time_scale << "):\n" << info.BriefReport();
  }
  if (!options.at.empty()) {
    PlaceThroughStation(info.station_port, options.at, options.quiet ? nullptr : &err);
  } else if (!options.quiet) {
    err << "note: the virtual station's IRED is off until placed; give --at "
           "SLIDE_MM,PAN_DEG,TILT_DEG,BIAS_MA\n";
  }
  return {info.camera_address, info.serial, "Line1", info.time_scale};  // the rig's trigger line
}

// The camera of a running `irdist sim` of the same rig file, fired by software trigger as on a
// bench: the station belongs to the sim (`irdist station` places the IRED), so --at is refused.
CameraRoute UseRunningSim(const RunningSim& sim, const LiveCameraOptions& options,
                          std::ostream& err) {
  const std::string pid = std::to_string(sim.pid);
  if (!options.at.empty()) {
    const std::string station = "'irdist station --rig " + options.rig_spec;
    throw UsageError("--at places the IRED through a virtual rig this command starts, but the "
                     "virtual rig of pid " + pid + " ('irdist sim', " + sim.state_path +
                     ") is running: place the IRED with " + station +
                     " move SLIDE_MM PAN_DEG TILT_DEG' and " + station +
                     " current MA', or stop that sim first.");
  }
  const auto value = [&sim](const char* key) {
    const auto found = sim.values.find(key);
    return found == sim.values.end() ? std::string() : found->second;
  };
  const double read_scale = std::atof(value("time_scale").c_str());
  const double time_scale = read_scale > 0.0 ? read_scale : 1.0;
  err << "using the running virtual rig of pid " << pid << " (camera " << value("camera_address")
      << " serial " << value("serial") << ", time scale " << time_scale
      << "); place the IRED with 'irdist station --rig " << options.rig_spec << "'\n";
  if (options.time_scale > 0.0 && options.time_scale != time_scale) {
    err << "note: --time-scale " << options.time_scale << " ignored: that rig runs at "
        << time_scale << "\n";
  }
  // The sim's trigger line belongs to its station: the host fires each frame, as on a bench.
  return {value("camera_address"), value("serial"), "Software", time_scale};
}

CameraRoute UseHardwareCamera(const Rig& rig, const std::string& rig_path,
                              const LiveCameraOptions& options) {
  if (!options.at.empty()) {
    throw RecipeError(rig_path, 0, 0,
                      "--at places the IRED on a virtual rig only; on hardware place it by hand "
                      "or with 'irdist station'.");
  }
  if (rig.camera.id == "auto") {
    throw RecipeError(rig_path, 0, 0,
                      "camera.id is 'auto', which only a virtual rig can resolve; set it to the "
                      "camera's IP address, Aravis id or serial number.");
  }
  return {rig.camera.id, "", "Software", 1.0};  // no station: the host fires each frame
}

}  // namespace

bool LiveCameraOptions::IsValid(std::string* why) const {
  std::string reason;
  if (rig_spec.empty()) {
    reason = "rig_spec is empty (give --rig a rig name or a rig file)";
  } else if (!(time_scale == 0.0 || (time_scale >= 0.01 && time_scale <= 1000.0))) {
    reason = "time_scale " + std::to_string(time_scale) +
             " is outside 0.01..1000 (simulated seconds per host second; 0 = the rig file's)";
  } else if (!at.empty() && (at.size() != 4 || !(at[3] >= 0.0))) {
    reason = "at must be SLIDE_MM,PAN_DEG,TILT_DEG,BIAS_MA with BIAS_MA >= 0";
  } else if (!(first_exposure_us > 0.0)) {
    reason = "first_exposure_us must be > 0";
  } else if (!(longest_exposure_us >= first_exposure_us)) {
    reason = "longest_exposure_us must be at least first_exposure_us";
  } else if (buffer_count < 1 || buffer_count > 1000) {
    reason = "buffer_count " + std::to_string(buffer_count) + " is outside 1..1000";
  }
  if (why != nullptr) *why = reason;
  return reason.empty();
}

LiveCamera::LiveCamera(const LiveCameraOptions& options, std::ostream& err) : impl_(new Impl) {
  std::string why;
  if (!options.IsValid(&why)) throw UsageError("live camera: " + why);
  Impl& m = *impl_;
  m.options = options;
  m.err = &err;
  m.rig_path = ResolveRig(options.rig_spec);
  m.rig = LoadRig(m.rig_path);
  PrintRigNotes(m.rig, err);
  CameraRoute route;
  if (m.rig.kind != RigKind::kVirtual) {
    route = UseHardwareCamera(m.rig, m.rig_path, options);
  } else if (const std::optional<RunningSim> sim = FindRunningSim(m.rig_path, err)) {
    route = UseRunningSim(*sim, options, err);
  } else {
    route = StartOwnVirtualRig(m.rig_path, options, err, &m.virtual_rig);
  }
  m.trigger_source = route.trigger_source;
  m.time_scale = route.time_scale;
  m.camera = AravisCamera::Open(route.name, route.serial);
  m.camera->Configure(SettingsOf(m.rig.camera, m.trigger_source, options));
  m.frame_timeout_ms =
      m.rig.camera.frame_timeout_ms +
      static_cast<int>(std::ceil(options.longest_exposure_us / 1000.0 / m.time_scale));
}

LiveCamera::~LiveCamera() {
  if (!impl_->camera) return;
  // Done, failed or interrupted alike: stopped, and put back unless the rig says otherwise.
  const std::string outcome = impl_->camera->LeaveAsFound(impl_->rig.camera.restore_after);
  if (!outcome.empty()) *impl_->err << outcome << "\n";
}

const Rig& LiveCamera::rig() const { return impl_->rig; }
const std::string& LiveCamera::rig_path() const { return impl_->rig_path; }
Camera& LiveCamera::camera() { return *impl_->camera; }
std::string LiveCamera::trigger_source() const { return impl_->trigger_source; }
int LiveCamera::frame_timeout_ms() const { return impl_->frame_timeout_ms; }
int LiveCamera::bit_depth() const { return BitDepthOfPixelFormat(impl_->rig.camera.pixel_format); }
bool LiveCamera::whole_sensor() const { return impl_->whole_sensor || impl_->rig.camera.FullFrame(); }

void LiveCamera::SetWholeSensor(bool whole) {
  Impl& m = *impl_;
  if (whole == m.whole_sensor) return;
  if (m.camera->streaming()) m.camera->StopStream();
  CameraSettings settings = SettingsOf(m.rig.camera, m.trigger_source, m.options);
  if (whole) settings.offset_x = settings.offset_y = settings.width = settings.height = 0;
  m.camera->Configure(settings);
  m.whole_sensor = whole;
}

std::function<void(int)> LiveCamera::Trigger() {
  Impl& m = *impl_;
  if (m.virtual_rig) {
    sim::World* world = &m.virtual_rig->world();
    return [world](int) { world->FireTrigger(); };
  }
  Camera* camera = m.camera.get();
  return [camera](int) { camera->SoftwareTrigger(); };
}

}  // namespace irdist
