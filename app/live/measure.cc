#include "app/live/measure.h"

#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <mutex>
#include <thread>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <ostream>
#include <sstream>

#include "acquisition/bracket.h"
#include "acquisition/recording_writer.h"
#include "app/inputs/errors.h"
#include "app/inputs/stop_signal.h"
#include "app/inputs/provenance.h"
#include "app/live/live_camera.h"
#include "app/processing/bracket_estimates.h"
#include "app/processing/frame_features.h"
#include "app/processing/position.h"
#include "app/runs/resume.h"
#include "app/runs/run_results.h"
#include "base/pi.h"
#include "base/utc_time.h"
#include "base/version.h"
#include "base/yaml_fields.h"
#include "estimator/model_file.h"

namespace irdist {

namespace fs = std::filesystem;

namespace {

// Free space a recording leaves on its disk by default (or 5% of the disk when that is less).
constexpr double kFreeMarginBytes = 1024.0 * 1024.0 * 1024.0;

// The bracket measure takes: the flags', else the model's calibration bracket.
struct MeasureBracket {
  std::vector<double> exposures_us;  // t_r first
  bool retake_reference = false;
};

MeasureBracket BracketFor(const MeasureArgs& args, const CalibrationModel& model) {
  const ModelProvenance& p = model.provenance;
  MeasureBracket b;
  const double t_ref_ms = args.t_ref_ms > 0.0 ? args.t_ref_ms : p.t_ref_ms;
  const std::vector<double>& t_meas_ms = args.t_meas_ms.empty() ? p.t_meas_ms : args.t_meas_ms;
  if (!(t_ref_ms > 0.0) || t_meas_ms.empty()) {
    throw UsageError("measure: the model " + args.model +
                     " does not record its calibration bracket (written before provenance); "
                     "give it with --t-ref-ms T_R --t-meas-ms T1,T2,...");
  }
  b.exposures_us.push_back(t_ref_ms * 1000.0);
  for (double t : t_meas_ms) b.exposures_us.push_back(t * 1000.0);
  b.retake_reference = args.t_meas_ms.empty() && p.retake_reference;
  return b;
}

// The truth of a bracket: the --at pose on a virtual rig, NaN (unknown) otherwise.
struct Truth {
  double slide_mm = NAN, pan_deg = NAN, tilt_deg = NAN, theta_deg = NAN, bias_ma = NAN;
};

Truth TruthOf(const std::vector<double>& at) {
  Truth t;
  if (at.size() != 4) return t;
  constexpr double kDeg = kPi / 180.0;
  t.slide_mm = at[0];
  t.pan_deg = at[1];
  t.tilt_deg = at[2];
  t.bias_ma = at[3];
  t.theta_deg = std::acos(std::cos(at[1] * kDeg) * std::cos(at[2] * kDeg)) / kDeg;
  return t;
}

// Threads that compute frames' features as the frames arrive, alive as long as the session: a
// bracket's frames overlap on the host's cores without a thread started per frame, so the
// process's thread count stays the same bracket after bracket.
class FeatureWorkers {
 public:
  explicit FeatureWorkers(int count) {
    for (int i = 0; i < count; ++i) threads_.emplace_back([this] { Loop(); });
  }
  ~FeatureWorkers() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : threads_) t.join();
  }
  FeatureWorkers(const FeatureWorkers&) = delete;
  FeatureWorkers& operator=(const FeatureWorkers&) = delete;

