#include "acquisition/aravis_camera.h"

#include <sstream>
#include <utility>

#include "acquisition/aravis_internal.h"
#include "acquisition/pixel_format.h"

namespace irdist {
namespace {

// Features read back for recording.yaml, when the camera has them.
const char* const kRecordedFeatures[] = {
    "DeviceVendorName",  "DeviceModelName",   "DeviceSerialNumber", "DeviceID",
    "DeviceFirmwareVersion", "DeviceVersion", "PixelFormat",       "Width",
    "Height",            "OffsetX",           "OffsetY",            "BinningHorizontal",
    "BinningVertical",   "ExposureMode",      "ExposureAuto",       "ExposureTime",
    "ExposureTimeAbs",   "GainAuto",          "GainSelector",       "Gain",
    "GainRaw",           "BlackLevelAuto",    "BlackLevelSelector", "BlackLevel",
    "BlackLevelRaw",     "Gamma",             "GammaEnable",        "AcquisitionMode",
    "AcquisitionFrameRate", "AcquisitionFrameRateAbs", "AcquisitionFrameRateEnable",
    "TriggerSelector", "TriggerMode", "TriggerSource", "TriggerOverlap",
    "TriggerActivation", "TriggerDelay",      "TriggerDelayAbs",    "ChunkModeActive",
    "PayloadSize",       "GevSCPSPacketSize", "GevSCPD",            "DeviceTemperature",
    "SensorWidth",       "SensorHeight",      "AcquisitionFrameRateEnabled", "PixelColorFilter",
};

// GigE Vision 2.0 bootstrap registers: the primary (controlling) application's port and address.
constexpr guint64 kPrimaryAppPortRegister = 0x0a10;
constexpr guint64 kPrimaryAppAddressRegister = 0x0a14;

// Who holds `device`'s control channel, as its bootstrap registers say (read access needs none).
std::string ControlHolder(ArvDevice* device) {
  guint32 address = 0;
  guint32 port = 0;
  GError* error = nullptr;
  arv_device_read_register(device, kPrimaryAppAddressRegister, &address, &error);
  if (error == nullptr) arv_device_read_register(device, kPrimaryAppPortRegister, &port, &error);
  const bool read = error == nullptr;
  if (!read) g_error_free(error);  // a GigE Vision 1.x camera: the holder unknown
  if (!read || address == 0) return "another application (the camera does not say which)";
  std::ostringstream out;
  out << "the application at " << (address >> 24) << "." << ((address >> 16) & 0xff) << "."
      << ((address >> 8) & 0xff) << "." << (address & 0xff) << " port " << (port & 0xffff)
      << " (the camera's primary application register)";
  return out.str();
}

}  // namespace

// Control first: a GigE Vision camera's control channel (CCP) is taken, or found held by this
// client, before any feature is written; another holder is named when the camera says who.
void TakeControl(ArvCamera* camera, const std::string& name) {
  if (arv_camera_is_gv_device(camera) == FALSE) return;
  ArvGvDevice* device = ARV_GV_DEVICE(arv_camera_get_device(camera));
  if (arv_gv_device_is_controller(device) != FALSE) return;
  GError* error = nullptr;
  const gboolean taken = arv_gv_device_take_control(device, &error);
  if (error != nullptr) g_error_free(error);  // refused: said below with the holder
  if (taken != FALSE && arv_gv_device_is_controller(device) != FALSE) return;
  throw CameraError("camera " + name + " is controlled by " +
                    ControlHolder(ARV_DEVICE(device)) +
                    "; irdist writes no feature without control. Close that application (a "
                    "viewer, another irdist), or wait a few seconds for a crashed one's heartbeat "
                    "to time out, then try again.");
}

std::string CameraIdentity::BriefReport() const {
  std::ostringstream out;
  out << vendor << " " << model << " serial " << serial << " firmware " << firmware;
  if (!address.empty()) out << " at " << address;
  return out.str();
}

AravisCamera::AravisCamera(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

AravisCamera::~AravisCamera() {
  if (impl_ && impl_->streaming) {
    GError* error = nullptr;
    arv_camera_stop_acquisition(impl_->camera.get(), &error);
    if (error != nullptr) g_error_free(error);  // destructor: nothing more to do with a dead link
  }
}

std::unique_ptr<AravisCamera> AravisCamera::Open(const std::string& id_serial_or_ip,
                                                 const std::string& expected_serial) {
  std::string address = id_serial_or_ip;
  std::string wanted_serial = expected_serial;
  if (!LooksLikeIpv4(id_serial_or_ip)) {
    const DeviceInfo found = ResolveCamera(id_serial_or_ip, ListCameras());
    const DeviceInfo* match = &found;
    if (wanted_serial.empty()) wanted_serial = match->serial;
    // Loopback cameras must be opened by address (by id Aravis picks another interface).
    address = match->address.empty() ? id_serial_or_ip : match->address;
  }
  auto impl = std::make_unique<Impl>();
  GError* error = nullptr;
  ArvCamera* camera = arv_camera_new(address.c_str(), &error);
  ThrowOnError(error, "opening", address);
  if (camera == nullptr) {
    throw CameraError("camera " + address + " could not be opened; check that it is reachable.");
  }
  impl->camera.reset(camera);
  impl->identity.address = LooksLikeIpv4(address) ? address : std::string();
  if (arv_camera_is_gv_device(camera) != FALSE && impl->identity.address.empty()) {
    impl->identity.address = address;
  }
  impl->identity.serial = OrEmpty(arv_camera_get_device_serial_number(camera, &error));
  ThrowOnError(error, "reading the serial number", address);
  if (!wanted_serial.empty() && impl->identity.serial != wanted_serial) {
    throw CameraError("camera at " + address + " has serial '" + impl->identity.serial +
                      "', expected '" + wanted_serial +
                      "': another device answers on that address (two cameras on one IP?). Stop "
                      "the other device or fix the rig file's camera id.");
  }
  impl->identity.vendor = OrEmpty(arv_camera_get_vendor_name(camera, &error));
  ThrowOnError(error, "reading the vendor name", impl->Name());
  impl->identity.model = OrEmpty(arv_camera_get_model_name(camera, &error));
  ThrowOnError(error, "reading the model name", impl->Name());
  for (const char* feature : {"DeviceFirmwareVersion", "DeviceVersion"}) {
    if (impl->Has(feature)) {
      impl->identity.firmware = impl->GetString(feature);
      break;
    }
  }
  TakeControl(camera, impl->Name());
  // A previous client (maybe crashed) may have left the camera streaming.
  if (impl->Has("AcquisitionStop")) {
    arv_camera_stop_acquisition(camera, &error);
    ThrowOnError(error, "stopping acquisition after connecting", impl->Name());
  }
  return std::unique_ptr<AravisCamera>(new AravisCamera(std::move(impl)));
}

CameraIdentity AravisCamera::Identity() const { return impl_->identity; }

void AravisCamera::Configure(const CameraSettings& settings) {
  std::string why;
  IRDIST_CHECK(settings.IsValid(&why), why);
  IRDIST_CHECK(!impl_->streaming, "Configure() while streaming; call StopStream() first");
  Impl& d = *impl_;
  d.settings = settings;
  d.stream.reset();
  d.configured = false;
  const std::vector<Impl::SavedFeature> found = d.SaveState();
  const std::vector<std::string> found_unsaved = d.unsaved;
  if (d.found_state.empty()) {  // as before irdist's first setup
    d.found_state = found;
    d.found_unsaved = found_unsaved;
  }
  try {
    d.SetEnum("PixelFormat", settings.pixel_format,
              "Set camera.pixel_format in the rig file to a Mono format the camera offers.");
    d.pixel_format = settings.pixel_format;
    d.bit_depth = FindPixelFormat(settings.pixel_format)->bit_depth;
    d.RefuseRawMosaic();
    d.ConfigureAnalog(settings);
    d.ConfigureGamma(settings);
    d.ConfigurePixelPipeline();
    d.SetRegion(settings);
    d.ConfigureTrigger(settings);
    d.ConfigureChunks();
    d.ReadExposureBounds();
    SetExposureUs(settings.exposure_us);
    d.SetupStream();
  } catch (const CameraError& error) {
    d.stream.reset();
    d.exposure_max_us = 0.0;
    throw CameraError(error.what() + d.RestoreState(found, found_unsaved));
  }
  d.configured = true;
}

std::map<std::string, std::string> AravisCamera::ReadBackFeatures() {
  std::map<std::string, std::string> values;
  for (const char* feature : kRecordedFeatures) {
    ArvGcNode* node = arv_device_get_feature(impl_->Device(), feature);
    if (node == nullptr || !ARV_IS_GC_FEATURE_NODE(node)) continue;
    GError* error = nullptr;
    const char* value = arv_gc_feature_node_get_value_as_string(ARV_GC_FEATURE_NODE(node), &error);
    if (error != nullptr) {
      // Present in the XML but unreadable right now: record why.
      values[feature] = std::string("<unreadable: ") + error->message + ">";
      g_error_free(error);
      continue;
    }
    values[feature] = OrEmpty(value);
  }
  for (const PixelFeatureState& state : impl_->pixel_pipeline) values[state.feature] = state.now;
  const std::string not_neutral = NotNeutralSummary(impl_->pixel_pipeline);
  values["irdist.PixelPipeline"] = not_neutral.empty() ? "neutral" : "not neutral: " + not_neutral;
  const std::string colour = impl_->ColourSensor();
  values["irdist.Sensor"] = colour.empty() ? "monochrome"
                                           : "colour (" + colour + "): Mono output interpolated "
                                             "by the camera";
  if (impl_->configured) {
    values["irdist.FrameTrigger"] =
        impl_->frame_trigger.empty() ? "single trigger" : impl_->frame_trigger;
  }
  if (impl_->packet_size > 0) values["irdist.PacketSize"] = std::to_string(impl_->packet_size);
  values["irdist.ExposureChunks"] = impl_->exposure_chunks ? "true" : "false";
  values["irdist.ExposureCheck"] = ExposureCheckName(impl_->settings.exposure_check);
  if (!impl_->exposure_bounds_note.empty()) {
    values["irdist.ExposureBounds"] = impl_->exposure_bounds_note;
  }
  return values;
}

double AravisCamera::SetExposureUs(double exposure_us) {
  IRDIST_CHECK(exposure_us > 0.0, "exposure_us must be positive, got ", exposure_us);
  Impl& d = *impl_;
  if (!(d.exposure_max_us > 0.0)) d.ReadExposureBounds();
  d.WriteExposure(exposure_us);
  const double back = ExposureUs();
  d.CheckFloat("ExposureTime", exposure_us, back);
  return back;
}

void AravisCamera::WriteExposureUs(double exposure_us) {
  IRDIST_CHECK(exposure_us > 0.0, "exposure_us must be positive, got ", exposure_us);
  Impl& d = *impl_;
  if (!(d.exposure_max_us > 0.0)) d.ReadExposureBounds();
  d.WriteExposure(exposure_us);
}

double AravisCamera::ExposureUs() {
  GError* error = nullptr;
  const double value = arv_camera_get_exposure_time(impl_->camera.get(), &error);
  ThrowOnError(error, "reading ExposureTime", impl_->Name());
  return value;
}

std::vector<PixelFeatureState> AravisCamera::PixelPipeline() const { return impl_->pixel_pipeline; }

std::pair<double, double> AravisCamera::ExposureBoundsUs() const {
  return {impl_->exposure_min_us, impl_->exposure_max_us};
}

std::string AravisCamera::ColourSensor() { return impl_->ColourSensor(); }

std::string AravisCamera::RestoreFound() {
  IRDIST_CHECK(!impl_->streaming, "RestoreFound() while streaming; call StopStream() first");
  if (impl_->found_state.empty()) return "";
  const std::string outcome = impl_->RestoreState(impl_->found_state, impl_->found_unsaved);
  impl_->configured = false;
  impl_->stream.reset();
  return outcome;
}

std::string AravisCamera::LeaveAsFound(bool restore) noexcept {
  try {
    if (impl_->streaming) StopStream();
    if (impl_->found_state.empty()) return "";
    if (!restore) {
      return "The camera is left as irdist set it (camera.restore_after: false in the rig file).";
    }
    std::string outcome = RestoreFound();
    if (!outcome.empty() && outcome.front() == ' ') outcome.erase(0, 1);
    return outcome;
  } catch (const std::exception& error) {
    return std::string("The camera could not be put back as it was found: ") + error.what();
  }
}

FeatureInfo AravisCamera::Describe(const std::string& feature, const std::string& selector) {
  Impl& d = *impl_;
  std::string selected;
  if (!selector.empty()) {
    selected = d.GetString("TriggerSelector");
    const std::string why = d.WriteFeature("", "TriggerSelector", selector);
    if (!why.empty()) throw CameraError("camera " + d.Name() + ": selecting " + why);
  }
  FeatureInfo info;
  info.present = d.Has(feature.c_str());
  ArvGcNode* node = info.present ? arv_device_get_feature(d.Device(), feature.c_str()) : nullptr;
  if (node != nullptr && ARV_IS_GC_FEATURE_NODE(node)) {
    ArvGcFeatureNode* feature_node = ARV_GC_FEATURE_NODE(node);
    info.writable =
        arv_gc_feature_node_get_actual_access_mode(feature_node) == ARV_GC_ACCESS_MODE_RW;
    info.value = d.ValueAsString(feature_node).value_or("");
    if (ARV_IS_GC_ENUMERATION(node)) info.entries = d.EnumEntries(feature.c_str());
    GError* error = nullptr;
    if (ARV_IS_GC_FLOAT(node)) {
      info.min = arv_gc_float_get_min(ARV_GC_FLOAT(node), &error);
      if (error == nullptr) info.max = arv_gc_float_get_max(ARV_GC_FLOAT(node), &error);
    } else if (ARV_IS_GC_INTEGER(node) && !ARV_IS_GC_ENUMERATION(node)) {
      info.min = static_cast<double>(arv_gc_integer_get_min(ARV_GC_INTEGER(node), &error));
      if (error == nullptr) {
        info.max = static_cast<double>(arv_gc_integer_get_max(ARV_GC_INTEGER(node), &error));
      }
    }
    if (error != nullptr) {
      g_error_free(error);  // bounds unknown: left out
      info.min.reset();
      info.max.reset();
    }
  }
  if (!selected.empty()) d.WriteFeature("", "TriggerSelector", selected);
  return info;
}

}  // namespace irdist
