#include "app/live/track_session.h"

#include <time.h>
#include <unistd.h>

#include <chrono>
#include <deque>
#include <cmath>
#include <optional>
#include <ostream>

#include "acquisition/camera.h"
#include "app/inputs/errors.h"
#include "app/inputs/stop_signal.h"
#include "app/live/live_camera.h"
#include "app/live/measure.h"
#include "app/live/track_estimate.h"
#include "app/processing/frame_features.h"
#include "app/processing/position.h"
#include "base/utc_time.h"
#include "base/yaml_fields.h"
#include "estimator/model_file.h"

namespace irdist {

namespace {

// The frames whose own blurs a track line's calibration health pools: a bracket's measurement
// frames (one 8 ms frame alone flagged 2% of static frames).
constexpr int kHealthFrames = 4;

// Whether `t_ms` lies in [lo, hi] within 0.1% (a range of 0, 0 is not recorded).
bool InRange(double t_ms, double lo_ms, double hi_ms) {
  return hi_ms > 0.0 && t_ms >= lo_ms * (1.0 - 1e-3) && t_ms <= hi_ms * (1.0 + 1e-3);
}

// A frame's time on one clock for the filter: the camera's timestamp, else the host's monotonic.
double FrameTimeS(std::uint64_t camera_ns, std::int64_t host_monotonic_ns) {
  return camera_ns != 0 ? static_cast<double>(camera_ns) * 1e-9
                        : static_cast<double>(host_monotonic_ns) * 1e-9;
}

// This thread's CPU time (ms): what one frame's estimate costs, apart from the other threads.
double ThreadCpuMs() {
  timespec t{};
  IRDIST_CHECK(clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t) == 0,
               "clock_gettime(CLOCK_THREAD_CPUTIME_ID) failed");
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

// The filter's process noise: --accel-psd, else the rig file's track.accel_psd_mm2_per_s3, else
// the filter's default.
TrackFilterOptions FilterOptionsOf(const MeasureArgs& args, const Rig& rig) {
  TrackFilterOptions options;
  if (args.accel_psd_mm2_per_s3 > 0.0) {
    options.accel_psd_mm2_per_s3 = args.accel_psd_mm2_per_s3;
  } else if (rig.track_accel_psd_mm2_per_s3 > 0.0) {
    options.accel_psd_mm2_per_s3 = rig.track_accel_psd_mm2_per_s3;
  }
  return options;
}

}  // namespace

double TrackExposureMs(const MeasureArgs& args, const CalibrationModel& model) {
  const double t_ms = args.exposure_ms > 0.0 ? args.exposure_ms : model.provenance.t_ref_ms;
  if (!(t_ms > 0.0)) {
    throw UsageError("measure --track: the model " + args.model +
                     " does not record its reference exposure (written before provenance); "
                     "give the exposure with --exposure-ms T.");
  }
  const CalibratedRanges& r = model.ranges;
  if (r.t_ref_max_ms <= 0.0 && r.t_max_ms <= 0.0) return t_ms;  // ranges not recorded
  if (InRange(t_ms, r.t_ref_min_ms, r.t_ref_max_ms) || InRange(t_ms, r.t_min_ms, r.t_max_ms)) {
    return t_ms;
  }
  throw UsageError("measure --track: exposure " + FixedText(t_ms, 3) +
                   " ms lies outside the calibrated exposures of " + args.model + " (reference " +
                   FixedText(r.t_ref_min_ms, 3) + "-" + FixedText(r.t_ref_max_ms, 3) +
                   " ms, measurement " + FixedText(r.t_min_ms, 3) + "-" + FixedText(r.t_max_ms, 3) +
                   " ms); give --exposure-ms inside them.");
}

struct TrackSession::Impl {
  Impl(const MeasureArgs& a, const CalibrationModel& m, CommandIo io)
      : args(a),
        model(m),
        exposure_ms(TrackExposureMs(a, m)),
        measure(a, m, io),
        geometry(GeometryOfRigText(yaml_fields::ReadFile(measure.live().rig_path()),
                                   measure.live().rig_path())),
        filter(1, FilterOptionsOf(a, measure.live().rig())) {
    const Rig& rig = measure.live().rig();
    GrabberOptions options;
    options.exposure_us = exposure_ms * 1000.0;
    // A trigger in flight during the previous frame is kept by a camera that queues triggers (the
    // virtual one) or overlaps them with readout (the rig's trigger_in_readout: true).
    options.ahead = rig.kind == RigKind::kVirtual || rig.camera.trigger_in_readout ? 2 : 1;
    options.frame_timeout = std::chrono::milliseconds(measure.live().frame_timeout_ms());
    LiveCamera& live = measure.live();
    grabber = std::make_unique<FrameGrabber>(live.camera(), live.Trigger(), options);
    ahead = options.ahead;
    readout_ms = rig.camera.readout_ms;
    trigger_source = live.trigger_source();
    grabber->Start();
  }