  std::future<Features> Submit(std::function<Features()> work) {
    std::packaged_task<Features()> task(std::move(work));
    std::future<Features> result = task.get_future();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      queue_.push_back(std::move(task));
    }
    wake_.notify_one();
    return result;
  }

 private:
  void Loop() {
    while (true) {
      std::packaged_task<Features()> task;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
        if (queue_.empty()) return;  // stopping, nothing left to compute
        task = std::move(queue_.front());
        queue_.pop_front();
      }
      task();  // an exception reaches the future
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::packaged_task<Features()>> queue_;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

// One camera, one bracket after another; each bracket's frames recorded (optionally) and
// estimated with the playback path.
class Session {
 public:
  Session(const MeasureArgs& args, const CalibrationModel& model, CommandIo io, bool quiet_rig)
      : args_(args), model_(model), truth_(TruthOf(args.at)) {
    const MeasureBracket bracket = BracketFor(args, model);
    LiveCameraOptions options;
    options.rig_spec = args.rig;
    options.time_scale = args.time_scale;
    options.at = args.at;
    options.first_exposure_us = bracket.exposures_us.front();
    options.longest_exposure_us =
        *std::max_element(bracket.exposures_us.begin(), bracket.exposures_us.end());
    options.buffer_count = static_cast<int>(2 * bracket.exposures_us.size() + 4);
    options.quiet = args.json || quiet_rig;
    live_ = std::make_unique<LiveCamera>(options, io.err);
    CheckModel(io);
    geometry_ = GeometryOfRigText(ReadRigText(), live_->rig_path());
    BracketOptions capture;
    capture.exposures_us = bracket.exposures_us;
    capture.interleave_reference = bracket.retake_reference;
    capture.trigger_source = live_->trigger_source();
    capture.frame_timeout = std::chrono::milliseconds(live_->frame_timeout_ms());
    capture.trigger_in_readout = live_->rig().camera.trigger_in_readout;
    std::ostream* err = &io.err;  // the command's stream outlives the session
    capture.on_notice = [err](const std::string& text) { *err << "warning: " << text << "\n"; };
    capture_ = std::make_unique<BracketCapture>(live_->camera(), capture);
    workers_ = std::make_unique<FeatureWorkers>(static_cast<int>(bracket.exposures_us.size()));
    if (!args.out_dir.empty()) {
      estimates_ = std::make_unique<EstimatesCsvWriter>(args.out_dir + "/estimates.csv");
    }
    if (args.record) OpenRecording();
  }

  MeasureSample Next(double time_s);
  std::string StopReason() const;
  void Finish();  // closes the recording as complete
  const cv::Mat& last_image() const { return last_image_; }
  const Features& last_features() const { return last_features_; }
  LiveCamera& live() { return *live_; }
  int bit_depth() const { return live_->bit_depth(); }

 private:
  void CheckModel(CommandIo io);
  void OpenRecording();
  // Captures one bracket (retaken once if incomplete); each frame's features are computed as it
  // arrives, on a worker, while the next frame is exposed. `last_frame_at` = when the last frame
  // was handed over.
  BracketResult CaptureWithFeatures(std::vector<Features>* arrived,
                                    std::chrono::steady_clock::time_point* last_frame_at);
  std::vector<FrameRecord> Records(const BracketResult& result,
                                   const std::vector<Features>& arrived, FeatureMap* features);

  const MeasureArgs& args_;
  const CalibrationModel& model_;
  Truth truth_;
  std::unique_ptr<LiveCamera> live_;
  std::unique_ptr<BracketCapture> capture_;
  std::unique_ptr<RecordingWriter> writer_;
  std::string ReadRigText() const;
  CameraGeometry geometry_;
  std::int64_t next_bracket_ = 0;
  std::int64_t next_index_ = 0;  // frame index when nothing is recorded
  std::unique_ptr<EstimatesCsvWriter> estimates_;  // --out's estimates.csv, one bracket at a time
  std::uint64_t recorded_bytes_ = 0;      // the recording's frames so far
  std::uint64_t last_bracket_bytes_ = 0;  // ... of the last bracket: what the next one needs
  cv::Mat last_image_;
  Features last_features_;
  std::unique_ptr<FeatureWorkers> workers_;  // last: stops before what its work uses
};

void Session::CheckModel(CommandIo io) {
  const std::string serial = live_->camera().Identity().serial;
  std::string warning;
  CheckModelProvenance(model_.provenance, args_.model, ProvenanceOfRig(live_->rig(), serial),
                       "the camera of rig " + live_->rig().name, args_.allow_model_mismatch,
                       &warning);
  if (!warning.empty()) io.err << warning << "\n";
  for (const std::string& w : ModelFitnessWarnings(model_, args_.model)) io.err << w << "\n";
}

std::string Session::ReadRigText() const { return yaml_fields::ReadFile(live_->rig_path()); }

void Session::OpenRecording() {
  RecordingHeader header;
  header.software_version = kSoftwareVersion;
  header.bit_depth = live_->bit_depth();
  header.pixel_format = live_->rig().camera.pixel_format;
  header.camera = live_->camera().Identity();
  header.camera_features = live_->camera().ReadBackFeatures();
  header.station_identity = args_.at.empty() ? "none (irdist measure)"
                                             : "virtual station (irdist measure --at)";
  header.rig_path = live_->rig_path();
  header.rig_text = ReadRigText();
  writer_ = RecordingWriter::Open(args_.out_dir + "/recording", header);
}

std::vector<FrameRecord> Session::Records(const BracketResult& result,
                                          const std::vector<Features>& arrived,
                                          FeatureMap* features) {
  std::vector<FrameRecord> records;
  std::uint64_t bracket_bytes = 0;
  const int size = static_cast<int>(result.frames.size());
  for (std::size_t i = 0; i < result.frames.size(); ++i) {
    const BracketFrame& frame = result.frames[i];
    FrameRecord record = RecordFromFrame(frame, size);
    record.bracket_id = next_bracket_;
    record.bias_ma_set = truth_.bias_ma;
    record.bias_ma_measured = std::nan("");
    record.slide_mm = truth_.slide_mm;
    record.pan_deg = truth_.pan_deg;
    record.tilt_deg = truth_.tilt_deg;
    record.theta_deg = truth_.theta_deg;
    if (writer_) {
      record = writer_->Append(frame.image, record);
      struct stat written {};
      const std::string png = writer_->dir() + "/" + record.file;
      if (::stat(png.c_str(), &written) != 0) {
        throw RecordingError(png + ": just written, cannot be read back (" +
                             std::strerror(errno) + "); check the disk.");
      }
      bracket_bytes += static_cast<std::uint64_t>(written.st_size);
    } else {
      record.index = next_index_++;
    }
    (*features)[record.index] = arrived[i];
    records.push_back(record);
  }
  recorded_bytes_ += bracket_bytes;
  last_bracket_bytes_ = bracket_bytes;
  return records;
}

BracketResult Session::CaptureWithFeatures(std::vector<Features>* arrived,
                                           std::chrono::steady_clock::time_point* last_frame_at) {
  // Each frame's features on a worker as it arrives (one worker per frame of the bracket): the
  // capture never waits for them (the blob fit may take longer than the next exposure), and
  // frames overlap on the host's cores.
  std::vector<std::future<Features>> pending;
  const int bit_depth = live_->bit_depth();
  const CalibrationModel* blob_fit_model = BlobFitModelOf(model_);
  const BracketCapture::FrameSink on_frame = [&](const BracketFrame& frame) {
    *last_frame_at = std::chrono::steady_clock::now();
    pending.push_back(workers_->Submit([this, image = frame.image, bit_depth,
                                                      blob_fit_model] {
      return FrameFeatures(image, bit_depth, model_.features, blob_fit_model);
    }));
  };
  BracketResult result = capture_->Capture(live_->Trigger(), on_frame);
  if (!result.complete) {
    pending.clear();  // the incomplete bracket's features are computed and dropped
    result = capture_->Capture(live_->Trigger(), on_frame);
  }
  if (!result.complete) {
    throw CameraError("bracket " + std::to_string(next_bracket_) + " incomplete twice (" +
                      result.failure + "; " + capture_->stats().BriefReport() +
                      "). Check the camera link and its trigger.");
  }
  for (std::future<Features>& f : pending) arrived->push_back(f.get());
  return result;
}

MeasureSample Session::Next(double time_s) {
  std::vector<Features> arrived;
  std::chrono::steady_clock::time_point last_frame_at;
  const BracketResult result = CaptureWithFeatures(&arrived, &last_frame_at);
  FeatureMap features;
  RecordedBracket bracket;
  bracket.frames = Records(result, arrived, &features);
  bracket.bracket_id = next_bracket_++;
  bracket.bracket_size = static_cast<int>(bracket.frames.size());
  bracket.complete = true;
  const BracketEstimateRows rows = EstimateRecordedBracket(bracket, features, model_, geometry_);
  MeasureSample sample = MeasureSampleOf(bracket, features, rows, model_, geometry_);
  sample.time_s = time_s;
  sample.latency_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() -
                                                                last_frame_at)
                          .count();
  // The bracket's time: its last frame's arrival, as estimates.csv's (the grabber's stamps).
  sample.utc_ns = bracket.frames.back().host_time_ns;
  sample.host_monotonic_ns = bracket.frames.back().host_monotonic_ns;
  sample.camera_timestamp_ns = bracket.frames.back().camera_timestamp_ns;
  if (estimates_) estimates_->Append(FlattenRows(rows));  // on disk before it is printed
  last_image_ = result.frames.back().image;
  last_features_ = features.at(bracket.frames.back().index);
  return sample;
}

}  // namespace

