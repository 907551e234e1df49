#include "acquisition/aravis_camera.h"

#include <arv.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <utility>

#include "base/utc_time.h"

namespace irdist {
namespace {

// --- C API at the edge ----------------------------------------------------------------------------

struct GObjectUnref {
  void operator()(gpointer object) const {
    if (object != nullptr) g_object_unref(object);
  }
};
template <typename T>
using GPtr = std::unique_ptr<T, GObjectUnref>;

// Throws a CameraError naming the failed call, the camera and the caller's line when `error` is
// set; frees the GError.
void ThrowOnError(GError* error, const std::string& what, const std::string& camera,
                  const char* file = __builtin_FILE(), int line = __builtin_LINE()) {
  if (error == nullptr) return;
  std::ostringstream out;
  out << "camera " << camera << ": " << what << " failed: " << error->message << " (" << file
      << ":" << line << "). Check that the camera is powered, reachable and not controlled by "
      << "another application.";
  g_error_free(error);
  throw CameraError(out.str());
}

std::string OrEmpty(const char* text) { return text == nullptr ? std::string() : std::string(text); }

bool LooksLikeIpv4(const std::string& name) {
  int dots = 0;
  for (char c : name) {
    if (c == '.') {
      ++dots;
    } else if (c < '0' || c > '9') {
      return false;
    }
  }
  return dots == 3;
}

bool IsLoopback(const std::string& address) { return address.rfind("127.", 0) == 0; }

FrameStatus MapStatus(ArvBufferStatus status) {
  switch (status) {
    case ARV_BUFFER_STATUS_SUCCESS:
      return FrameStatus::kOk;
    case ARV_BUFFER_STATUS_TIMEOUT:
      return FrameStatus::kTimeout;
    case ARV_BUFFER_STATUS_MISSING_PACKETS:
      return FrameStatus::kMissingPackets;
    case ARV_BUFFER_STATUS_WRONG_PACKET_ID:
      return FrameStatus::kWrongPacketId;
    case ARV_BUFFER_STATUS_SIZE_MISMATCH:
      return FrameStatus::kSizeMismatch;
    case ARV_BUFFER_STATUS_FILLING:
      return FrameStatus::kFilling;
    case ARV_BUFFER_STATUS_ABORTED:
      return FrameStatus::kAborted;
    case ARV_BUFFER_STATUS_CLEARED:
      return FrameStatus::kUnknown;
    case ARV_BUFFER_STATUS_UNKNOWN:
      return FrameStatus::kUnknown;
  }
  return FrameStatus::kUnknown;
}

int BitDepthOf(const std::string& pixel_format) {
  if (pixel_format == "Mono8") return 8;
  if (pixel_format == "Mono10") return 10;
  if (pixel_format == "Mono12") return 12;
  if (pixel_format == "Mono14") return 14;
  return 16;
}

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

// Features read back for recording.yaml, when the camera has them.
const char* const kRecordedFeatures[] = {
    "DeviceVendorName",  "DeviceModelName",   "DeviceSerialNumber", "DeviceID",
    "DeviceFirmwareVersion", "DeviceVersion", "PixelFormat",       "Width",
    "Height",            "OffsetX",           "OffsetY",            "BinningHorizontal",
    "BinningVertical",   "ExposureMode",      "ExposureAuto",       "ExposureTime",
    "ExposureTimeAbs",   "GainAuto",          "GainSelector",       "Gain",
    "GainRaw",           "BlackLevelAuto",    "BlackLevelSelector", "BlackLevel",
    "BlackLevelRaw",     "Gamma",             "GammaEnable",        "AcquisitionMode",
    "AcquisitionFrameRate", "TriggerSelector", "TriggerMode",       "TriggerSource",
    "TriggerActivation", "TriggerDelay",      "TriggerDelayAbs",    "ChunkModeActive",
    "PayloadSize",       "GevSCPSPacketSize", "GevSCPD",            "DeviceTemperature",
    "SensorWidth",       "SensorHeight",
};

}  // namespace

// --- DeviceInfo / identity ------------------------------------------------------------------------

std::string CameraIdentity::BriefReport() const {
  std::ostringstream out;
  out << vendor << " " << model << " serial " << serial << " firmware " << firmware;
  if (!address.empty()) out << " at " << address;
  return out.str();
}

std::vector<DeviceInfo> ListCameras() {
  arv_update_device_list();
  std::vector<DeviceInfo> devices;
  const unsigned int count = arv_get_n_devices();
  for (unsigned int i = 0; i < count; ++i) {
    DeviceInfo info;
    info.id = OrEmpty(arv_get_device_id(i));
    info.vendor = OrEmpty(arv_get_device_vendor(i));
    info.model = OrEmpty(arv_get_device_model(i));
    info.serial = OrEmpty(arv_get_device_serial_nbr(i));
    info.address = OrEmpty(arv_get_device_address(i));
    info.protocol = OrEmpty(arv_get_device_protocol(i));
    devices.push_back(std::move(info));
  }
  return devices;
}

DeviceInfo ResolveCamera(const std::string& id_serial_or_ip,
                         const std::vector<DeviceInfo>& devices) {
  for (const auto& device : devices) {
    if (device.id == id_serial_or_ip || device.serial == id_serial_or_ip) return device;
  }
  std::vector<std::string> names;
  for (const auto& device : devices) names.push_back(device.id + " (" + device.address + ")");
  throw CameraError("no camera named '" + id_serial_or_ip + "' (id, serial or IP) answers; " +
                    "cameras found: [" + Join(names) +
                    "]. Check power and cabling, or give the camera's IP address in the rig "
                    "file (camera: id:).");
}

// --- Impl -----------------------------------------------------------------------------------------

struct AravisCamera::Impl {
  GPtr<ArvCamera> camera;
  GPtr<ArvStream> stream;
  GPtr<ArvChunkParser> chunk_parser;
  CameraIdentity identity;
  CameraSettings settings;
  bool configured = false;
  bool streaming = false;
  bool exposure_chunks = false;
  int payload_bytes = 0;
  int packet_size = 0;
  int bit_depth = 16;
  int warmup_discarded = 0;
  double exposure_min_us = 0.0;
  double exposure_max_us = 0.0;
  std::string pixel_format;

