#include "app/runs/run.h"

#include <unistd.h>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <memory>
#include <optional>
#include <ostream>
#include <set>
#include <sstream>
#include <thread>

#include "acquisition/recording_reader.h"
#include "app/cli/stop_signal.h"
#include "app/devices/station_setup.h"
#include "app/inputs/camera_settings.h"
#include "app/inputs/provenance.h"
#include "app/inputs/recipe.h"
#include "app/processing/bracket_estimates.h"
#include "app/processing/frame_features.h"
#include "app/processing/run_results.h"
#include "app/runs/bracket_committer.h"
#include "app/runs/capture.h"
#include "app/runs/linearity_check.h"
#include "app/runs/resume.h"
#include "app/runs/suggest.h"
#include "base/safe_file.h"
#include "base/yaml_fields.h"
#include "estimator/model_file.h"
#include "sim/virtual_rig.h"
#include "station/line_log.h"
#include "station/station.h"
#include "station/sweep.h"

namespace irdist {

namespace fs = std::filesystem;

namespace {

constexpr const char* kSoftwareVersion = "irdist 0.1.0";

// A recipe's or rig file's text, through the one reader that refuses FIFOs and devices.
std::string ReadText(const std::string& path) { return yaml_fields::ReadFile(path); }

std::string Timestamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  localtime_r(&now, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof(buffer), "%Y%m%d-%H%M%S", &tm);
  return buffer;
}

// Progress on stderr: a bar with ETA on a terminal, one log line per pose otherwise.
class Progress {
 public:
  Progress(std::ostream& err, bool quiet, int total, double estimate_host_s)
      : err_(err),
        quiet_(quiet),
        tty_(isatty(STDERR_FILENO) == 1),
        total_(total),
        estimate_host_s_(estimate_host_s),
        start_(std::chrono::steady_clock::now()) {}

  void Update(int done, const std::string& what) {
    if (quiet_) return;
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    // The plan's estimate per pose, corrected by the rate measured since the first pose was
    // done (before it, homing and the move from home would make the rate look slow).
    const double per_pose_plan = total_ > 0 ? estimate_host_s_ / total_ : 0.0;
    double per_pose = per_pose_plan;
    if (first_done_ < 0) {
      first_done_ = done;
      first_time_ = std::chrono::steady_clock::now();
    } else if (done > first_done_) {
      const int measured_poses = done - first_done_;
      const double measured =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - first_time_).count() /
          measured_poses;
      const double weight = std::min(1.0, measured_poses / 5.0);
      per_pose = weight * measured + (1.0 - weight) * per_pose_plan;
    }
    const double eta = per_pose * (total_ - done);
    const double fraction = total_ > 0 ? static_cast<double>(done) / total_ : 1.0;
    if (tty_) {
      constexpr int kWidth = 30;
      const int filled = static_cast<int>(fraction * kWidth);
      err_ << "\r[" << std::string(static_cast<size_t>(filled), '#')
           << std::string(static_cast<size_t>(kWidth - filled), '.') << "] " << done << "/"
           << total_ << " poses, ETA " << FormatDuration(eta) << "   " << std::flush;
      line_open_ = true;
    } else {
      err_ << "pose " << done << "/" << total_ << " (" << what << "), elapsed "
           << FormatDuration(elapsed) << ", ETA " << FormatDuration(eta) << "\n";
    }
  }
  void Finish() {
    if (line_open_) err_ << "\n";
    line_open_ = false;
  }

 private:
  std::ostream& err_;
  bool quiet_;
  bool tty_;
  int total_;
  double estimate_host_s_;
  std::chrono::steady_clock::time_point start_;
  int first_done_ = -1;  // poses done at the first update, and when
  std::chrono::steady_clock::time_point first_time_;
  bool line_open_ = false;
};

enum class RunKind { kCalibrate, kValidate };

