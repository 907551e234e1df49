#pragma once
// Model provenance on the app side: what model.yaml records about the calibration's camera and
// bracket (estimator/provenance.h), filled from a recording, and the check that validate,
// playback and measure make before using a model: the same camera serial, pixel format and region
// of interest, unless --allow-model-mismatch.

#include <string>

#include "app/inputs/rig.h"
#include "base/check.h"
#include "estimator/provenance.h"

namespace irdist {

class RecordingReader;

// A model used with another camera, pixel format or ROI than it was calibrated with. Exit code 1.
class ModelMismatchError : public Error {
 public:
  using Error::Error;
};

// The provenance of a calibration recorded in `reader`: its header (camera, pixel format, bit
// depth, rig and recipe, start time) and the exposures of its first complete bracket.
ModelProvenance ProvenanceOfRecording(const RecordingReader& reader);

// What a live run will use: the rig's camera settings and the camera's serial ("" = unknown).
ModelProvenance ProvenanceOfRig(const Rig& rig, const std::string& camera_serial);

// Throws ModelMismatchError naming both sides (`model_path` and `actual_source`) when the model
// was calibrated with another camera serial, pixel format or ROI than `actual`, unless `allow`
// (then `warn` gets the same text as a warning, when not null). A model without provenance, or an
// unknown serial on either side, is not compared on that point. A model of another rig name with
// the same camera setup passes with a warning in `warn` (rigs sharing a camera, e.g. virtual and
// virtual-offset).
void CheckModelProvenance(const ModelProvenance& model, const std::string& model_path,
                          const ModelProvenance& actual, const std::string& actual_source,
                          bool allow, std::string* warn = nullptr);

}  // namespace irdist
