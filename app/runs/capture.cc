#include "app/runs/capture.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <future>
#include <ostream>
#include <optional>

#include "acquisition/aravis_camera.h"
#include "acquisition/bracket.h"
#include "acquisition/recording_reader.h"
#include "acquisition/recording_writer.h"
#include "app/runs/linearity_check.h"

namespace irdist {

namespace {

// The camera's TriggerSoftware command as the station's trigger role.
class CameraSoftwareTrigger : public Trigger {
 public:
  explicit CameraSoftwareTrigger(AravisCamera& camera) : camera_(camera) {}
  DeviceIdentity Identify() override {
    const CameraIdentity id = camera_.Identity();
    return {"camera_software", "camera", id.vendor, id.model, id.serial, id.firmware};
  }
  const char* CameraSource() const override { return "Software"; }
  void Fire(int) override {
    camera_.SoftwareTrigger();
    ++fired_;
  }
  std::uint64_t Fired() const override { return fired_; }

 private:
  AravisCamera& camera_;
  std::uint64_t fired_ = 0;
};

// Commits a bracket's staged frames (PNGs already written) with their rows; returns their indices.
std::vector<std::int64_t> CommitBracket(RecordingWriter& writer, const Pose& pose,
                                        const BracketResult& bracket, double measured_ma) {
  const int size = static_cast<int>(bracket.frames.size());
  std::vector<FrameRecord> records;
  for (const BracketFrame& frame : bracket.frames) {
    FrameRecord record = RecordFromFrame(frame, size);
    record.bracket_id = pose.index;
    record.bias_ma_set = pose.bias_ma;
    record.bias_ma_measured = measured_ma;
    record.slide_mm = pose.slide_mm;
    record.pan_deg = pose.pan_deg;
    record.tilt_deg = pose.tilt_deg;
    record.theta_deg = pose.theta_deg;
    record.repeat = pose.repeat;
    records.push_back(std::move(record));
  }
  std::vector<std::int64_t> indices;
  for (const FrameRecord& record : writer.CommitStaged(std::move(records))) {
    indices.push_back(record.index);
  }
  return indices;
}

}  // namespace

struct LiveRecorder::Impl {
  LiveCaptureSetup setup;
  std::ostream* notices = nullptr;
  std::unique_ptr<AravisCamera> camera;
  std::unique_ptr<RecordingWriter> writer;
  std::unique_ptr<BracketCapture> capture;
  FeatureMap cache;
  int bit_depth = 16;
  // The last bracket captured, not yet appended.
  bool has_pending = false;
  Pose pending_pose;
  BracketResult pending;
  double pending_measured_ma = 0.0;
  std::future<void> committing;  // the commit in flight
  std::future<void> appended;    // its frames are in the recording
  std::future<void> staging;     // the last frame handed to the writer (each waits for the one before)
  bool has_staged = false;       // frames staged for the pending bracket (a commit takes them over)
  std::unique_ptr<CameraSoftwareTrigger> software_trigger;