  std::string Name() const { return identity.serial + "@" + identity.address; }
  ArvDevice* Device() const { return arv_camera_get_device(camera.get()); }

  bool Has(const char* feature) const {
    GError* error = nullptr;
    const gboolean available = arv_camera_is_feature_available(camera.get(), feature, &error);
    if (error != nullptr) {
      g_error_free(error);
      return false;
    }
    return available != FALSE;
  }

  std::string GetString(const char* feature) {
    GError* error = nullptr;
    const char* value = arv_camera_get_string(camera.get(), feature, &error);
    ThrowOnError(error, std::string("reading ") + feature, Name());
    return OrEmpty(value);
  }

  std::vector<std::string> EnumEntries(const char* feature) {
    GError* error = nullptr;
    guint count = 0;
    const char** entries =
        arv_camera_dup_available_enumerations_as_strings(camera.get(), feature, &count, &error);
    ThrowOnError(error, std::string("listing ") + feature, Name());
    std::vector<std::string> out;
    for (guint i = 0; i < count; ++i) out.emplace_back(OrEmpty(entries[i]));
    g_free(static_cast<void*>(entries));
    return out;
  }

  // Sets an enumeration feature and reads it back. `why` explains what the value is for.
  void SetEnum(const char* feature, const std::string& value, const std::string& fix) {
    if (!Has(feature)) {
      throw CameraError("camera " + Name() + " has no feature " + feature + " (needed to set it to " +
                        value + "). " + fix);
    }
    const std::vector<std::string> entries = EnumEntries(feature);
    if (std::find(entries.begin(), entries.end(), value) == entries.end()) {
      throw CameraError("camera " + Name() + ": " + feature + " cannot be " + value +
                        "; it offers: " + Join(entries) + ". " + fix);
    }
    GError* error = nullptr;
    arv_camera_set_string(camera.get(), feature, value.c_str(), &error);
    ThrowOnError(error, std::string("setting ") + feature + "=" + value, Name());
    const std::string back = GetString(feature);
    if (back != value) {
      throw CameraError("camera " + Name() + ": " + feature + " was set to " + value +
                        " but reads back " + back + ". " + fix);
    }
  }