struct RunRequest {
  RunKind kind = RunKind::kCalibrate;
  std::string recipe_path;
  std::string model_path;  // validate
  std::string out_dir;
  std::string resume_dir;
  double time_scale = 0.0;
  bool quiet = false;
  bool allow_model_mismatch = false;  // validate
  bool allow_nonlinear = false;       // calibrate: --allow-nonlinear
  // validate on hardware: the model's camera serial, which AravisCamera::Open then requires
  // ("" = none: another camera is allowed, or the model does not say).
  std::string expected_serial;
};

// What the recording phase leaves for the processing phase.
struct Recorded {
  std::string dir;
  FeatureMap cache;  // features of the frames captured in this session
  bool cut = false;
  std::unique_ptr<RunFolderLock> lock;  // held through the processing too
};

std::vector<Pose> SweepPoses(const Plan& plan, const std::set<std::int64_t>& done) {
  std::vector<Pose> poses;
  for (const Pose& p : plan.poses) {
    if (done.count(p.index) == 0) poses.push_back(p);
  }
  return poses;
}

void SleepHostMs(double ms) {
  if (ms > 0.0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(ms));
}

// A free station.N.log name for the log of an earlier session.
std::string KeepEarlierLog(const std::string& dir) {
  const std::string current = dir + "/station.log";
  if (!fs::exists(current)) return "";
  for (int n = 1;; ++n) {
    std::string kept = dir + "/station." + std::to_string(n) + ".log";
    if (!fs::exists(kept)) {
      fs::rename(current, kept);
      return kept;
    }
  }
}

const char* CommandName(RunKind kind) {
  return kind == RunKind::kCalibrate ? "calibrate" : "validate";
}

// The files a finished run of `recipe` leaves in its folder, the last one written last.
std::vector<std::string> ResultsOf(RunKind kind, const Recipe& recipe) {
  if (recipe.after == AfterRecording::kNone) return {"features.csv"};
  if (kind == RunKind::kCalibrate) return {"model.yaml", "report/index.html"};
  return {"estimates.csv", "summary.yaml", "report/index.html"};
}

// A new run folder holds no recording or results of another run (nor a link in their place).
void RefuseOtherResults(const std::string& dir, RunKind kind) {
  for (const char* name : {"recording", "model.yaml", "features.csv", "estimates.csv",
                           "summary.yaml", "report"}) {
    const fs::path path = fs::path(dir) / name;
    std::error_code ec;
    if (fs::exists(fs::symlink_status(path, ec))) {
      throw RunFolderError(path.string() + " exists already: irdist " + CommandName(kind) +
                           " never replaces a run's recording or results. Continue that run "
                           "with --resume " + ShellQuoted(dir) + ", or choose a new --out "
                           "folder.");
    }
  }
}

// The run folder: a new one, or the cut run to resume (its complete brackets in `done_ids`).
// Returns false when the recording to resume is complete already (only its processing is left).
bool PrepareRunFolder(const RunRequest& request, const Recipe& recipe, const Plan& plan,
                      const std::string& recipe_text, CommandIo io, Recorded* recorded,
                      std::set<std::int64_t>* done_ids) {
  if (request.resume_dir.empty()) {
    recorded->dir =
        request.out_dir.empty() ? recipe.output_dir + "-" + Timestamp() : request.out_dir;
    RefuseOtherResults(recorded->dir, request.kind);
    CreateRunFolder(recorded->dir);
    return true;
  }
  recorded->dir = request.resume_dir;
  ResumeExpectation expected = ResumeExpectationOf(recipe, recipe_text, ReadText(recipe.rig_path));
  expected.results = ResultsOf(request.kind, recipe);
  const ResumeState state = CheckResume(recorded->dir, CommandName(request.kind), expected);
  if (state.complete) {
    io.err << "Resuming " << recorded->dir << ": the recording is complete but "
           << state.missing_result << " is missing (the run was stopped while processing); "
           << "processing it now.\n";
    return false;
  }
  *done_ids = state.complete_brackets;
  io.err << "Resuming " << recorded->dir << ": " << done_ids->size() << " of "
         << plan.poses.size() << " brackets already recorded.\n";
  return true;
}

