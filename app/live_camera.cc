#include "app/live_camera.h"

#include <cmath>
#include <filesystem>
#include <ostream>

#include "acquisition/aravis_camera.h"
#include "app/errors.h"
#include "app/offline.h"
#include "app/recipe.h"
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
};

namespace {

std::string ResolveRigSpec(const std::string& spec) {
  if (fs::exists(spec)) return spec;
  const std::string found = FindRigFile(spec, fs::current_path().string());
  if (found.empty()) {
    throw RecipeError(spec, 0, 0,
                      "no such rig: give a rig file (recipes/rigs/virtual.yaml) or the name of "
                      "one in recipes/rigs/ (e.g. virtual).");
  }
  return found;
}

// Places the IRED through the virtual station: home, move, current (the sweep's calls).
void PlaceThroughStation(const std::string& port, const std::vector<double>& at) {
  SerialTransport transport(port);
  StationClient client(transport);
  client.Identify();
  client.Home();
  client.SetCurrent(at[3]);
  client.MoveTo({at[0], at[1], at[2]});
}

CameraSettings SettingsOf(const CameraConfig& c, const std::string& trigger_source,
                          const LiveCameraOptions& options) {
  CameraSettings s;
  s.pixel_format = c.pixel_format;
  s.trigger_source = trigger_source;
  s.trigger_activation = c.trigger_activation;
  s.black_level = c.black_level;
  s.packet_size = c.packet_size;
  s.offset_x = c.roi_offset_x;
  s.offset_y = c.roi_offset_y;
  s.width = c.roi_width;
  s.height = c.roi_height;
  s.exposure_us = options.first_exposure_us;
  s.buffer_count = std::max(s.buffer_count, options.buffer_count);
  return s;
}

}  // namespace

LiveCamera::LiveCamera(const LiveCameraOptions& options, std::ostream& err) : impl_(new Impl) {
  Impl& m = *impl_;
  m.rig_path = ResolveRigSpec(options.rig_spec);
  m.rig = LoadRig(m.rig_path);
  std::string name = m.rig.camera.id;
  std::string serial;
  if (m.rig.kind == RigKind::kVirtual) {
    sim::VirtualRigOverrides overrides;
    if (options.time_scale > 0.0) overrides.time_scale = options.time_scale;
    m.virtual_rig = sim::VirtualRig::Start(m.rig_path, overrides);
    const sim::VirtualRigInfo& info = m.virtual_rig->Info();
    m.time_scale = info.time_scale;
    name = info.camera_address;
    serial = info.serial;
    if (!options.quiet) err << "Virtual rig (time scale " << m.time_scale << "):\n" << info.BriefReport();
    if (!options.at.empty()) {
      PlaceThroughStation(info.station_port, options.at);
    } else if (!options.quiet) {
      err << "note: the virtual station's IRED is off until placed; give --at "
             "SLIDE_MM,PAN_DEG,TILT_DEG,BIAS_MA\n";
    }
    m.trigger_source = "Line1";  // the rig's trigger line
  } else {
    if (!options.at.empty()) {
      throw RecipeError(m.rig_path, 0, 0,
                        "--at places the IRED on a virtual rig only; on hardware place it by hand "
                        "or with 'irdist station'.");
    }
    if (name == "auto") {
      throw RecipeError(m.rig_path, 0, 0,
                        "camera.id is 'auto', which only a virtual rig can resolve; set it to the "
                        "camera's IP address, Aravis id or serial number.");
    }
    m.trigger_source = "Software";  // no station: the host fires each frame
  }
  m.camera = AravisCamera::Open(name, serial);
  m.camera->Configure(SettingsOf(m.rig.camera, m.trigger_source, options));
  m.frame_timeout_ms = m.rig.camera.frame_timeout_ms +
                       static_cast<int>(std::ceil(options.longest_exposure_us / 1000.0 / m.time_scale));
}

LiveCamera::~LiveCamera() {
  if (impl_->camera && impl_->camera->streaming()) {
    try {
      impl_->camera->StopStream();
    } catch (const Error&) {
      // Closing anyway; the camera is released with the object.
    }
  }
}

const Rig& LiveCamera::rig() const { return impl_->rig; }
const std::string& LiveCamera::rig_path() const { return impl_->rig_path; }
Camera& LiveCamera::camera() { return *impl_->camera; }
std::string LiveCamera::trigger_source() const { return impl_->trigger_source; }
int LiveCamera::frame_timeout_ms() const { return impl_->frame_timeout_ms; }
int LiveCamera::bit_depth() const { return BitDepthOfPixelFormat(impl_->rig.camera.pixel_format); }

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