  // Sets an "...Auto" enumeration to Off when the camera has it (absent = nothing automatic).
  void AutoOff(const char* feature) {
    if (!Has(feature)) return;
    SetEnum(feature, "Off", "Automatic control must be off for radiometric measurements.");
  }

  void CheckFloat(const char* feature, double wanted, double got) const {
    const double tolerance = std::max(1e-6, settings.readback_tolerance * std::fabs(wanted));
    if (std::fabs(got - wanted) > tolerance) {
      std::ostringstream out;
      out << "camera " << Name() << ": " << feature << " was set to " << wanted
          << " but reads back " << got
          << " (the camera clamped or rounded it). Use a value within the camera's range.";
      throw CameraError(out.str());
    }
  }

  void SetRegion(const CameraSettings& s) {
    GError* error = nullptr;
    gint width_min = 0, width_max = 0, height_min = 0, height_max = 0;
    arv_camera_get_width_bounds(camera.get(), &width_min, &width_max, &error);
    ThrowOnError(error, "reading Width bounds", Name());
    arv_camera_get_height_bounds(camera.get(), &height_min, &height_max, &error);
    ThrowOnError(error, "reading Height bounds", Name());
    // Offsets first at 0 so the full size is allowed, then the size, then the offsets.
    const bool has_offsets = Has("OffsetX") && Has("OffsetY");
    if (has_offsets) {
      arv_camera_set_integer(camera.get(), "OffsetX", 0, &error);
      ThrowOnError(error, "setting OffsetX", Name());
      arv_camera_set_integer(camera.get(), "OffsetY", 0, &error);
      ThrowOnError(error, "setting OffsetY", Name());
      arv_camera_get_width_bounds(camera.get(), &width_min, &width_max, &error);
      ThrowOnError(error, "reading Width bounds", Name());
      arv_camera_get_height_bounds(camera.get(), &height_min, &height_max, &error);
      ThrowOnError(error, "reading Height bounds", Name());
    } else if (s.offset_x != 0 || s.offset_y != 0) {
      throw CameraError("camera " + Name() +
                        " has no OffsetX/OffsetY; set the region offsets to 0 in the rig file.");
    }
    const int width = s.width > 0 ? s.width : width_max;
    const int height = s.height > 0 ? s.height : height_max;
    const std::pair<const char*, int> wanted[] = {
        {"Width", width}, {"Height", height}, {"OffsetX", s.offset_x}, {"OffsetY", s.offset_y}};
    for (const auto& [feature, value] : wanted) {
      if (!has_offsets && (std::strcmp(feature, "OffsetX") == 0 ||
                           std::strcmp(feature, "OffsetY") == 0)) {
        continue;
      }
      arv_camera_set_integer(camera.get(), feature, value, &error);
      ThrowOnError(error, std::string("setting ") + feature, Name());
      const gint64 back = arv_camera_get_integer(camera.get(), feature, &error);
      ThrowOnError(error, std::string("reading ") + feature, Name());
      if (back != value) {
        throw CameraError("camera " + Name() + ": " + feature + " was set to " +
                          std::to_string(value) + " but reads back " + std::to_string(back) +
                          " (width max " + std::to_string(width_max) + ", height max " +
                          std::to_string(height_max) +
                          "). Choose a region inside the sensor and on its increments.");
      }
    }
  }

  // GigE Vision: packet socket off on loopback, the rig's packet size or a negotiated one.
  void SetupPacketSize() {
    if (arv_camera_is_gv_device(camera.get()) == FALSE) return;
    GError* error = nullptr;
    arv_camera_gv_set_stream_options(camera.get(),
                                     IsLoopback(identity.address)
                                         ? ARV_GV_STREAM_OPTION_PACKET_SOCKET_DISABLED
                                         : ARV_GV_STREAM_OPTION_NONE);
    if (settings.packet_size > 0) {
      arv_camera_gv_set_packet_size(camera.get(), settings.packet_size, &error);
      ThrowOnError(error, "setting the packet size", Name());
      const guint back = arv_camera_gv_get_packet_size(camera.get(), &error);
      ThrowOnError(error, "reading the packet size", Name());
      if (static_cast<int>(back) != settings.packet_size) {
        throw CameraError("camera " + Name() + ": packet size " +
                          std::to_string(settings.packet_size) + " reads back " +
                          std::to_string(back) +
                          "; use a packet size the network path supports or 0 to negotiate.");
      }
      packet_size = static_cast<int>(back);
    } else {
      packet_size = static_cast<int>(arv_camera_gv_auto_packet_size(camera.get(), &error));
      ThrowOnError(error, "negotiating the packet size", Name());
    }
  }