// Where the rig's devices and camera are: a virtual rig is started here (and stopped by the
// caller's unique_ptr on every path); a hardware rig names them in its file.
struct RigEndpoints {
  std::unique_ptr<sim::VirtualRig> virtual_rig;
  double time_scale = 1.0;
  std::map<std::string, std::string> ports;  // device name -> port, overriding the rig file
  std::string camera_name, camera_serial;
};

RigEndpoints StartRig(const RunRequest& request, const Recipe& recipe, CommandIo io) {
  RigEndpoints rig;
  rig.camera_name = recipe.rig.camera.id;
  rig.camera_serial = request.expected_serial;  // validate on hardware: the model's camera
  if (recipe.rig.kind == RigKind::kVirtual) {
    sim::VirtualRigOverrides overrides;
    if (request.time_scale > 0.0) overrides.time_scale = request.time_scale;
    rig.virtual_rig = sim::VirtualRig::Start(recipe.rig_path, overrides);
    const sim::VirtualRigInfo& info = rig.virtual_rig->Info();
    rig.time_scale = info.time_scale;
    rig.ports = VirtualDevicePorts(recipe.rig, info);
    rig.camera_name = info.camera_address;
    rig.camera_serial = info.serial;
    if (!request.quiet)
      io.err << "Virtual rig (time scale " << rig.time_scale << "):\n" << info.BriefReport();
    return rig;
  }
  // Discovery broadcasts on every network interface: a hardware run never starts it on its own,
  // the rig file names the camera.
  if (rig.camera_name == "auto") {
    throw RecipeError(recipe.rig_path, 0, 0,
                      "camera.id is 'auto', which only a virtual rig can resolve; set it to the "
                      "camera's IP address, Aravis id or serial number ('irdist devices "
                      "--discover' lists the cameras on the network).");
  }
  return rig;
}

// The camera and recording settings of a live run.
LiveCaptureSetup CaptureSetup(const Recipe& recipe, const RigEndpoints& rig,
                              const std::string& trigger_source) {
  LiveCaptureSetup setup;
  const CameraConfig& camera = recipe.rig.camera;
  setup.camera_name = rig.camera_name;
  setup.camera_serial = rig.camera_serial;
  setup.camera = CameraSettingsOf(camera, trigger_source);
  const BracketSpec& bracket = recipe.sweep.bracket;
  setup.exposures_us.push_back(bracket.t_ref_ms * 1000.0);
  double longest_ms = bracket.t_ref_ms;
  for (double t : bracket.t_meas_ms) {
    setup.exposures_us.push_back(t * 1000.0);
    longest_ms = std::max(longest_ms, t);
  }
  setup.interleave_reference = bracket.retake_reference;
  setup.frame_timeout_ms =
      camera.frame_timeout_ms + static_cast<int>(std::ceil(longest_ms / rig.time_scale));
  setup.software_version = kSoftwareVersion;
  setup.recipe_path = recipe.path;
  setup.rig_path = recipe.rig_path;
  setup.rig_text = ReadText(recipe.rig_path);
  return setup;
}

// The recipe's waits on top of the station's own settle. The move's wait starts now (settled);
// the current's started when the sweep set it, before the move, so only what is left of it is
// waited. Host waits are simulated waits divided by the time scale.
void WaitSettle(const SettleSpec& settle, const Sweep::Transition& transition,
                double time_scale) {
  double wait_host_ms = 0.0;
  if (transition.moved) wait_host_ms = settle.after_move_ms / time_scale;
  if (transition.current_changed) {
    const double since_change_ms = std::chrono::duration<double, std::milli>(
                                       std::chrono::steady_clock::now() -
                                       transition.current_changed_at)
                                       .count();
    wait_host_ms = std::max(wait_host_ms, settle.after_current_ms / time_scale - since_change_ms);
  }
  SleepHostMs(wait_host_ms);
}

std::string PoseText(const Pose& pose) {
  std::ostringstream what;
  what << "d " << pose.slide_mm << " mm, theta " << pose.theta_deg << " deg, " << pose.bias_ma
       << " mA";
  return what.str();
}

