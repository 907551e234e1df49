// AravisCamera's features: reading them, writing them (each write checked first: Aravis 0.8
// writes a read-only or locked feature without a word), and the state found, saved and put back.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "acquisition/aravis_internal.h"
#include "acquisition/pixel_pipeline.h"

namespace irdist {

void ThrowOnError(GError* error, const std::string& what, const std::string& camera) {
  if (error == nullptr) return;
  std::ostringstream out;
  out << "camera " << camera << ": " << what << " failed: " << error->message
      << ". Check that the camera is powered, reachable and not controlled by another "
      << "application.";
  g_error_free(error);
  throw CameraError(out.str());
}

std::string OrEmpty(const char* text) {
  return text == nullptr ? std::string() : std::string(text);
}

std::string JoinNames(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

bool AravisCamera::Impl::Has(const char* feature) const {
  GError* error = nullptr;
  const gboolean available = arv_camera_is_feature_available(camera.get(), feature, &error);
  if (error != nullptr) {
    g_error_free(error);
    return false;
  }
  return available != FALSE;
}

// The feature's node when the camera implements it and it is available now, else nullptr.
ArvGcFeatureNode* AravisCamera::Impl::FeatureNode(const char* feature) const {
  if (!Has(feature)) return nullptr;
  ArvGcNode* node = arv_device_get_feature(Device(), feature);
  if (node == nullptr || !ARV_IS_GC_FEATURE_NODE(node)) return nullptr;
  return ARV_GC_FEATURE_NODE(node);
}

ArvGcFeatureNode* AravisCamera::Impl::RequireWritable(const char* feature,
                                                      const std::string& fix) const {
  ArvGcFeatureNode* node = FeatureNode(feature);
  const std::string head = "camera " + Name() + ": " + feature;
  if (node == nullptr) {
    throw CameraError(head +
                      " is not available on this camera now, and irdist needs to write "
                      "it. " +
                      fix);
  }
  const ArvGcAccessMode mode = arv_gc_feature_node_get_actual_access_mode(node);
  if (mode != ARV_GC_ACCESS_MODE_RW && mode != ARV_GC_ACCESS_MODE_WO) {
    throw CameraError(head +
                      " is read-only on this camera (the camera derives it from another "
                      "setting), and irdist needs to write it. " +
                      fix);
  }
  GError* error = nullptr;
  const gboolean locked = arv_gc_feature_node_is_locked(node, &error);
  ThrowOnError(error, std::string("reading whether ") + feature + " is locked", Name());
  if (locked != FALSE) {
    throw CameraError(head +
                      " is locked now (the camera holds it while acquiring, or another "
                      "setting fixes it), and irdist needs to write it. " +
                      fix + " Stop any other application using the camera and run again.");
  }
  return node;
}

std::string AravisCamera::Impl::GetString(const char* feature) {
  GError* error = nullptr;
  const char* value = arv_camera_get_string(camera.get(), feature, &error);
  ThrowOnError(error, std::string("reading ") + feature, Name());
  return OrEmpty(value);
}

std::vector<std::string> AravisCamera::Impl::EnumEntries(const char* feature) {
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

// Sets an enumeration feature and reads it back. `fix` says what to do when it cannot be set.
void AravisCamera::Impl::SetEnum(const char* feature, const std::string& value,
                                 const std::string& fix) {
  if (!Has(feature)) {
    throw CameraError("camera " + Name() + " has no feature " + feature + " (needed to set it to " +
                      value + "). " + fix);
  }
  const std::vector<std::string> entries = EnumEntries(feature);
  if (std::find(entries.begin(), entries.end(), value) == entries.end()) {
    throw CameraError("camera " + Name() + ": " + feature + " cannot be " + value +
                      "; it offers: " + JoinNames(entries) + ". " + fix);
  }
  // Held already: nothing to write (a register holding no entry reads as none, never throws).
  if (ValueAsString(FeatureNode(feature)) == value) return;
  RequireWritable(feature, fix);
  GError* error = nullptr;
  arv_camera_set_string(camera.get(), feature, value.c_str(), &error);
  ThrowOnError(error, std::string("setting ") + feature + "=" + value, Name());
  const std::string back = GetString(feature);
  if (back != value) {
    throw CameraError("camera " + Name() + ": " + feature + " was set to " + value +
                      " but reads back " + back + ". " + fix);
  }
}

void AravisCamera::Impl::SetBoolean(const char* feature, bool value, const std::string& fix) {
  RequireWritable(feature, fix);
  GError* error = nullptr;
  arv_camera_set_boolean(camera.get(), feature, value ? TRUE : FALSE, &error);
  ThrowOnError(error, std::string("setting ") + feature, Name());
  const bool back = arv_camera_get_boolean(camera.get(), feature, &error) != FALSE;
  ThrowOnError(error, std::string("reading ") + feature, Name());
  if (back != value) {
    throw CameraError("camera " + Name() + ": " + feature + " was set to " +
                      (value ? "true" : "false") + " but reads back " + (back ? "true" : "false") +
                      ". " + fix);
  }
}

void AravisCamera::Impl::SetFloat(const char* feature, double value, const std::string& fix) {
  RequireWritable(feature, fix);
  GError* error = nullptr;
  arv_camera_set_float(camera.get(), feature, value, &error);
  ThrowOnError(error, std::string("setting ") + feature, Name());
  const double back = arv_camera_get_float(camera.get(), feature, &error);
  ThrowOnError(error, std::string("reading ") + feature, Name());
  CheckFloat(feature, value, back);
}

// Sets an "...Auto" enumeration to Off when the camera has it (absent = nothing automatic).
void AravisCamera::Impl::AutoOff(const char* feature) {
  if (!Has(feature)) return;
  SetEnum(feature, "Off", "Automatic control must be off for radiometric measurements.");
}

void AravisCamera::Impl::CheckFloat(const char* feature, double wanted, double got) const {
  const double tolerance = std::max(1e-6, settings.readback_tolerance * std::fabs(wanted));
  if (std::fabs(got - wanted) > tolerance) {
    std::ostringstream out;
    out << "camera " << Name() << ": " << feature << " was set to " << wanted << " but reads back "
        << got << " (the camera clamped or rounded it). Use a value within the camera's range.";
    throw CameraError(out.str());
  }
}

// The feature's node when the camera has it readable, writable and unlocked now, else nullptr.
ArvGcFeatureNode* AravisCamera::Impl::WritableNode(const char* feature) const {
  ArvGcFeatureNode* node = FeatureNode(feature);
  if (node == nullptr) return nullptr;
  if (arv_gc_feature_node_get_actual_access_mode(node) != ARV_GC_ACCESS_MODE_RW) return nullptr;
  GError* error = nullptr;
  const gboolean locked = arv_gc_feature_node_is_locked(node, &error);
  if (error != nullptr) {
    g_error_free(error);  // lock unknown: not written
    return nullptr;
  }
  return locked != FALSE ? nullptr : node;
}

std::optional<std::string> AravisCamera::Impl::ValueAsString(ArvGcFeatureNode* node) const {
  GError* error = nullptr;
  const char* value = arv_gc_feature_node_get_value_as_string(node, &error);
  if (error != nullptr) {
    g_error_free(error);  // unreadable now: nothing to save or compare
    return std::nullopt;
  }
  return OrEmpty(value);
}

namespace {
// Whether `value` names an entry of the enumeration `node` (available now or not).
bool IsEnumEntry(ArvGcFeatureNode* node, const std::string& value) {
  for (const GSList* item = arv_gc_enumeration_get_entries(ARV_GC_ENUMERATION(node));
       item != nullptr; item = item->next) {
    if (OrEmpty(arv_gc_feature_node_get_name(ARV_GC_FEATURE_NODE(item->data))) == value) {
      return true;
    }
  }
  return false;
}
}  // namespace

void AravisCamera::Impl::SaveFeature(const std::string& selector, const char* feature,
                                     std::vector<SavedFeature>* saved) {
  ArvGcFeatureNode* node = WritableNode(feature);
  if (node == nullptr) return;
  const auto value = ValueAsString(node);
  if (ARV_IS_GC_ENUMERATION(node) && (!value || value->empty() || !IsEnumEntry(node, *value))) {
    // A register holding no entry's value: nothing that could be written back.
    unsaved.push_back((selector.empty() ? "" : selector + " ") + feature);
    return;
  }
  if (value) saved->push_back({selector, feature, *value});
}

// The features Configure() may change, in the order they are put back: the pixel pipeline's
// (acquisition/pixel_pipeline.h) after the analog ones.
std::vector<AravisCamera::Impl::SavedFeature> AravisCamera::Impl::SaveState() {
  static const char* const kGlobal[] = {"PixelFormat",
                                        "Width",
                                        "Height",
                                        "OffsetX",
                                        "OffsetY",
                                        "ExposureMode",
                                        "ExposureAuto",
                                        "ExposureTime",
                                        "ExposureTimeAbs",
                                        "GainAuto",
                                        "Gain",
                                        "GainRaw",
                                        "BlackLevelAuto",
                                        "BlackLevel",
                                        "BlackLevelRaw",
                                        "AcquisitionMode",
                                        "AcquisitionFrameRateEnable",
                                        "AcquisitionFrameRateEnabled",
                                        "AcquisitionFrameRate",
                                        "ChunkModeActive"};
  static const char* const kPerTrigger[] = {"TriggerSource", "TriggerActivation", "TriggerOverlap",
                                            "TriggerMode"};
  std::vector<SavedFeature> saved;
  unsaved.clear();
  for (const char* feature : kGlobal) SaveFeature("", feature, &saved);
  for (const PixelFeatureSpec& spec : PixelPipelineTable()) {
    for (const char* feature : spec.spellings) SaveFeature("", feature, &saved);
  }
  if (WritableNode("TriggerSelector") == nullptr) {
    for (const char* feature : kPerTrigger) SaveFeature("", feature, &saved);
    return saved;
  }
  const std::string selected = GetString("TriggerSelector");
  for (const std::string& selector : EnumEntries("TriggerSelector")) {
    if (WriteFeature("", "TriggerSelector", selector).empty()) {
      for (const char* feature : kPerTrigger) SaveFeature(selector, feature, &saved);
    }
  }
  WriteFeature("", "TriggerSelector", selected);
  saved.push_back({"", "TriggerSelector", selected});
  return saved;
}

// Writes `value` (under `selector` when not empty) unless the feature holds it already (a
// read-only feature holding it is fine); returns why it failed, or an empty string.
std::string AravisCamera::Impl::WriteFeature(const std::string& selector, const char* feature,
                                             const std::string& value) {
  if (!selector.empty()) {
    const std::string why = WriteFeature("", "TriggerSelector", selector);
    if (!why.empty()) return why;
  }
  ArvGcFeatureNode* node = FeatureNode(feature);
  if (node != nullptr && ValueAsString(node) == value) return "";
  node = WritableNode(feature);
  if (node == nullptr) return std::string(feature) + " is read-only or locked";
  GError* error = nullptr;
  arv_gc_feature_node_set_value_from_string(node, value.c_str(), &error);
  if (error == nullptr) return "";
  const std::string why = std::string(feature) + ": " + error->message;
  g_error_free(error);
  return why;
}

// Puts back every saved feature (offsets at 0 first, so the saved size fits); returns the text
// that ends the setup's error message.
std::string AravisCamera::Impl::RestoreState(const std::vector<SavedFeature>& saved,
                                             const std::vector<std::string>& skipped_names) {
  for (const char* offset : {"OffsetX", "OffsetY"}) {
    if (WritableNode(offset) != nullptr) WriteFeature("", offset, "0");
  }
  std::vector<std::string> failed;
  for (const SavedFeature& f : saved) {
    const std::string why = WriteFeature(f.selector, f.feature.c_str(), f.value);
    if (!why.empty()) failed.push_back((f.selector.empty() ? "" : f.selector + " ") + why);
  }
  const std::string skipped =
      skipped_names.empty() ? ""
                            : " Not put back: " + JoinNames(skipped_names) +
                            " (found holding no entry of its enumeration; set it with the vendor's "
                            "tool if it matters).";
  if (failed.empty()) return " The camera was put back as it was found." + skipped;
  return skipped + " The camera could not be put back as it was found (" + JoinNames(failed) +
         "); it is left with acquisition stopped: power-cycle it before another application "
         "uses it.";
}

}  // namespace irdist