  TrackSample Frame(double time_s);
  TrackSample Check(double time_s);
  // The last frame's own blur, measured after its line (off the latency path), into the pool.
  void MeasurePending();
  void AddToPool(const Features& f);
  std::vector<const Features*> HealthFrames() const;

  const MeasureArgs& args;
  const CalibrationModel& model;
  double exposure_ms;
  MeasureSession measure;  // the camera, and the bracket of a check
  CameraGeometry geometry;
  TrackFilter filter;
  TrackState last_state;
  double last_filter_time_s = -1.0;
  double last_check_s = 0.0;
  int ahead = 1;
  double readout_ms = 0.0;
  std::string trigger_source;
  // The calibration health of a line pools the own blurs of the kHealthFrames frames before it
  // (as a bracket pools its measurement frames); the first line's is its own.
  PendingOwnBlur pending;
  Features pending_features;
  std::deque<Features> blur_pool;
  std::unique_ptr<FrameGrabber> grabber;  // last: stops before the camera closes
};

void TrackSession::Impl::MeasurePending() {
  if (MeasurePendingOwnBlur(&pending, &pending_features)) AddToPool(pending_features);
}

void TrackSession::Impl::AddToPool(const Features& f) {
  blur_pool.push_back(f);
  if (blur_pool.size() > static_cast<std::size_t>(kHealthFrames)) blur_pool.pop_front();
}

std::vector<const Features*> TrackSession::Impl::HealthFrames() const {
  std::vector<const Features*> frames;
  for (const Features& f : blur_pool) frames.push_back(&f);
  return frames;
}

TrackSample TrackSession::Impl::Frame(double time_s) {
  // A frame period is at most the longest exposure plus the timeout's margin: three of them
  // without a frame is a camera that stopped.
  const auto wait = std::chrono::milliseconds(3 * measure.live().frame_timeout_ms());
  const double pending_cpu0_ms = ThreadCpuMs();
  MeasurePending();
  const double pending_cpu_ms = ThreadCpuMs() - pending_cpu0_ms;
  std::optional<GrabbedFrame> grabbed = grabber->Take(wait);
  if (!grabbed) {
    const TrackCounters c = grabber->counters();
    throw CameraError("measure --track: no frame in " + std::to_string(wait.count()) + " ms (" +
                      std::to_string(c.received) + " received, " + std::to_string(c.lost) +
                      " lost so far). Check the camera link and its trigger.");
  }
  const double cpu0_ms = ThreadCpuMs();
  const RawFrame& raw = grabbed->raw;
  // The first frame's own blur at once (its line's health), the others' after their lines.
  const bool later = !blur_pool.empty();
  Features features = FrameFeatures(raw.image, measure.bit_depth(), model.features,
                                    BlobFitModelOf(model), nullptr, later ? &pending : nullptr);
  TrackSample t;
  t.estimate =
      EstimateFrame(features, exposure_ms, model, geometry, grabbed->number, HealthFrames());
  if (later) {
    pending_features = std::move(features);
  } else if (std::isfinite(features.own_blur_var_px2)) {
    AddToPool(features);
  }
  MeasureSample& s = t.estimate;
  s.mode = "track";
  s.time_s = time_s;
  s.utc_ns = raw.host_time_ns;
  s.host_monotonic_ns = raw.host_monotonic_ns;
  s.camera_timestamp_ns = raw.timestamp_ns;
  const double frame_time_s = FrameTimeS(raw.timestamp_ns, raw.host_monotonic_ns);
  if (s.estimate.ok && frame_time_s > last_filter_time_s) {
    t.filter = filter.Add(frame_time_s, {s.estimate.d_mm}, {s.estimate.d_std_mm});
    t.filtered = true;
    last_state = t.filter;
    last_filter_time_s = frame_time_s;
  }
  s.latency_ms = static_cast<double>(MonotonicNowNs() - raw.host_monotonic_ns) * 1e-6;
  t.cpu_ms = ThreadCpuMs() - cpu0_ms + pending_cpu_ms;  // the last frame's own blur included
  t.frame = grabbed->number;
  t.counters = grabbed->counters;
  t.camera_frame_id = raw.frame_id;
  t.exposure_ms = exposure_ms;
  return t;
}

TrackSample TrackSession::Impl::Check(double time_s) {
  grabber->Stop();  // the frames in flight arrive (counted) before the bracket starts
  TrackSample t;
  t.estimate = measure.Next(time_s);
  const MeasureSample& b = t.estimate;
  t.check = CheckAgainstTrack(last_state, filter.started(),
                              FrameTimeS(b.camera_timestamp_ns, b.host_monotonic_ns), b);
  last_check_s = time_s;
  grabber->Start();
  return t;
}

TrackSession::TrackSession(const MeasureArgs& args, const CalibrationModel& model, CommandIo io)
    : impl_(new Impl(args, model, io)) {}

TrackSession::~TrackSession() = default;

std::string TrackSession::Header() const {
  const Impl& m = *impl_;
  const double bound_fps = 1000.0 / (m.exposure_ms + m.readout_ms);
  return "track: triggered (" + m.trigger_source + ", " + std::to_string(m.ahead) + " trigger" +
         (m.ahead > 1 ? "s" : "") + " in flight), exposure " + FixedText(m.exposure_ms, 3) +
         " ms; the camera's bound 1 / (exposure + readout " + FixedText(m.readout_ms, 1) +
         " ms) = " + FixedText(bound_fps, 1) + " frames/s" +
         (m.args.check_every_s > 0.0
              ? "; a bracket every " + FixedText(m.args.check_every_s, 1) + " s"
              : std::string());
}

TrackSample TrackSession::Next(double time_s) {
  Impl& m = *impl_;
  const bool check_due =
      m.args.check_every_s > 0.0 && time_s - m.last_check_s >= m.args.check_every_s;
  if (!check_due) {
    TrackSample t = m.Frame(time_s);
    t.acquisition = "triggered";
    return t;
  }
  TrackSample t = m.Check(time_s);
  t.acquisition = "triggered";
  t.counters = m.grabber->counters();
  return t;
}

void TrackSession::Finish() {
  impl_->grabber->Stop();
  impl_->measure.Finish();
}

TrackCounters TrackSession::counters() const { return impl_->grabber->counters(); }

namespace {

// Where the lines go: JSON lines, a live line on a terminal (cut to its width), or plain lines.
void PrintTrack(std::ostream& out, const TrackSample& s, bool json, bool tty) {
  if (json) {
    out << TrackJson(s) << std::endl;
  } else if (tty) {
    const std::size_t width = TerminalWidthChars(STDOUT_FILENO);
    out << "\r\033[K" << TrackLine(s).substr(0, width > 1 ? width - 1 : 1) << std::flush;
  } else {
    out << TrackLine(s) << std::endl;
  }
}

}  // namespace

void RunTrack(const MeasureArgs& args, CommandIo io) {
  if (args.record || !args.out_dir.empty()) {
    throw UsageError(
        "measure --track writes no estimates.csv or recording: give --json and keep "
        "its lines (docs/measure.md \"Tracking\"), or measure brackets with --out.");
  }
  const CalibrationModel model = LoadModel(args.model);
  TrackExposureMs(args, model);  // refused before the camera starts
  SignalGuard guard;             // Ctrl-C ends the loop after the frame in flight
  TrackSession session(args, model, io);
  const bool tty = !args.json && isatty(STDOUT_FILENO) == 1;
  (args.json ? io.err : io.out) << session.Header() << std::endl;
  TrackStats stats;
  const auto t0 = std::chrono::steady_clock::now();
  const auto elapsed = [&t0] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  std::string stopped;
  bool warned = false;
  int frames = 0;
  while (!StopRequested().load() && !(args.count > 0 && frames >= args.count) &&
         !(args.duration_s > 0.0 && elapsed() >= args.duration_s)) {
    const TrackSample sample = session.Next(elapsed());
    stats.Add(sample);
    frames += sample.frame >= 0 ? 1 : 0;
    PrintTrack(io.out, sample, args.json, tty);
    if (sample.check.assessed && !sample.check.agree && !warned) {
      warned = true;
      io.err << (tty ? "\n" : "") << "warning: the bracket at "
             << FixedText(sample.estimate.time_s, 2) << " s disagrees with the track (z "
             << FixedText(sample.check.z, 1)
             << "): the size and the radiometric models part; check the calibration's health "
                "and the scene.\n";
    }
    if (!io.out) {
      stopped = "stdout was closed (its reader went away).";
      break;
    }
  }
  if (tty) io.out << "\n";
  const double wall_s = elapsed();
  session.Finish();
  std::ostream& summary = args.json || !io.out ? io.err : io.out;
  summary << stats.Report(wall_s, session.counters());
  if (!stopped.empty()) summary << "Stopped: " << stopped << "\n";
}

void RunMeasureOrTrack(const MeasureArgs& args, CommandIo io) {
  RequireValid(args, "measure");
  args.track ? RunTrack(args, io) : RunMeasure(args, io);
}

}  // namespace irdist