namespace {

void Session::Finish() {
  if (capture_ && live_->camera().streaming()) live_->camera().StopStream();
  if (writer_) writer_->Close(Completion::kComplete);
}

// A size for a person: MB below a GB, GB above.
std::string SizeText(double bytes) {
  return bytes < 1e9 ? FixedText(bytes / 1e6, 1) + " MB" : FixedText(bytes / 1e9, 2) + " GB";
}

std::string Shortest(double value) {
  char text[40];
  std::snprintf(text, sizeof(text), "%g", value);
  return text;
}

std::string Session::StopReason() const {
  if (!writer_) return "";
  const double recorded = static_cast<double>(recorded_bytes_);
  const double next = static_cast<double>(last_bracket_bytes_);
  if (args_.max_disk_gb > 0.0 && recorded + next > args_.max_disk_gb * 1e9) {
    return "the recording (" + SizeText(recorded) + ") would exceed --max-disk-gb " +
           Shortest(args_.max_disk_gb) + " with another bracket (" + SizeText(next) +
           "); it is complete up to here. Give a larger --max-disk-gb to record longer.";
  }
  struct statvfs disk {};
  if (::statvfs(writer_->dir().c_str(), &disk) != 0) {
    return "the free space of " + writer_->dir() + " cannot be read (" + std::strerror(errno) +
           "); stopped before the disk could fill.";
  }
  const double free_bytes = static_cast<double>(disk.f_bavail) * disk.f_frsize;
  const double margin = std::min(kFreeMarginBytes, 0.05 * disk.f_blocks * disk.f_frsize);
  if (free_bytes - next < margin) {
    return "the disk of " + writer_->dir() + " has " + SizeText(free_bytes) +
           " free; another bracket (" + SizeText(next) + ") would leave less than the margin of " +
           SizeText(margin) + " (min(1 GiB, 5% of the disk)). Free space, or record to another "
           "disk with --out.";
  }
  return "";
}

}  // namespace