  // GigE Vision stream: fixed socket buffer, packet resend when the camera supports it (GVCP
  // capability bit), the frame retention.
  void TuneGvStream(ArvStream* raw_stream) {
    if (!ARV_IS_GV_STREAM(raw_stream)) return;
    GError* error = nullptr;
    const int socket_bytes = settings.socket_buffer_bytes > 0
                                 ? settings.socket_buffer_bytes
                                 : std::max(4 << 20, 2 * payload_bytes);
    guint32 capabilities = 0;
    arv_device_read_register(Device(), 0x0934, &capabilities, &error);  // GVCP capability
    ThrowOnError(error, "reading the GVCP capability register", Name());
    const bool resend = (capabilities & (1u << 2)) != 0;  // PACKETRESEND_CMD supported
    g_object_set(raw_stream, "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_FIXED,
                 "socket-buffer-size", socket_bytes, "packet-resend",
                 resend ? ARV_GV_STREAM_PACKET_RESEND_ALWAYS : ARV_GV_STREAM_PACKET_RESEND_NEVER,
                 "frame-retention", static_cast<guint>(settings.frame_retention_ms * 1000),
                 "packet-request-ratio", settings.packet_request_ratio, nullptr);
    gint size_back = 0;
    guint retention_back = 0;
    double ratio_back = 0.0;
    g_object_get(raw_stream, "socket-buffer-size", &size_back, "frame-retention",
                 &retention_back, "packet-request-ratio", &ratio_back, nullptr);
    if (size_back != socket_bytes ||
        retention_back != static_cast<guint>(settings.frame_retention_ms * 1000) ||
        std::fabs(ratio_back - settings.packet_request_ratio) > 1e-9) {
      throw CameraError("camera " + Name() +
                        ": the stream did not keep its socket buffer / frame retention / packet request ratio "
                        "settings; this Aravis version is not supported (need 0.8.x).");
    }
  }

  void SetupStream() {
    GError* error = nullptr;
    stream.reset();
    SetupPacketSize();
    payload_bytes = static_cast<int>(arv_camera_get_payload(camera.get(), &error));
    ThrowOnError(error, "reading PayloadSize", Name());
    if (payload_bytes <= 0) {
      throw CameraError("camera " + Name() + " reports a payload of " +
                        std::to_string(payload_bytes) + " bytes; check Width/Height/PixelFormat.");
    }

    ArvStream* raw_stream = arv_camera_create_stream(camera.get(), nullptr, nullptr, &error);
    ThrowOnError(error, "creating the stream", Name());
    if (raw_stream == nullptr) {
      throw CameraError("camera " + Name() + ": Aravis could not create a stream; check the " +
                        "network interface and firewall (UDP from the camera).");
    }
    stream.reset(raw_stream);

    TuneGvStream(raw_stream);
    for (int i = 0; i < settings.buffer_count; ++i) {
      arv_stream_push_buffer(raw_stream, arv_buffer_new_allocate(payload_bytes));
    }
  }

