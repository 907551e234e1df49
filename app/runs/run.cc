#include "app/runs/run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <memory>
#include <optional>
#include <ostream>
#include <set>
#include <sstream>
#include <thread>

#include "app/inputs/stop_signal.h"
#include "app/devices/station_setup.h"
#include "app/inputs/camera_settings.h"
#include "app/inputs/provenance.h"
#include "app/inputs/recipe.h"
#include "app/processing/bracket_estimates.h"
#include "app/processing/frame_features.h"
#include "app/runs/bracket_committer.h"
#include "app/runs/capture.h"
#include "app/runs/linearity_check.h"
#include "app/runs/resume.h"
#include "app/runs/run_folder.h"
#include "app/runs/run_progress.h"
#include "app/runs/run_results.h"
#include "base/version.h"
#include "base/yaml_fields.h"
#include "estimator/model_file.h"
#include "sim/virtual_rig.h"
#include "station/line_log.h"
#include "station/station.h"
#include "station/sweep.h"

namespace irdist {

namespace {

// A recipe's or rig file's text, through the one reader that refuses FIFOs and devices.
std::string ReadText(const std::string& path) { return yaml_fields::ReadFile(path); }

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
// (read at connection and homing): its plan and bound are on those; a single-box station's are the
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

}  // namespace

Recorded Record(const RunRequest& request, const Recipe& recipe, const Plan& plan,
                const FeatureOptions& feature_options, const CalibrationModel* blob_fit_model,
                CommandIo io) {
  Recorded recorded;
  const std::string recipe_text = ReadText(recipe.path);
  RunFolder folder = OpenRunFolder(request.kind, request.out_dir, request.resume_dir, recipe, plan,
                                   recipe_text, io.err);
  recorded.dir = folder.dir;
  recorded.lock = std::move(folder.lock);
  const std::set<std::int64_t>& done_ids = folder.done_ids;
  const std::string command = CommandName(request.kind);
  if (!folder.record) return recorded;
  const std::vector<Pose> poses = SweepPoses(plan, done_ids);
  // Declared first: the camera and the station links are closed before a virtual rig stops.
  RigEndpoints rig = StartRig(request, recipe, io);
  const std::string earlier_log = KeepEarlierLog(recorded.dir);
  if (!earlier_log.empty()) io.err << "Earlier station log kept as " << earlier_log << "\n";
  LineLog log(recorded.dir + "/station.log");
  Station station(recipe.rig.station.composition, StationRunOptions(rig.ports, &log));
  station.Identify();

  LiveRecorder recorder(RecorderSetup(request, recipe, rig, station, recorded.dir, recipe_text,
                                      feature_options, blob_fit_model),
                        io.err);
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

namespace {

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
  PrintRigNotes(recipe.rig, io.err);
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
  const std::string advice =
      CompleteResultsAdvice(request.kind, recipe.path, request.model_path, recorded.dir);
  WriteResults(advice, [&] {
    if (recipe.after == AfterRecording::kNone) {
      ProcessRecordingOnly(recorded.dir, feature_options, recorded.cache, io.out);
    } else if (request.kind == RunKind::kCalibrate) {
      ProcessCalibration(recorded.dir, feature_options, recorded.cache, io.out,
                         request.keep_model);
    } else {
      ProcessValidation(recorded.dir, *model,
                        {{"recipe", recipe.path},
                         {"model", request.model_path},
                         {"recording", recorded.dir + "/recording"}},
                        recorded.cache, io);
    }
  });
  io.out << "Run folder: " << recorded.dir << "\n";
}

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
  RequireValid(args, "calibrate");
  RunRequest request = RequestFrom(RunKind::kCalibrate, args);
  request.allow_nonlinear = args.allow_nonlinear;
  request.keep_model = args.keep_model;
  RunRecipe(request, io);
}

void RunValidate(const ValidateArgs& args, CommandIo io) {
  RunRequest request = RequestFrom(RunKind::kValidate, args);
  request.model_path = args.model;
  request.allow_model_mismatch = args.allow_model_mismatch;
  RunRecipe(request, io);
}

}  // namespace irdist
