#pragma once
// The camera and recording side of a live run, behind plain types: app/runs/run.cc drives the
// station and the acquisition headers stay in capture.cc, so each side of the run sees one module.

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "acquisition/camera.h"
#include "app/processing/frame_features.h"
#include "app/runs/bracket_committer.h"
#include "estimator/features.h"
#include "station/pose.h"
#include "station/trigger.h"

namespace irdist {

struct LiveCaptureSetup {
  std::string camera_name;    // address, id or serial for AravisCamera::Open
  std::string camera_serial;  // expected serial ("" = no check)
  // Format, trigger, black level, packet size, region (app/inputs/rig.h CameraSettingsOf); the
  // recorder sets the first exposure and enough buffers for a bracket.
  CameraSettings camera;
  std::vector<double> exposures_us;  // t_r first, then the t_n
  bool interleave_reference = false;
  int frame_timeout_ms = 1000;
  // The recording: a new one (header from these) or a cut one to continue.
  std::string recording_dir;
  bool resume = false;
  std::string software_version;
  std::string command;  // the irdist command recording ("calibrate"), kept in recording.yaml
  std::string station_identity;
  std::string recipe_path, recipe_text, rig_path, rig_text;
  FeatureOptions feature_options;  // features of every frame, computed while it is in memory
  // The model FrameFeatures refines them with (app/processing/frame_features.h BlobFitModelOf);
  // null = moments. Must outlive the recorder.
  const CalibrationModel* blob_fit_model = nullptr;
  // A calibration's first pose measures the camera's linearity before its first bracket
  // (app/runs/linearity_check.h); above the limit it stops unless allow_nonlinear.
  bool check_linearity = false;
  bool allow_nonlinear = false;
};

// What is already in a recording: its recipe text, whether it is complete, its complete brackets.
struct RecordingState {
  std::string recipe_text;
  std::string recipe_path;
  bool complete = false;
  std::set<std::int64_t> complete_brackets;
};
RecordingState ReadRecordingState(const std::string& recording_dir);  // throws RecordingError

class LiveRecorder : public PendingBrackets {
 public:
  // Opens and configures the camera, opens (or resumes) the recording. Throws CameraError,
  // RecordingError. `notices` (the command's diagnostics stream, outliving the recorder): the
  // camera's state put back, a cut run's leftovers set aside, the capture's and the linearity
  // check's warnings.
  LiveRecorder(const LiveCaptureSetup& setup, std::ostream& notices);
  ~LiveRecorder();  // without Close(): the recording stays "running" (reads as cut)
  LiveRecorder(const LiveRecorder&) = delete;
  LiveRecorder& operator=(const LiveRecorder&) = delete;
  LiveRecorder(LiveRecorder&&) = delete;
  LiveRecorder& operator=(LiveRecorder&&) = delete;

  // Captures one bracket (`trigger` fires one pulse; called with -1 for a warm-up frame), retaking
  // an incomplete bracket once, and measures the current. The bracket is held back (pending) until
  // CommitPending(): the sweep checks every device alive after the pose's callback (a restart
  // retakes the pose) and confirms the pose before anything moves again; app/runs/run.cc commits
  // there. A pending bracket is replaced by the next capture. Throws CameraError when it stays
  // incomplete, and what `measure_current_ma` throws (a current off its set-point).
  void CaptureBracket(const Pose& pose, const std::function<void(int)>& trigger,
                      const std::function<double()>& measure_current_ma);
  // Appends the pending bracket's frames to the recording and computes their features, on a
  // worker thread. Waits for the previous commit first. `on_committed` runs on the worker after the
  // append. Returns whether there was a pending bracket. The caller waits for WaitAppended()
  // before anything moves again: the frames are then in the recording (a kill -9 during the next
  // move cannot lose them) while the features still overlap the move.
  bool CommitPending(std::function<void()> on_committed = {}) override;
  // Waits until the committed bracket's frames are appended (rows written). Rethrows the append's
  // error (RecordingError).
  void WaitAppended() override;
  // Waits for the commit in flight; rethrows its error (RecordingError).
  void WaitCommitted() override;
  void DropPending() override;
  void Close(bool cut);  // stops the stream, closes the recording as complete or cut
  std::string StatsReport() const;
  // The camera's own software trigger (GenICam TriggerSoftware) as the station's trigger role,
  // for `station.roles.trigger: camera_software` (camera.trigger_source: Software).
  Trigger& CameraTrigger();
  const FeatureMap& FeatureCache() const;  // after WaitCommitted()

 private:
  // The recording opened (or resumed) and the capture set up, after the camera's Configure.
  void OpenRecording(const LiveCaptureSetup& setup);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace irdist