struct MeasureSession::Impl {
  Session session;
};

MeasureSession::MeasureSession(const MeasureArgs& args, const CalibrationModel& model,
                               CommandIo io, bool quiet_rig)
    : impl_(new Impl{Session(args, model, io, quiet_rig)}) {}
MeasureSession::~MeasureSession() = default;
MeasureSample MeasureSession::Next(double time_s) { return impl_->session.Next(time_s); }
std::string MeasureSession::StopReason() const { return impl_->session.StopReason(); }
void MeasureSession::Finish() { impl_->session.Finish(); }
const cv::Mat& MeasureSession::last_image() const { return impl_->session.last_image(); }
const Features& MeasureSession::last_features() const { return impl_->session.last_features(); }
int MeasureSession::bit_depth() const { return impl_->session.bit_depth(); }
LiveCamera& MeasureSession::live() { return impl_->session.live(); }

namespace {

// Where the per-bracket output goes: JSON lines, a live line on a terminal, or plain lines.
class MeasurePrinter {
 public:
  MeasurePrinter(std::ostream& out, bool json, bool tty) : out_(out), json_(json), tty_(tty) {}
  void Print(const MeasureSample& s) {
    if (json_) {
      out_ << MeasureJson(s) << std::endl;
    } else if (tty_) {
      out_ << "\r\033[K" << MeasureLine(s, TerminalWidthChars(STDOUT_FILENO)) << std::flush;
      line_open_ = true;
    } else {
      out_ << MeasureLine(s) << std::endl;
    }
  }
  void Close() {
    if (line_open_) out_ << "\n";
    line_open_ = false;
  }

 private:
  std::ostream& out_;
  bool json_;
  bool tty_;
  bool line_open_ = false;
};

// The run's stderr warnings, each once: the optics fingerprint at the first bracket whose health
// is assessed, the calibration health at the first unhealthy bracket (what to do), and the first
// moving bracket.
class MeasureWarnings {
 public:
  MeasureWarnings(const CalibrationModel& model, std::ostream& err) : model_(model), err_(err) {}
  void Check(const MeasureSample& s) {
    if (s.health.assessed && !fingerprint_done_) {
      fingerprint_done_ = true;
      const std::string w = OpticsFingerprintWarning(model_, s.health, s.estimate.d_mm);
      if (!w.empty()) err_ << Break() << w << "\n";
    }
    if (s.health.flagged && !health_done_) {
      health_done_ = true;
      err_ << Break() << "warning: calibration health at bracket " << s.bracket << ": "
           << s.health.Advice() << " (JSON health, live flag " << s.health.Label() << ").\n";
    }
    if (s.motion.moving && !motion_done_) {
      motion_done_ = true;
      err_ << Break() << "warning: bracket " << s.bracket << " moving: its per-exposure "
           << "distances spread " << FixedText(s.motion.spread_mm, 1)
           << " mm, beyond their noise; the IRED moved during the bracket. Its estimate mixes "
              "positions: hold the IRED still, or discard brackets flagged moving.\n";
    }
  }