  // Automatic controls off, gain at its minimum, the rig's black level and gamma.
  void ConfigureAnalog(const CameraSettings& s) {
    AutoOff("ExposureAuto");
    AutoOff("GainAuto");
    AutoOff("BlackLevelAuto");
    GError* error = nullptr;
    if (arv_camera_is_gain_available(camera.get(), nullptr) != FALSE) {
      double gain_min = 0.0, gain_max = 0.0;
      arv_camera_get_gain_bounds(camera.get(), &gain_min, &gain_max, &error);
      ThrowOnError(error, "reading Gain bounds", Name());
      arv_camera_set_gain(camera.get(), gain_min, &error);
      ThrowOnError(error, "setting Gain to its minimum", Name());
      const double gain = arv_camera_get_gain(camera.get(), &error);
      ThrowOnError(error, "reading Gain", Name());
      CheckFloat("Gain", gain_min, gain);
    }
    ConfigureBlackLevel(s);
    if (s.gamma > 0.0 && Has("Gamma")) {
      if (Has("GammaEnable")) {
        arv_camera_set_boolean(camera.get(), "GammaEnable", s.gamma != 1.0, &error);
        ThrowOnError(error, "setting GammaEnable", Name());
      }
      arv_camera_set_float(camera.get(), "Gamma", s.gamma, &error);
      ThrowOnError(error, "setting Gamma", Name());
      const double gamma = arv_camera_get_float(camera.get(), "Gamma", &error);
      ThrowOnError(error, "reading Gamma", Name());
      CheckFloat("Gamma", s.gamma, gamma);
    }
  }

  void ConfigureBlackLevel(const CameraSettings& s) {
    if (s.black_level < 0.0) return;
    GError* error = nullptr;
    if (arv_camera_is_black_level_available(camera.get(), nullptr) != FALSE) {
      arv_camera_set_black_level(camera.get(), s.black_level, &error);
      ThrowOnError(error, "setting BlackLevel", Name());
      const double black = arv_camera_get_black_level(camera.get(), &error);
      ThrowOnError(error, "reading BlackLevel", Name());
      CheckFloat("BlackLevel", s.black_level, black);
    } else if (s.black_level > 0.0) {
      throw CameraError("camera " + Name() + " has no BlackLevel feature but the rig asks for " +
                        std::to_string(s.black_level) +
                        "; set camera.black_level to 0 (or -1 to leave it).");
    }
  }

  // Continuous acquisition, the FrameStart trigger (or the free-running frame rate).
  void ConfigureTrigger(const CameraSettings& s) {
    if (Has("AcquisitionMode")) {
      SetEnum("AcquisitionMode", "Continuous", "The camera must support continuous acquisition.");
    }
    SetEnum("TriggerSelector", "FrameStart",
            "irdist triggers each frame; the camera needs a FrameStart trigger.");
    SetEnum("TriggerMode", s.triggered ? "On" : "Off",
            "irdist needs TriggerMode On/Off for FrameStart.");
    if (s.triggered) {
      SetEnum("TriggerSource", s.trigger_source,
              "Set camera.trigger_source in the rig file to the input wired to the station.");
      if (s.trigger_source != "Software" && Has("TriggerActivation")) {
        SetEnum("TriggerActivation", s.trigger_activation,
                "Set camera.trigger_activation in the rig file to a value the camera offers.");
      }
      if (s.trigger_overlap_readout && Has("TriggerOverlap")) {
        SetEnum("TriggerOverlap", "ReadOut",
                "Set camera.trigger_overlap: off in the rig file: this camera has no ReadOut "
                "overlap.");
      }
    }
    if (!s.triggered && s.frame_rate_hz > 0.0) {
      GError* error = nullptr;
      arv_camera_set_frame_rate(camera.get(), s.frame_rate_hz, &error);
      ThrowOnError(error, "setting AcquisitionFrameRate", Name());
      const double rate = arv_camera_get_frame_rate(camera.get(), &error);
      ThrowOnError(error, "reading AcquisitionFrameRate", Name());
      CheckFloat("AcquisitionFrameRate", s.frame_rate_hz, rate);
    }
  }

  // Exposure chunks, where the camera offers them.
  void ConfigureChunks() {
    exposure_chunks = false;
    chunk_parser.reset();
    if (arv_camera_are_chunks_available(camera.get(), nullptr) == FALSE || !Has("ChunkSelector")) {
      return;
    }
    GError* error = nullptr;
    const std::vector<std::string> chunks = EnumEntries("ChunkSelector");
    if (!settings.exposure_chunks ||
        std::find(chunks.begin(), chunks.end(), "ExposureTime") == chunks.end()) {
      arv_camera_set_chunk_mode(camera.get(), FALSE, &error);  // none left on by a previous client
      ThrowOnError(error, "turning chunk mode off", Name());
      return;
    }
    arv_camera_set_chunks(camera.get(), "ExposureTime", &error);
    ThrowOnError(error, "enabling the ExposureTime chunk", Name());
    chunk_parser.reset(arv_camera_create_chunk_parser(camera.get()));
    exposure_chunks = chunk_parser != nullptr;
  }

