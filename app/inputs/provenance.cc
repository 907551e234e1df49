#include "app/inputs/provenance.h"

#include <sstream>
#include <vector>

#include "acquisition/recording_reader.h"
#include "app/inputs/errors.h"

namespace irdist {
namespace {

std::string RoiText(const ModelProvenance& p) {
  if (p.roi_width == 0) return "full sensor";
  std::ostringstream out;
  out << "[" << p.roi_offset_x << ", " << p.roi_offset_y << ", " << p.roi_width << ", "
      << p.roi_height << "]";
  return out.str();
}

bool SameRoi(const ModelProvenance& a, const ModelProvenance& b) {
  if (a.roi_width == 0 || b.roi_width == 0) return a.roi_width == b.roi_width;
  return a.roi_offset_x == b.roi_offset_x && a.roi_offset_y == b.roi_offset_y &&
         a.roi_width == b.roi_width && a.roi_height == b.roi_height;
}

// The differences between model and actual, one phrase each.
std::vector<std::string> Differences(const ModelProvenance& model, const ModelProvenance& actual) {
  std::vector<std::string> out;
  if (!model.camera_serial.empty() && !actual.camera_serial.empty() &&
      model.camera_serial != actual.camera_serial) {
    out.push_back("camera serial " + model.camera_serial + " vs " + actual.camera_serial);
  }
  if (!model.pixel_format.empty() && !actual.pixel_format.empty() &&
      model.pixel_format != actual.pixel_format) {
    out.push_back("pixel format " + model.pixel_format + " vs " + actual.pixel_format);
  }
  if (!SameRoi(model, actual)) out.push_back("roi_px " + RoiText(model) + " vs " + RoiText(actual));
  return out;
}

void FillBracket(const RecordingReader& reader, ModelProvenance* p) {
  for (const RecordedBracket& bracket : reader.Brackets()) {
    if (!bracket.complete) continue;
    int references = 0;
    for (const FrameRecord& row : bracket.frames) {
      if (row.role == FrameRole::kReference) {
        if (references++ == 0) p->t_ref_ms = row.requested_exposure_us / 1000.0;
      } else {
        p->t_meas_ms.push_back(row.requested_exposure_us / 1000.0);
      }
    }
    p->retake_reference = references > 1;
    return;
  }
}

}  // namespace

ModelProvenance ProvenanceOfRecording(const RecordingReader& reader) {
  const RecordingHeader& h = reader.header();
  ModelProvenance p;
  p.known = true;
  p.rig_path = h.rig_path;
  p.camera_vendor = h.camera.vendor;
  p.camera_model = h.camera.model;
  p.camera_serial = h.camera.serial;
  p.pixel_format = h.pixel_format;
  p.bit_depth = h.bit_depth;
  p.recipe_path = h.recipe_path;
  p.calibration_date = h.start_time;
  if (!h.rig_text.empty()) {
    Rig rig;
    try {
      rig = ParseRig(h.rig_text, h.rig_path.empty() ? reader.dir() + " (rig)" : h.rig_path);
    } catch (const InputError&) {
      p.known = false;  // a rig file this build no longer reads: nothing to compare against
      return p;
    }
    p.rig_name = rig.name;
    p.roi_offset_x = rig.camera.roi_offset_x;
    p.roi_offset_y = rig.camera.roi_offset_y;
    p.roi_width = rig.camera.roi_width;
    p.roi_height = rig.camera.roi_height;
  }
  FillBracket(reader, &p);
  return p;
}

ModelProvenance ProvenanceOfRig(const Rig& rig, const std::string& camera_serial) {
  ModelProvenance p;
  p.known = true;
  p.rig_name = rig.name;
  p.rig_path = rig.path;
  p.camera_serial = camera_serial;
  p.pixel_format = rig.camera.pixel_format;
  p.roi_offset_x = rig.camera.roi_offset_x;
  p.roi_offset_y = rig.camera.roi_offset_y;
  p.roi_width = rig.camera.roi_width;
  p.roi_height = rig.camera.roi_height;
  return p;
}

void CheckModelProvenance(const ModelProvenance& model, const std::string& model_path,
                          const ModelProvenance& actual, const std::string& actual_source,
                          bool allow, std::string* warn) {
  if (!model.known || !actual.known) return;
  const std::vector<std::string> diffs = Differences(model, actual);
  if (diffs.empty()) {
    // Another rig's name with the same camera setup (rigs/virtual-offset.yaml shares virtual's
    // camera) is allowed, never silent.
    if (warn != nullptr && !model.rig_name.empty() && !actual.rig_name.empty() &&
        model.rig_name != actual.rig_name) {
      *warn = "warning: the model " + model_path + " was calibrated on rig " + model.rig_name +
              ", not on " + actual_source + " (rig " + actual.rig_name + "); the camera serial, "
              "pixel format and ROI agree, so it is used. Calibrate on " + actual.rig_name +
              " if its lens or station differ.";
    }
    return;
  }
  std::string text = "the model " + model_path + " (rig " + model.rig_name + ") was calibrated ";
  text += "with another camera setup than " + actual_source + ": ";
  for (size_t i = 0; i < diffs.size(); ++i) text += (i > 0 ? "; " : "") + diffs[i];
  text += " (model vs " + actual_source + ")";
  if (!allow) {
    throw ModelMismatchError(text +
                             ". Calibrate this camera setup, or pass --allow-model-mismatch to "
                             "use the model anyway.");
  }
  if (warn != nullptr) *warn = "warning: " + text + "; used anyway (--allow-model-mismatch).";
}

}  // namespace irdist