// Host seconds spent in each step of the poses (added up over the sweep), for the run's report.
struct PoseTiming {
  double settle_s = 0.0;      // the recipe's settle waits
  double capture_s = 0.0;     // the bracket's frames (triggers, exposures, readouts)
  double current_s = 0.0;     // the measured-current query after each bracket
};

// Runs `step` and adds its host time to `*total_s`.
template <typename F>
void Timed(double* total_s, F&& step) {
  const auto t0 = std::chrono::steady_clock::now();
  step();
  *total_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// One live session's sweep: station, recorder and committer in place.
struct LiveSession {
  const Recipe& recipe;
  const Plan& plan;
  Station& station;
  LiveRecorder& recorder;
  BracketCommitter& committer;
  double time_scale = 1.0;
  PoseTiming timing;
};

// The message of the exception being handled ("" when it is not a std::exception).
std::string CurrentErrorText() {
  try {
    throw;
  } catch (const std::exception& e) {
    return e.what();
  } catch (...) {
    return "";
  }
}

SweepResult SweepAndCapture(LiveSession& s, const std::vector<Pose>& poses) {
  Sweep sweep(s.station);
  // Fires one frame (also the warm-up frame, -1) through the station's trigger role.
  const auto fire = [&](int frame) { s.station.Fire(frame); };
  // The measured current, checked against the set-point: an open IRED or a source in compliance
  // stops the run (the bracket is not kept); a device restart retakes the pose.
  const auto measure = [&]() {
    double ma = 0.0;
    Timed(&s.timing.current_s, [&] { ma = s.station.MeasureCheckedCurrent().current_ma; });
    return ma;
  };
  const PoseCallback at_pose = [&](const Pose& pose, int) {
    s.committer.Begin();
    Timed(&s.timing.settle_s,
          [&] { WaitSettle(s.recipe.sweep.settle, sweep.transition(), s.time_scale); });
    Timed(&s.timing.capture_s, [&] { s.recorder.CaptureBracket(pose, fire, measure); });
    s.committer.Captured(PoseText(pose));
  };
  const ConfirmCallback confirmed = [&](const Pose&) { s.committer.Confirmed(); };
  return sweep.Run(poses, at_pose, &StopRequested(), confirmed);
}

// Where the sweep's host time went (sums over the poses, s; capture includes the current query).
void ReportTiming(const SweepResult& result, const PoseTiming& timing, double commit_wait_s,
                  std::ostream& out) {
  out << std::fixed << std::setprecision(3) << "Timing: homing " << result.homing_s
      << " s; sweep " << result.sweep_s << " s after homing = current set + moves "
      << result.goto_s << " s, settle " << timing.settle_s << " s, brackets "
      << timing.capture_s - timing.current_s << " s, current queries " << timing.current_s
      << " s, alive checks " << result.check_alive_s << " s, commit wait " << commit_wait_s
      << " s, other " << result.sweep_s - result.goto_s - timing.settle_s - timing.capture_s -
                             result.check_alive_s - commit_wait_s
      << " s\n";
  out << std::defaultfloat;
}

// The run's report: the sweep, the capture, the commit waits, where the time went, and the wall
// time beside the plan and the physical bound. A composed rig's devices report their own speeds
// (read at connection and homing): its plan and bound are on those; a legacy station's are the
// rig file's (its protocol has no speed query).
void ReportRun(LiveSession& s, const SweepResult& result, double wall_s, std::size_t pose_count,
               std::ostream& out) {
  const double scale = s.time_scale;
  const Plan timed =
      s.recipe.rig.station.composed
          ? MakePlan(s.recipe.sweep, WithDeviceSpeeds(s.recipe.motion, s.station.Speeds()))
          : s.plan;
  out << "Sweep: " << result.BriefReport() << "\n";
  out << "Capture: " << s.recorder.StatsReport() << "\n";
  out << "Commit: every bracket in the recording before the next move; waited "
      << FormatDuration(s.committer.waited_s()) << " in all\n";
  ReportTiming(result, s.timing, s.committer.waited_s(), out);
  out << "Wall time " << FormatDuration(wall_s) << " for " << pose_count << " poses; plan estimate "
      << FormatDuration(timed.summary.total_s / scale) << " and physical bound "
      << FormatDuration(timed.summary.physical_bound_s / scale) << " for all "
      << s.plan.poses.size() << " poses at time scale " << scale
      << (s.recipe.rig.station.composed ? " (axes at the devices' speeds)" : "") << "\n";
  out << std::fixed << std::setprecision(3) << "Bound: physical "
      << timed.summary.physical_bound_s / scale << " s, plan " << timed.summary.total_s / scale
      << " s\n" << std::defaultfloat;
}

// The live recorder's set-up: the rig's camera, the run folder's recording, the station's
// identity and the recipe, the features computed while recording.
LiveCaptureSetup RecorderSetup(const RunRequest& request, const Recipe& recipe,
                               const RigEndpoints& rig, const Station& station,
                               const std::string& run_dir, const std::string& recipe_text,
                               const FeatureOptions& feature_options,
                               const CalibrationModel* blob_fit_model) {
  LiveCaptureSetup setup = CaptureSetup(recipe, rig, RigTriggerSource(recipe.rig));
  setup.recording_dir = run_dir + "/recording";
  setup.resume = !request.resume_dir.empty();
  setup.command = CommandName(request.kind);
  setup.check_linearity = request.kind == RunKind::kCalibrate &&
                          NeedsFirstPoseLinearity(setup.recording_dir, setup.resume);
  setup.allow_nonlinear = request.allow_nonlinear;
  setup.station_identity = station.IdentityBrief();
  setup.recipe_text = recipe_text;
  setup.feature_options = feature_options;
  setup.blob_fit_model = blob_fit_model;
  return setup;
}

Recorded Record(const RunRequest& request, const Recipe& recipe, const Plan& plan,
                const FeatureOptions& feature_options, const CalibrationModel* blob_fit_model,
                CommandIo io) {
  Recorded recorded;
  const std::string recipe_text = ReadText(recipe.path);
  std::set<std::int64_t> done_ids;
  const bool record = PrepareRunFolder(request, recipe, plan, recipe_text, io, &recorded, &done_ids);
  const std::string command = CommandName(request.kind);
  // One run per folder, for the whole run (recording and processing).
  recorded.lock = std::make_unique<RunFolderLock>(recorded.dir, command);
  if (!record) return recorded;
  const std::vector<Pose> poses = SweepPoses(plan, done_ids);
  // Declared first: the camera and the station links are closed before a virtual rig stops.
  RigEndpoints rig = StartRig(request, recipe, io);
  const std::string earlier_log = KeepEarlierLog(recorded.dir);
  if (!earlier_log.empty()) io.err << "Earlier station log kept as " << earlier_log << "\n";
  LineLog log(recorded.dir + "/station.log");
  Station station(recipe.rig.station.composition, StationRunOptions(rig.ports, &log));
  station.Identify();

  LiveRecorder recorder(RecorderSetup(request, recipe, rig, station, recorded.dir, recipe_text,
                                      feature_options, blob_fit_model));
  if (recipe.rig.station.composition.trigger == kCameraSoftwareTrigger) {
    station.SetCameraTrigger(&recorder.CameraTrigger());
  }

  Progress progress(io.err, request.quiet, static_cast<int>(plan.poses.size()),
                    plan.summary.total_s / rig.time_scale);
  BracketCommitter committer(recorder, static_cast<int>(done_ids.size()),
                             [&progress](int done, const std::string& what) {
                               progress.Update(done, what);
                             });
  LiveSession session{recipe, plan, station, recorder, committer, rig.time_scale, {}};
  const auto t0 = std::chrono::steady_clock::now();
  SweepResult result;
  try {
    result = SweepAndCapture(session, poses);
  } catch (...) {
    // The pose in flight was not confirmed by the sweep: it is retaken on --resume.
    committer.Abandon(io.err, CurrentErrorText());
    progress.Finish();
    recorder.Close(true);
    io.err << "\nThe recording in " << recorded.dir << "/recording is closed as cut. Continue it "
           << "with: " << ResumeCommand(command, recipe.path, request.model_path, recorded.dir)
           << "\n";
    throw;
  }
  recorder.WaitCommitted();
  progress.Finish();
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  recorded.cut = result.stopped || result.next_index >= 0;
  recorder.Close(recorded.cut);
  recorded.cache = recorder.FeatureCache();
  ReportRun(session, result, wall_s, poses.size(), io.out);
  return recorded;
}

// Validate refuses a model of another camera setup before anything moves: pixel format and ROI
// from the rig file, the serial from a virtual rig's physics (a hardware camera's serial is only
// known once it is opened).
void CheckModelAgainstRig(const CalibrationModel& model, const RunRequest& request,
                          const Recipe& recipe, CommandIo io) {
  const std::string serial = recipe.rig.kind == RigKind::kVirtual
                                 ? sim::LoadRigPhysics(recipe.rig_path).camera.serial
                                 : std::string();
  std::string warning;
  CheckModelProvenance(model.provenance, request.model_path, ProvenanceOfRig(recipe.rig, serial),
                       "rig " + recipe.rig.name + " (" + recipe.rig_path + ")",
                       request.allow_model_mismatch, &warning);
  if (!warning.empty()) io.err << warning << "\n";
  for (const std::string& w : ModelFitnessWarnings(model, request.model_path)) io.err << w << "\n";
}

void RunRecipe(const RunRequest& request, CommandIo io) {
  const Recipe recipe = LoadRecipe(request.recipe_path);
  const Plan plan = PlanRecipe(recipe);
  std::optional<CalibrationModel> model;
  if (request.kind == RunKind::kValidate) {
    model = LoadModel(request.model_path);
    CheckModelAgainstRig(*model, request, recipe, io);
  }
  RunRequest checked = request;
  if (model && !request.allow_model_mismatch) {
    checked.expected_serial = model->provenance.camera_serial;
  }
  const FeatureOptions feature_options = model ? model->features : FeatureOptions{};
  io.out << "Recipe " << recipe.path << ": " << plan.summary.BriefReport() << "\n";

  Recorded recorded;
  {
    // Ctrl-C stops the sweep cleanly; after the recording it ends the process as usual.
    SignalGuard guard;
    recorded = Record(checked, recipe, plan, feature_options,
                      model ? BlobFitModelOf(*model) : nullptr, io);
  }
  if (recorded.cut) {
    throw InterruptedError("run stopped; the recording in " + recorded.dir +
                           "/recording is closed as cut. Continue it with: " +
                           ResumeCommand(CommandName(request.kind), recipe.path,
                                         request.model_path, recorded.dir));
  }

  // A result that cannot be written (a full disk): the resume completes them.
  WriteResults("complete the results with: " +
                   ResumeCommand(CommandName(request.kind), recipe.path, request.model_path,
                                 recorded.dir), [&] {
    if (recipe.after == AfterRecording::kNone) {
      ProcessRecordingOnly(recorded.dir, feature_options, recorded.cache, io.out);
    } else if (request.kind == RunKind::kCalibrate) {
      ProcessCalibration(recorded.dir, feature_options, recorded.cache, io.out);
    } else {
      ProcessValidation(recorded.dir, *model,
                        {{"recipe", recipe.path},
                         {"model", request.model_path},
                         {"recording", recorded.dir + "/recording"}},
                        recorded.cache, io.out);
    }
  });
  io.out << "Run folder: " << recorded.dir << "\n";
}

// The probe recipe of `plan --suggest`: the recipe's two ends (nearest distance at the smallest
// angle and the highest current; farthest at the largest angle and the lowest current) crossed,
// each taken at the recipe's t_r and its longest t_n. Written as YAML so that the probe run is
// recorded like any other (its recipe text stands in its recording.yaml).
struct RecipeEnds {
  double d_min = 1e300, d_max = -1e300;    // mm
  double th_min = 1e300, th_max = -1e300;  // |theta|, deg
  double i_min = 1e300, i_max = -1e300;    // mA
  // The bright end (nearest, smallest angle, highest current) or the faint end (farthest,
  // largest angle, lowest current), compared at the station's resolution (0.01 unit).
  bool Nearest(double d, double theta, double ma) const {
    return Same(d, d_min) && Same(std::abs(theta), th_min) && Same(ma, i_max);
  }
  bool Farthest(double d, double theta, double ma) const {
    return Same(d, d_max) && Same(std::abs(theta), th_max) && Same(ma, i_min);
  }
  static bool Same(double a, double b) {
    return std::llround(a * 100.0) == std::llround(b * 100.0);
  }
};

RecipeEnds EndsOf(const Plan& plan) {
  RecipeEnds e;
  for (const Pose& p : plan.poses) {
    e.d_min = std::min(e.d_min, p.slide_mm);
    e.d_max = std::max(e.d_max, p.slide_mm);
    e.th_min = std::min(e.th_min, std::abs(p.theta_deg));
    e.th_max = std::max(e.th_max, std::abs(p.theta_deg));
    e.i_min = std::min(e.i_min, p.bias_ma);
    e.i_max = std::max(e.i_max, p.bias_ma);
  }
  return e;
}

std::string ProbeRecipeText(const Recipe& recipe, const RecipeEnds& e) {
  // [lo, hi], or [lo] when the recipe has one value on the axis.
  const auto pair = [](YAML::Emitter& out, double lo, double hi) {
    out << YAML::Flow << YAML::BeginSeq << lo;
    if (hi != lo) out << hi;
    out << YAML::EndSeq;
  };
  const BracketSpec& b = recipe.sweep.bracket;
  const double t_long = *std::max_element(b.t_meas_ms.begin(), b.t_meas_ms.end());
  YAML::Emitter y;  // every path and name quoted as it needs ('#', ':', quotes, spaces)
  y.SetDoublePrecision(10);
  y << YAML::Comment("Probe frames for 'irdist plan --suggest " + recipe.path + "'");
  y << YAML::BeginMap;
  y << YAML::Key << "name" << YAML::Value << YAML::DoubleQuoted << recipe.name + "-probe";
  y << YAML::Key << "rig" << YAML::Value << YAML::DoubleQuoted
    << fs::absolute(recipe.rig_path).string();
  y << YAML::Key << "after" << YAML::Value << "none";
  y << YAML::Key << "axes" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "slide_mm" << YAML::Value;
  pair(y, e.d_min, e.d_max);
  y << YAML::Key << "theta_deg" << YAML::Value;
  pair(y, e.th_min, e.th_max);
  y << YAML::Key << "bias_ma" << YAML::Value;
  pair(y, e.i_min, e.i_max);
  y << YAML::EndMap;
  y << YAML::Key << "bracket" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "t_ref_ms" << YAML::Value << b.t_ref_ms;
  y << YAML::Key << "t_meas_ms" << YAML::Value << YAML::Flow << YAML::BeginSeq << t_long
    << YAML::EndSeq;
  y << YAML::EndMap << YAML::EndMap;
  return std::string(y.c_str()) + "\n";
}

}  // namespace