  void ReadExposureBounds() {
    if (arv_camera_is_exposure_time_available(camera.get(), nullptr) == FALSE) {
      throw CameraError("camera " + Name() +
                        " has no ExposureTime (or ExposureTimeAbs) feature; irdist needs it.");
    }
    GError* error = nullptr;
    arv_camera_get_exposure_time_bounds(camera.get(), &exposure_min_us, &exposure_max_us, &error);
    ThrowOnError(error, "reading ExposureTime bounds", Name());
  }

  void CheckExposureRange(double exposure_us) const {
    if (exposure_us >= exposure_min_us && exposure_us <= exposure_max_us) return;
    std::ostringstream out;
    out << "camera " << Name() << ": exposure " << exposure_us << " us is outside the camera's "
        << "range [" << exposure_min_us << ", " << exposure_max_us
        << "] us; change the recipe's exposures.";
    throw CameraError(out.str());
  }

  void WriteExposure(double exposure_us) {
    CheckExposureRange(exposure_us);
    GError* error = nullptr;
    arv_camera_set_exposure_time(camera.get(), exposure_us, &error);
    ThrowOnError(error, "setting ExposureTime", Name());
  }

  cv::Mat ToMat(ArvBuffer* buffer) const {
    const int width = arv_buffer_get_image_width(buffer);
    const int height = arv_buffer_get_image_height(buffer);
    size_t size = 0;
    const void* data = arv_buffer_get_image_data(buffer, &size);
    const ArvPixelFormat format = arv_buffer_get_image_pixel_format(buffer);
    cv::Mat out;
    if (data == nullptr || width <= 0 || height <= 0) return out;
    if (format == ARV_PIXEL_FORMAT_MONO_8) {
      if (size < static_cast<size_t>(width) * height) return out;
      cv::Mat view(height, width, CV_8UC1, const_cast<void*>(data));
      view.convertTo(out, CV_16UC1);
    } else if (format == ARV_PIXEL_FORMAT_MONO_10 || format == ARV_PIXEL_FORMAT_MONO_12 ||
               format == ARV_PIXEL_FORMAT_MONO_14 || format == ARV_PIXEL_FORMAT_MONO_16) {
      if (size < static_cast<size_t>(width) * height * 2) return out;
      cv::Mat view(height, width, CV_16UC1, const_cast<void*>(data));
      out = view.clone();
    }
    return out;
  }
};

// --- AravisCamera ---------------------------------------------------------------------------------

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
  d.SetEnum("PixelFormat", settings.pixel_format,
            "Set camera.pixel_format in the rig file to a Mono format the camera offers.");
  d.pixel_format = settings.pixel_format;
  d.bit_depth = BitDepthOf(settings.pixel_format);
  d.ConfigureAnalog(settings);
  d.SetRegion(settings);
  d.ConfigureTrigger(settings);
  d.ConfigureChunks();
  d.ReadExposureBounds();
  SetExposureUs(settings.exposure_us);
  d.SetupStream();
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
  if (impl_->packet_size > 0) values["irdist.PacketSize"] = std::to_string(impl_->packet_size);
  values["irdist.ExposureChunks"] = impl_->exposure_chunks ? "true" : "false";
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

void AravisCamera::StartStream() {
  Impl& d = *impl_;
  IRDIST_CHECK(d.configured && d.stream != nullptr, "StartStream() before Configure()");
  if (d.streaming) return;
  GError* error = nullptr;
  arv_camera_start_acquisition(d.camera.get(), &error);
  ThrowOnError(error, "starting acquisition", d.Name());
  d.streaming = true;
  const bool self_timed = !d.settings.triggered || d.settings.trigger_source == "Software";
  for (int i = 0; self_timed && i < d.settings.warmup_frames; ++i) {
    if (d.settings.triggered) SoftwareTrigger();
    const auto frame = WaitFrame(std::chrono::milliseconds(2000));
    if (!frame) break;  // nothing to warm up with; the capture's retries take over
    ++d.warmup_discarded;
  }
}

int AravisCamera::warmup_discarded() const { return impl_->warmup_discarded; }

void AravisCamera::StopStream() {
  Impl& d = *impl_;
  if (!d.streaming) return;
  d.streaming = false;
  GError* error = nullptr;
  arv_camera_stop_acquisition(d.camera.get(), &error);
  ThrowOnError(error, "stopping acquisition", d.Name());
}

bool AravisCamera::streaming() const { return impl_->streaming; }

std::optional<RawFrame> AravisCamera::WaitFrame(std::chrono::milliseconds timeout) {
  Impl& d = *impl_;
  IRDIST_CHECK(d.stream != nullptr, "WaitFrame() before Configure()");
  const auto timeout_us = static_cast<guint64>(std::max<std::int64_t>(0, timeout.count()) * 1000);
  ArvBuffer* buffer = arv_stream_timeout_pop_buffer(d.stream.get(), timeout_us);
  if (buffer == nullptr) return std::nullopt;
  RawFrame frame;
  // Received: stamped the moment the complete frame is taken from the stream, before any copy.
  frame.host_time_ns = UtcNowNs();
  frame.host_monotonic_ns = MonotonicNowNs();
  frame.status = MapStatus(arv_buffer_get_status(buffer));
  frame.frame_id = arv_buffer_get_frame_id(buffer);
  frame.timestamp_ns = arv_buffer_get_timestamp(buffer);
  frame.bit_depth = d.bit_depth;
  if (frame.status == FrameStatus::kOk) {
    frame.image = d.ToMat(buffer);
    if (frame.image.empty()) frame.status = FrameStatus::kSizeMismatch;
    if (d.exposure_chunks && arv_buffer_has_chunks(buffer) != FALSE) {
      GError* error = nullptr;
      const double chunk = arv_chunk_parser_get_float_value(d.chunk_parser.get(), buffer,
                                                            "ChunkExposureTime", &error);
      if (error == nullptr) {
        frame.chunk_exposure_us = chunk;
      } else {
        g_error_free(error);  // a frame without a readable chunk falls back to the read-back
      }
    }
  }
  arv_stream_push_buffer(d.stream.get(), buffer);
  return frame;
}

int AravisCamera::Flush() {
  Impl& d = *impl_;
  if (d.stream == nullptr) return 0;
  int count = 0;
  while (ArvBuffer* buffer = arv_stream_try_pop_buffer(d.stream.get())) {
    arv_stream_push_buffer(d.stream.get(), buffer);
    ++count;
  }
  return count;
}

void AravisCamera::SoftwareTrigger() {
  GError* error = nullptr;
  arv_camera_software_trigger(impl_->camera.get(), &error);
  ThrowOnError(error, "TriggerSoftware", impl_->Name());
}

bool AravisCamera::HasExposureChunks() const { return impl_->exposure_chunks; }

std::map<std::string, std::uint64_t> AravisCamera::StreamStatistics() const {
  std::map<std::string, std::uint64_t> out;
  if (impl_->stream == nullptr) return out;
  ArvStream* stream = impl_->stream.get();
  const guint count = arv_stream_get_n_infos(stream);
  for (guint i = 0; i < count; ++i) {
    if (arv_stream_get_info_type(stream, i) == G_TYPE_UINT64) {
      out[OrEmpty(arv_stream_get_info_name(stream, i))] = arv_stream_get_info_uint64(stream, i);
    }
  }
  return out;
}

TransferStats AravisCamera::Transfer() const {
  TransferStats out;
  if (impl_->stream == nullptr || !ARV_IS_GV_STREAM(impl_->stream.get())) return out;
  const std::map<std::string, std::uint64_t> infos = StreamStatistics();
  auto get = [&infos](const char* name) {
    const auto it = infos.find(name);
    return it == infos.end() ? std::uint64_t{0} : it->second;
  };
  out.resend_requests = get("n_resend_requests");
  out.resent_packets = get("n_resent_packets");
  out.missing_packets = get("n_missing_packets");
  out.completed_frames = get("n_completed_buffers");
  out.failed_frames = get("n_failures");
  return out;
}

int AravisCamera::PayloadBytes() const { return impl_->payload_bytes; }
int AravisCamera::PacketSizeBytes() const { return impl_->packet_size; }

}  // namespace irdist
