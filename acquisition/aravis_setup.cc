// AravisCamera's setup of what shapes a pixel: region, analog controls, gamma and the neutral
// pixel pipeline (acquisition/pixel_pipeline.h), exposure chunks and the exposure itself.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <utility>

#include "acquisition/aravis_internal.h"

namespace irdist {

namespace {
const char kRegionFix[] = "irdist sets the region of interest: the camera must let it be written.";

// The region asked for, inside the sensor the camera states (its Width and Height bounds with the
// offsets at 0): a camera that stores a size beyond them would read it back as set and deliver
// something else. Refused before anything is written, naming the rig key.
void CheckRegionInside(const std::string& camera, int width, int height, int offset_x,
                       int offset_y, gint width_min, gint width_max, gint height_min,
                       gint height_max) {
  const auto out = [](int low, int value, int high) { return value < low || value > high; };
  if (out(width_min, width, width_max) || out(height_min, height, height_max) ||
      offset_x < 0 || offset_y < 0 || offset_x + width > width_max ||
      offset_y + height > height_max) {
    throw CameraError("camera " + camera + ": the region " + std::to_string(width) + " x " +
                      std::to_string(height) + " at (" + std::to_string(offset_x) + ", " +
                      std::to_string(offset_y) + ") does not fit the sensor (width " +
                      std::to_string(width_min) + ".." + std::to_string(width_max) + ", height " +
                      std::to_string(height_min) + ".." + std::to_string(height_max) +
                      " px, offset + size within them). Set camera.roi_px in the rig file "
                      "inside the sensor (or leave it out for the whole sensor).");
  }
}
}  // namespace

void AravisCamera::Impl::SetRegion(const CameraSettings& s) {
  GError* error = nullptr;
  gint width_min = 0, width_max = 0, height_min = 0, height_max = 0;
  // Offsets first at 0 so the full size is allowed, then the size, then the offsets.
  const bool has_offsets = Has("OffsetX") && Has("OffsetY");
  if (has_offsets) {
    for (const char* offset : {"OffsetX", "OffsetY"}) {
      const std::string why = WriteFeature("", offset, "0");
      if (!why.empty()) throw CameraError("camera " + Name() + ": " + why + ". " + kRegionFix);
    }
  } else if (s.offset_x != 0 || s.offset_y != 0) {
    throw CameraError("camera " + Name() +
                      " has no OffsetX/OffsetY; set the region offsets to 0 in the rig file.");
  }
  arv_camera_get_width_bounds(camera.get(), &width_min, &width_max, &error);
  ThrowOnError(error, "reading Width bounds", Name());
  arv_camera_get_height_bounds(camera.get(), &height_min, &height_max, &error);
  ThrowOnError(error, "reading Height bounds", Name());
  const int width = s.width > 0 ? s.width : width_max;
  const int height = s.height > 0 ? s.height : height_max;
  CheckRegionInside(Name(), width, height, s.offset_x, s.offset_y, width_min, width_max,
                    height_min, height_max);
  const std::pair<const char*, int> wanted[] = {{"Width", width},
                                                {"Height", height},
                                                {"OffsetX", s.offset_x},
                                                {"OffsetY", s.offset_y}};
  for (const auto& [feature, value] : wanted) {
    if (!has_offsets && std::strncmp(feature, "Offset", 6) == 0) continue;
    if (arv_camera_get_integer(camera.get(), feature, &error) != value || error != nullptr) {
      if (error != nullptr) g_error_free(error);
      error = nullptr;
      RequireWritable(feature, kRegionFix);
      arv_camera_set_integer(camera.get(), feature, value, &error);
      ThrowOnError(error, std::string("setting ") + feature, Name());
    }
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

// Automatic controls off, gain at its minimum, the rig's black level.
void AravisCamera::Impl::ConfigureAnalog(const CameraSettings& s) {
  AutoOff("ExposureAuto");
  AutoOff("GainAuto");
  AutoOff("BlackLevelAuto");
  GError* error = nullptr;
  if (arv_camera_is_gain_available(camera.get(), nullptr) != FALSE) {
    double gain_min = 0.0, gain_max = 0.0;
    arv_camera_get_gain_bounds(camera.get(), &gain_min, &gain_max, &error);
    ThrowOnError(error, "reading Gain bounds", Name());
    RequireWritable(Has("Gain") ? "Gain" : "GainRaw",
                    "irdist sets the gain to its minimum (the method's noise model assumes it).");
    arv_camera_set_gain(camera.get(), gain_min, &error);
    ThrowOnError(error, "setting Gain to its minimum", Name());
    const double gain = arv_camera_get_gain(camera.get(), &error);
    ThrowOnError(error, "reading Gain", Name());
    CheckFloat("Gain", gain_min, gain);
  }
  ConfigureBlackLevel(s);
}

void AravisCamera::Impl::ConfigureBlackLevel(const CameraSettings& s) {
  if (s.black_level < 0.0) return;
  GError* error = nullptr;
  if (arv_camera_is_black_level_available(camera.get(), nullptr) != FALSE) {
    RequireWritable(Has("BlackLevel") ? "BlackLevel" : "BlackLevelRaw",
                    "Set camera.black_level to -1 in the rig file to leave it as it is.");
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

// A gamma other than 1 that the rig asks for (1, the neutral value, is the pixel pipeline's).
void AravisCamera::Impl::ConfigureGamma(const CameraSettings& s) {
  if (!(s.gamma > 0.0) || s.gamma == 1.0 || !Has("Gamma")) return;
  const char* fix = "Set camera.gamma to 1 in the rig file (the method needs a linear response).";
  for (const char* enable : {"GammaEnable", "GammaEnabled"}) {
    if (Has(enable)) SetBoolean(enable, true, fix);
  }
  SetFloat("Gamma", s.gamma, fix);
}

// One pixel-shaping feature set to its neutral value when `write` (and not neutral already).
PixelFeatureState AravisCamera::Impl::SetNeutral(const PixelFeatureSpec& spec, const char* feature,
                                                 bool write) {
  ArvGcFeatureNode* node = FeatureNode(feature);
  PixelFeatureState state{spec.what, feature, ValueAsString(node).value_or("<unreadable>"),
                          "",        true,    ""};
  if (write && !IsNeutralValue(state.found, spec.neutral)) {
    state.why = WriteFeature("", feature, spec.neutral);
  }
  state.now = ValueAsString(node).value_or("<unreadable>");
  state.neutral = IsNeutralValue(state.now, spec.neutral);
  if (!state.neutral && state.why.empty()) {
    state.why = write ? "reads back " + state.now : "set by the rig's camera.gamma";
  }
  return state;
}

// Every pixel-shaping feature the camera has, neutral where it can be written (the gamma rows
// only when the rig's gamma is 1). One that cannot be is recorded, not refused: the linearity
// series then says whether it bends the response.
void AravisCamera::Impl::ConfigurePixelPipeline() {
  pixel_pipeline.clear();
  for (const PixelFeatureSpec& spec : PixelPipelineTable()) {
    const bool gamma_row = std::strncmp(spec.what, "gamma", 5) == 0;
    if (gamma_row && !(settings.gamma > 0.0)) continue;  // the rig leaves gamma as it is
    const bool write = *spec.neutral != '\0' && (!gamma_row || settings.gamma == 1.0);
    for (const char* feature : spec.spellings) {
      if (FeatureNode(feature) != nullptr)
        pixel_pipeline.push_back(SetNeutral(spec, feature, write));
    }
  }
}

// "" for a monochrome sensor, else what names it colour: a PixelColorFilter other than None, or
// Bayer pixel formats offered.
std::string AravisCamera::Impl::ColourSensor() {
  if (Has("PixelColorFilter")) {
    const std::string filter = GetString("PixelColorFilter");
    if (filter != "None" && !filter.empty()) return "PixelColorFilter " + filter;
  }
  std::vector<std::string> bayer;
  for (const std::string& entry : EnumEntries("PixelFormat")) {
    if (entry.rfind("Bayer", 0) == 0) bayer.push_back(entry);
  }
  return bayer.empty() ? "" : "Bayer pixel formats " + JoinNames(bayer);
}

// The method's decision on a mosaic (docs/devices/README.md): a raw Mono format on a colour
// filter array (PixelColorFilter names a pattern for the format in use) modulates the blob's gray
// levels pixel by pixel with each filter's transmission at the IRED's wavelength; the blob's
// features (E_rel, F(0,0), Sigma) would carry the pattern, and per-channel flat-field gains would
// hold only at the flat frame's wavelength and angle. irdist refuses it. A colour camera's Mono
// output that it interpolates itself (PixelColorFilter None) is a linear mix of the channels at one
// wavelength: accepted, named in recording.yaml, its linearity measured like any camera's.
void AravisCamera::Impl::RefuseRawMosaic() {
  if (!Has("PixelColorFilter")) return;
  const std::string filter = GetString("PixelColorFilter");
  if (filter.empty() || filter == "None") return;
  throw CameraError("camera " + Name() + ": " + pixel_format +
                    " is a raw colour mosaic "
                    "(PixelColorFilter " +
                    filter +
                    "): the filters modulate the blob's gray "
                    "levels pixel by pixel, and irdist reads distance from them. Use a monochrome "
                    "camera, or a Mono format the camera interpolates itself (PixelColorFilter "
                    "None).");
}

// Exposure chunks, where the camera offers them and camera.exposure_check wants them.
void AravisCamera::Impl::ConfigureChunks() {
  exposure_chunks = false;
  chunk_parser.reset();
  const ExposureCheck check = settings.exposure_check;
  const bool wanted = settings.exposure_chunks &&
                      (check == ExposureCheck::kAuto || check == ExposureCheck::kChunk);
  const bool available =
      arv_camera_are_chunks_available(camera.get(), nullptr) != FALSE && Has("ChunkSelector");
  const std::vector<std::string> chunks =
      available ? EnumEntries("ChunkSelector") : std::vector<std::string>{};
  const bool declared = std::find(chunks.begin(), chunks.end(), "ExposureTime") != chunks.end();
  if (check == ExposureCheck::kChunk && !declared) {
    throw CameraError("camera " + Name() + " does not declare an ExposureTime chunk (ChunkSelector" +
                      " entries: " + (chunks.empty() ? "none" : JoinNames(chunks)) +
                      "), but the rig file asks for camera.exposure_check: chunk. Set it to "
                      "readback (or remove it).");
  }
  if (!available) return;
  GError* error = nullptr;
  const char* fix = "Set camera.exposure_check: readback in the rig file.";
  RequireWritable("ChunkModeActive", fix);
  if (!wanted || !declared) {
    arv_camera_set_chunk_mode(camera.get(), FALSE, &error);  // none left on by a previous client
    ThrowOnError(error, "turning chunk mode off", Name());
    return;
  }
  RequireWritable("ChunkSelector", fix);
  arv_camera_set_chunks(camera.get(), "ExposureTime", &error);
  ThrowOnError(error, "enabling the ExposureTime chunk", Name());
  chunk_parser.reset(arv_camera_create_chunk_parser(camera.get()));
  exposure_chunks = chunk_parser != nullptr;
}

void AravisCamera::Impl::ReadExposureBounds() {
  if (arv_camera_is_exposure_time_available(camera.get(), nullptr) == FALSE) {
    throw CameraError("camera " + Name() +
                      " has no ExposureTime (or ExposureTimeAbs) feature; irdist needs it.");
  }
  GError* error = nullptr;
  arv_camera_get_exposure_time_bounds(camera.get(), &exposure_min_us, &exposure_max_us, &error);
  ThrowOnError(error, "reading ExposureTime bounds", Name());
  exposure_node = FeatureNode(Has("ExposureTime") ? "ExposureTime" : "ExposureTimeAbs");
  CrossCheckExposureBounds();
}

// The exposure feature's own bounds are in microseconds (SFNC); Aravis takes a Basler ace's from
// ExposureTimeRaw, in raw steps of ExposureTimeBaseAbs. The feature's bounds win; a difference is
// named in irdist.ExposureBounds (recording.yaml).
void AravisCamera::Impl::CrossCheckExposureBounds() {
  std::ostringstream note;
  note << "[" << exposure_min_us << ", " << exposure_max_us << "] us";
  exposure_bounds_note = note.str() + " (Aravis)";
  if (exposure_node == nullptr || !ARV_IS_GC_FLOAT(exposure_node)) return;
  GError* error = nullptr;
  const double min_us = arv_gc_float_get_min(ARV_GC_FLOAT(exposure_node), &error);
  const double max_us = error == nullptr ? arv_gc_float_get_max(ARV_GC_FLOAT(exposure_node), &error)
                                         : 0.0;
  if (error != nullptr) {
    g_error_free(error);  // the feature states none: Aravis's kept
    return;
  }
  const std::string name = OrEmpty(arv_gc_feature_node_get_name(exposure_node));
  const bool same = std::fabs(min_us - exposure_min_us) <= 1e-6 * std::max(1.0, min_us) &&
                    std::fabs(max_us - exposure_max_us) <= 1e-6 * std::max(1.0, max_us);
  std::ostringstream out;
  out << "[" << min_us << ", " << max_us << "] us (" << name << ")";
  if (!same) out << "; Aravis reported " << note.str() << ", not microseconds (a raw timebase)";
  exposure_bounds_note = out.str();
  exposure_min_us = min_us;
  exposure_max_us = max_us;
}

void AravisCamera::Impl::CheckExposureRange(double exposure_us) const {
  if (exposure_us >= exposure_min_us && exposure_us <= exposure_max_us) return;
  std::ostringstream out;
  out << "camera " << Name() << ": exposure " << exposure_us << " us is outside the camera's "
      << "range [" << exposure_min_us << ", " << exposure_max_us
      << "] us; change the recipe's exposures.";
  throw CameraError(out.str());
}

// The bracket's hot path: the access mode is the XML's (no round trip), the lock a round trip only
// on a camera whose exposure has one.
void AravisCamera::Impl::WriteExposure(double exposure_us) {
  CheckExposureRange(exposure_us);
  if (exposure_node != nullptr) {
    const ArvGcAccessMode mode = arv_gc_feature_node_get_actual_access_mode(exposure_node);
    GError* error = nullptr;
    const bool locked = arv_gc_feature_node_is_locked(exposure_node, &error) != FALSE;
    ThrowOnError(error, "reading whether the exposure time is locked", Name());
    if ((mode != ARV_GC_ACCESS_MODE_RW && mode != ARV_GC_ACCESS_MODE_WO) || locked) {
      RequireWritable(arv_gc_feature_node_get_name(exposure_node),
                      "irdist writes each frame's exposure time: set ExposureAuto Off and "
                      "ExposureMode Timed, or use a camera whose exposure is writable.");
    }
  }
  GError* error = nullptr;
  arv_camera_set_exposure_time(camera.get(), exposure_us, &error);
  ThrowOnError(error, "setting ExposureTime", Name());
}

}  // namespace irdist