  // Hands a frame to the writer on a worker (encode, write, sync under a temporary name) while the
  // next one is exposed; frames are staged in arrival order.
  void StageAsync(const cv::Mat& image) {
    has_staged = true;
    staging = std::async(std::launch::async,
                         [this, previous = std::move(staging), image]() mutable {
                           if (previous.valid()) previous.get();
                           writer->Stage(image);
                         });
  }
  // Waits for the staging in flight and removes the staged frames (a bracket not kept). A staging
  // error is not rethrown here: the writer keeps it and refuses the next write with it.
  void DropStaged() {
    if (!has_staged) return;  // none, or a commit owns them (it alone touches the writer then)
    has_staged = false;
    if (staging.valid()) {
      try {
        staging.get();
      } catch (const Error&) {
      }
    }
    writer->DropStaged();
  }
};

RecordingState ReadRecordingState(const std::string& recording_dir) {
  const RecordingReader reader(recording_dir);
  RecordingState state;
  state.recipe_text = reader.header().recipe_text;
  state.recipe_path = reader.header().recipe_path;
  state.complete = reader.IsComplete();
  state.complete_brackets = reader.CompleteBracketIds();
  return state;
}

LiveRecorder::LiveRecorder(const LiveCaptureSetup& setup, std::ostream& notices)
    : impl_(new Impl) {
  Impl& m = *impl_;
  m.setup = setup;
  m.notices = &notices;
  m.camera = AravisCamera::Open(setup.camera_name, setup.camera_serial);
  CameraSettings settings = setup.camera;
  IRDIST_CHECK(!setup.exposures_us.empty(), "a bracket needs exposures");
  settings.exposure_us = setup.exposures_us.front();
  settings.buffer_count =
      std::max(settings.buffer_count, static_cast<int>(2 * setup.exposures_us.size() + 4));
  m.camera->Configure(settings);
  try {
    OpenRecording(setup);
  } catch (...) {
    *m.notices << m.camera->LeaveAsFound(setup.camera.restore_after) << "\n";
    throw;
  }
}

void LiveRecorder::OpenRecording(const LiveCaptureSetup& setup) {
  Impl& m = *impl_;
  if (setup.resume) {
    m.writer = RecordingWriter::Resume(setup.recording_dir);
    if (!m.writer->set_aside().empty()) {
      *m.notices << "Moved " << m.writer->set_aside().size()
                 << " leftover file(s) of the cut run aside to " << m.writer->set_aside_dir()
                 << " (nothing was deleted).\n";
    }
  } else {
    RecordingHeader header;
    header.software_version = setup.software_version;
    header.run_command = setup.command;
    header.bit_depth = BitDepthOfPixelFormat(setup.camera.pixel_format);
    header.pixel_format = setup.camera.pixel_format;
    header.camera = m.camera->Identity();
    header.camera_features = m.camera->ReadBackFeatures();
    header.station_identity = setup.station_identity;
    header.recipe_path = setup.recipe_path;
    header.recipe_text = setup.recipe_text;
    header.rig_path = setup.rig_path;
    header.rig_text = setup.rig_text;
    m.writer = RecordingWriter::Open(setup.recording_dir, header);
  }
  m.bit_depth = m.writer->header().bit_depth;

  BracketOptions options;
  options.exposures_us = setup.exposures_us;
  options.interleave_reference = setup.interleave_reference;
  options.trigger_source = setup.camera.trigger_source;
  options.frame_timeout = std::chrono::milliseconds(setup.frame_timeout_ms);
  options.trigger_in_readout = setup.camera.trigger_in_readout;
  std::ostream* notices = m.notices;
  options.on_notice = [notices](const std::string& text) {
    *notices << "warning: " << text << "\n";
  };
  m.capture = std::make_unique<BracketCapture>(*m.camera, options);
  m.software_trigger = std::make_unique<CameraSoftwareTrigger>(*m.camera);
}

LiveRecorder::~LiveRecorder() {
  if (impl_->staging.valid()) impl_->staging.wait();
  if (impl_->committing.valid()) impl_->committing.wait();
  // Done, failed or interrupted alike: stopped, and put back unless the rig says otherwise.
  const std::string outcome = impl_->camera->LeaveAsFound(impl_->setup.camera.restore_after);
  if (!outcome.empty()) *impl_->notices << outcome << "\n";
}

void LiveRecorder::CaptureBracket(const Pose& pose, const std::function<void(int)>& trigger,
                                  const std::function<double()>& measure_current_ma) {
  Impl& m = *impl_;
  if (m.setup.check_linearity) {  // the first pose, once
    m.setup.check_linearity = false;
    CheckFirstPoseLinearity(*m.camera, [&trigger] { trigger(-1); },
                            {m.setup.recording_dir, m.setup.allow_nonlinear,
                             m.setup.exposures_us.front(), m.bit_depth},
                            *m.notices);
  }
  m.DropStaged();  // frames of a bracket never committed
  const BracketCapture::FrameSink stage = [&m](const BracketFrame& frame) {
    m.StageAsync(frame.image);
  };
  // The current is read back while the last frame is read out (its light is over by then).
  std::optional<double> measured_ma;
  const auto measure = [&] { measured_ma = measure_current_ma(); };
  BracketResult result = m.capture->Capture(trigger, stage, measure);
  if (!result.complete) {
    m.DropStaged();
    result = m.capture->Capture(trigger, stage, measure);
  }
  if (!result.complete) {
    m.DropStaged();
    // The failure names the cause: the network when packets were lost, the trigger when nothing
    // arrived.
    throw CameraError("bracket " + std::to_string(pose.index) + " incomplete twice: " +
                      result.failure + " (" + m.capture->stats().BriefReport() +
                      "). Then resume the run.");
  }
  // A complete bracket took its last frame, whose readout ran the read-back.
  IRDIST_CHECK(measured_ma.has_value(), "the current was not read during the last readout");
  m.pending_measured_ma = *measured_ma;
  m.pending = std::move(result);
  m.pending_pose = pose;
  m.has_pending = true;
}

bool LiveRecorder::CommitPending(std::function<void()> on_committed) {
  Impl& m = *impl_;
  WaitCommitted();
  if (!m.has_pending) return false;
  m.has_pending = false;
  m.has_staged = false;  // the commit takes the staged frames over
  // The worker owns the bracket from here; the writer and the cache are only touched by it until
  // WaitCommitted().
  auto appended = std::make_shared<std::promise<void>>();
  m.appended = appended->get_future();
  auto task = [&m, pose = m.pending_pose, bracket = std::move(m.pending),
               measured_ma = m.pending_measured_ma, done = std::move(on_committed), appended,
               staging = std::move(m.staging)]() mutable {
    std::vector<std::int64_t> indices;
    try {
      if (staging.valid()) staging.get();
      indices = CommitBracket(*m.writer, pose, bracket, measured_ma);
    } catch (...) {
      appended->set_exception(std::current_exception());
      throw;
    }
    appended->set_value();
    if (done) done();
    // Features yield to the capture path (camera, station, and on a virtual rig the renderer),
    // which shares the host's cores: a nice of 10 for this thread only (Linux applies nice per
    // thread). If the host refuses, the work only competes as before.
    if (setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), 10) != 0) {
      // Not an error: the features are still computed, at the default priority.
    }
    for (std::size_t i = 0; i < indices.size(); ++i) {
      m.cache[indices[i]] =
          FrameFeatures(bracket.frames[i].image, m.bit_depth, m.setup.feature_options,
                        m.setup.blob_fit_model);
    }
  };
  m.pending = BracketResult{};
  m.committing = std::async(std::launch::async, std::move(task));
  return true;
}

void LiveRecorder::WaitAppended() {
  if (impl_->appended.valid()) impl_->appended.get();
}

void LiveRecorder::WaitCommitted() {
  if (impl_->committing.valid()) impl_->committing.get();
}

void LiveRecorder::DropPending() {
  impl_->DropStaged();
  impl_->has_pending = false;
  impl_->pending = BracketResult{};
}

void LiveRecorder::Close(bool cut) {
  if (impl_->committing.valid()) impl_->committing.wait();  // its error, if any, is already known
  impl_->DropStaged();
  if (impl_->camera->streaming()) impl_->camera->StopStream();
  impl_->writer->Close(cut ? Completion::kCut : Completion::kComplete);
}

std::string LiveRecorder::StatsReport() const { return impl_->capture->stats().BriefReport(); }

const FeatureMap& LiveRecorder::FeatureCache() const { return impl_->cache; }

Trigger& LiveRecorder::CameraTrigger() { return *impl_->software_trigger; }

}  // namespace irdist