 private:
  // A warning under a live line starts on a line of its own.
  const char* Break() const { return isatty(STDERR_FILENO) == 1 ? "\n" : ""; }
  const CalibrationModel& model_;
  std::ostream& err_;
  bool fingerprint_done_ = false, health_done_ = false, motion_done_ = false;
};

bool StopNow(const MeasureArgs& args, int count, double elapsed_s) {
  if (StopRequested().load()) return true;
  if (args.count > 0 && count >= args.count) return true;
  return args.duration_s > 0.0 && elapsed_s >= args.duration_s;
}

void CheckMeasureArgs(const MeasureArgs& args) {
  if (!args.track && (args.exposure_ms > 0.0 || args.accel_psd_mm2_per_s3 > 0.0 ||
                      args.check_every_s > 0.0)) {
    throw UsageError("measure: --exposure-ms, --accel-psd and --check-every go with --track.");
  }
  if (args.record && args.out_dir.empty()) {
    throw UsageError("measure: --record needs --out DIR (the recording goes to DIR/recording).");
  }
  if (args.max_disk_gb > 0.0 && !args.record) {
    throw UsageError("measure: --max-disk-gb bounds a recording; give it with --record --out DIR.");
  }
  if (!args.out_dir.empty()) {
    if (fs::exists(args.out_dir + "/recording") || fs::exists(args.out_dir + "/estimates.csv")) {
      throw RunFolderError(args.out_dir +
                           " holds an earlier measurement (estimates.csv or recording/); choose "
                           "another --out folder.");
    }
    CreateRunFolder(args.out_dir);
  }
}

void Measure(const MeasureArgs& args, const CalibrationModel& model, CommandIo io);

}  // namespace

// An estimates.csv or recording that cannot be written (a full disk) ends the run; --out keeps
// what was measured, so the next measurement goes to another folder.
void RunMeasure(const MeasureArgs& args, CommandIo io) {
  CheckMeasureArgs(args);
  std::optional<RunFolderLock> folder_lock;  // one measurement per --out folder at a time
  if (!args.out_dir.empty()) folder_lock.emplace(args.out_dir, "measure");
  const CalibrationModel model = LoadModel(args.model);
  if (args.out_dir.empty()) return Measure(args, model, io);
  WriteResults("measure again with another --out folder (" + args.out_dir + " keeps the "
               "brackets measured so far, and measure never writes into an earlier "
               "measurement's folder)", [&] { Measure(args, model, io); });
}

namespace {

void Measure(const MeasureArgs& args, const CalibrationModel& model, CommandIo io) {
  SignalGuard guard;  // Ctrl-C ends the loop after the bracket in flight
  MeasureSession session(args, model, io);
  MeasurePrinter printer(io.out, args.json, !args.json && isatty(STDOUT_FILENO) == 1);
  MeasureStats stats;
  const auto t0 = std::chrono::steady_clock::now();
  const auto elapsed = [&t0] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  std::string stopped;  // why the loop ended early, "" for --count, --duration and Ctrl-C
  MeasureWarnings warnings(model, io.err);
  while (!StopNow(args, stats.count(), elapsed())) {
    stopped = session.StopReason();
    if (!stopped.empty()) break;
    const MeasureSample sample = session.Next(elapsed());
    stats.Add(sample);
    printer.Print(sample);
    warnings.Check(sample);
    if (!io.out) {
      stopped = "stdout was closed (its reader went away) after bracket " +
                std::to_string(sample.bracket) + ".";
      break;
    }
  }
  printer.Close();
  const double wall_s = elapsed();
  session.Finish();
  std::ostream& summary = args.json || !io.out ? io.err : io.out;
  summary << stats.Report(wall_s);
  if (!stopped.empty()) summary << "Stopped: " << stopped << "\n";
  if (!args.out_dir.empty()) summary << "Estimates: " << args.out_dir << "/estimates.csv\n";
  if (args.record) summary << "Recording: " << args.out_dir << "/recording\n";
}

}  // namespace

}  // namespace irdist