std::string SuggestProbeRecipe(const Recipe& recipe, const Plan& plan) {
  return ProbeRecipeText(recipe, EndsOf(plan));
}

namespace {

// The suggestion's options, with --from's best dt; checked before the probe sweep (a bad value
// must not cost a sweep).
SuggestOptions SuggestOptionsOf(const PlanArgs& args, std::ostream& err) {
  SuggestOptions options;
  if (!args.from_summary.empty()) {
    const std::optional<double> best = ReadBestDtMs(args.from_summary);
    if (best) {
      options.best_dt_ms = *best;
    } else {
      err << args.from_summary << " has no best_dt_ms (a validation with one t_n?); "
          << "suggesting without it.\n";
    }
  }
  std::string why;
  if (!options.IsValid(&why)) throw SuggestError(args.from_summary + ": " + why);
  return options;
}

}  // namespace

void RunSuggest(const PlanArgs& args, CommandIo io) {
  const Recipe recipe = LoadRecipe(args.recipe);
  const Plan plan = PlanRecipe(recipe);
  const RecipeEnds ends = EndsOf(plan);
  const SuggestOptions options = SuggestOptionsOf(args, io.err);
  const std::string dir =
      args.out_dir.empty() ? recipe.output_dir + "-suggest-" + Timestamp() : args.out_dir;
  fs::create_directories(dir);
  const std::string probe_path = dir + "/probe-recipe.yaml";
  std::string why;
  if (!WriteFileAtomically(probe_path, SuggestProbeRecipe(recipe, plan), 0644, &why)) {
    throw RunFolderError(probe_path + " " + why + "; check the folder.");
  }
  RunRequest request;
  request.kind = RunKind::kCalibrate;
  request.recipe_path = probe_path;
  request.out_dir = dir;
  request.time_scale = args.time_scale;
  request.quiet = args.quiet;
  const Recipe probe_recipe = LoadRecipe(probe_path);
  const Plan probe_plan = PlanRecipe(probe_recipe);
  io.out << "Probing " << recipe.path << " at its ends: " << probe_plan.summary.pose_count
         << " poses, t " << recipe.sweep.bracket.t_ref_ms << " and "
         << probe_recipe.sweep.bracket.t_meas_ms.front() << " ms\n";
  Recorded recorded;
  {
    SignalGuard guard;
    recorded = Record(request, probe_recipe, probe_plan, FeatureOptions{}, nullptr, io);
  }
  if (recorded.cut) throw InterruptedError("probe stopped; nothing suggested.");
  const RecordingReader reader(dir + "/recording");
  const FeatureMap features = RecordingFeatures(reader, FeatureOptions{}, recorded.cache);
  std::vector<ProbeFrame> probes;
  for (const FrameRecord& row : reader.rows()) {
    const bool nearest = ends.Nearest(row.slide_mm, row.theta_deg, row.bias_ma_set);
    const bool farthest = ends.Farthest(row.slide_mm, row.theta_deg, row.bias_ma_set);
    if (!nearest && !farthest) continue;
    const auto f = features.find(row.index);
    if (f == features.end() || !f->second.blob_found) {
      throw RunFolderError(reader.dir() + ": no IRED image in frame " + row.file +
                           "; is the IRED in view and on? (see " + dir + "/features.csv)");
    }
    probes.push_back({nearest, row.requested_exposure_us / 1000.0, row.bias_ma_set, f->second.peak,
                      f->second.background});
  }
  const Suggestion s = SuggestExposures(probes, options);
  io.out << "Suggested bracket for " << recipe.path << " (probe run in " << dir << "):\n"
         << s.BriefReport();
  if (!s.feasible) throw SuggestError("no feasible exposures: " + s.reason);
}

namespace {

// The options calibrate and validate share.
template <typename Args>
RunRequest RequestFrom(RunKind kind, const Args& args) {
  RunRequest request;
  request.kind = kind;
  request.recipe_path = args.recipe;
  request.out_dir = args.out_dir;
  request.resume_dir = args.resume_dir;
  request.time_scale = args.time_scale;
  request.quiet = args.quiet;
  return request;
}

}  // namespace

void RunCalibrate(const CalibrateArgs& args, CommandIo io) {
  RunRequest request = RequestFrom(RunKind::kCalibrate, args);
  request.allow_nonlinear = args.allow_nonlinear;
  RunRecipe(request, io);
}

void RunValidate(const ValidateArgs& args, CommandIo io) {
  RunRequest request = RequestFrom(RunKind::kValidate, args);
  request.model_path = args.model;
  request.allow_model_mismatch = args.allow_model_mismatch;
  RunRecipe(request, io);
}

}  // namespace irdist
