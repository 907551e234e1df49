#include "app/live/track_run.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <exception>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <ostream>
#include <thread>

#include "acquisition/recording_types.h"
#include "app/devices/station_setup.h"
#include "app/inputs/errors.h"
#include "app/inputs/rig_lookup.h"
#include "app/inputs/stop_signal.h"
#include "app/inputs/track_recipe.h"
#include "app/live/track_session.h"
#include "app/processing/track_summary.h"
#include "app/processing/track_truth.h"
#include "app/runs/run.h"
#include "base/safe_file.h"
#include "base/utc_time.h"
#include "base/yaml_fields.h"
#include "estimator/model_file.h"
#include "station/line_log.h"
#include "station/station.h"

namespace irdist {

namespace {

namespace fs = std::filesystem;

// The filter's velocity is compared on a cruise from this long after it began: the filter
// needs some frames to follow the acceleration's step (its memory).
constexpr double kCruiseSettleS = 0.5;

// Where the station is and what the truth is: a virtual rig's running sim (its ports and its
// trajectory file), or the rig file's ports on hardware.
struct TrackRig {
  std::map<std::string, std::string> ports;
  std::string trajectory_csv;  // virtual rig: the truth; "" on hardware
};

TrackRig FindTrackRig(const TrackRecipe& recipe, std::ostream& err) {
  TrackRig rig;
  if (recipe.rig.kind != RigKind::kVirtual) return rig;
  const std::optional<RunningSim> sim = FindRunningSim(recipe.rig_path, err);
  if (!sim) {
    throw UsageError("the track recipe " + recipe.path + " runs on the virtual rig " +
                     recipe.rig_path + ": start it first with 'irdist sim " + recipe.rig_path +
                     "' in another terminal (its station's trajectory is the truth of every "
                     "frame), then run this again");
  }
  rig.ports = PortsOfRunningSim(*sim);
  const auto csv = sim->values.find("trajectory_csv");
  if (csv == sim->values.end() || csv->second.empty()) {
    throw UsageError("the running sim of " + recipe.rig_path + " (pid " +
                     std::to_string(sim->pid) + ") logs no trajectory: restart it with this "
                     "version's 'irdist sim " + recipe.rig_path + "'");
  }
  rig.trajectory_csv = csv->second;
  return rig;
}

// A new run folder with the recipe and the rig file beside the results.
std::string MakeTrackFolder(const ValidateArgs& args, const TrackRecipe& recipe) {
  const std::string dir = args.out_dir.empty() ? recipe.output_dir : args.out_dir;
  std::error_code ec;
  if (fs::exists(dir, ec) && !(fs::is_directory(dir, ec) && fs::is_empty(dir, ec))) {
    throw RunFolderError(dir + " exists and is not an empty folder: a track run writes a new "
                               "folder (it cannot be resumed); give --out NEW_DIR or move " +
                         dir + " away");
  }
  fs::create_directories(dir, ec);
  if (ec) throw RunFolderError(dir + ": " + ec.message() + "; check the path and permissions");
  for (const auto& [from, name] : {std::make_pair(recipe.path, "recipe.yaml"),
                                   std::make_pair(recipe.rig_path, "rig.yaml")}) {
    std::string why;
    if (!WriteNewFileSynced(dir + "/" + name, yaml_fields::ReadFile(from), 0644, &why)) {
      throw RunFolderError(dir + "/" + name + ": " + why + "; check the disk");
    }
  }
  return dir;
}

// track.csv, a row appended as each frame is estimated (created new; kept on a Ctrl-C).
class TrackCsv {
 public:
  explicit TrackCsv(std::string path) : path_(std::move(path)) {
    std::string why;
    fd_ = CreateNewFile(path_, 0644, &why);
    if (fd_ < 0) throw RecordingError(path_ + ": " + why + "; check the folder");
    Write(TrackCsvHeader() + "\n");
  }
  ~TrackCsv() {
    if (fd_ >= 0) {
      (void)fsync(fd_);  // best effort here; Close() reports
      (void)close(fd_);
    }
  }
  TrackCsv(const TrackCsv&) = delete;
  TrackCsv& operator=(const TrackCsv&) = delete;

  void Append(const TrackFrameRow& row) { Write(TrackCsvRow(row) + "\n"); }
  void Close() {
    const int fd = fd_;
    fd_ = -1;
    const bool synced = fsync(fd) == 0;
    const bool closed = close(fd) == 0;
    if (!synced || !closed) {
      throw RecordingError(path_ + ": " + std::strerror(errno) + "; free space and check the disk");
    }
  }

 private:
  void Write(const std::string& text) {
    std::size_t done = 0;
    while (done < text.size()) {
      const ssize_t n = write(fd_, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        throw RecordingError(path_ + ": " + std::strerror(errno) +
                             "; free space and check the disk (the rows so far are kept)");
      }
      done += static_cast<std::size_t>(n);
    }
  }
  std::string path_;
  int fd_ = -1;
};

// The profile on a thread of its own (the station is used by it alone once it starts): each
// segment to its start at the station's own speed, the settle, then its move at its speed.
class ProfileRunner {
 public:
  ProfileRunner(Station& station, const TrackRecipe& recipe)
      : station_(station), recipe_(recipe), own_speeds_(station.Speeds()) {}
  ~ProfileRunner() {
    if (thread_.joinable()) thread_.join();
  }
  void Start() { thread_ = std::thread([this] { Run(); }); }
  bool done() const { return done_.load(); }
  int segment() const { return segment_.load(); }
  // Waits for the thread (a Ctrl-C has stopped the move in progress).
  void Join() {
    if (thread_.joinable()) thread_.join();
  }
  // After Join: the moves sent, and the thread's error (null when none).
  const std::vector<CommandedMove>& moves() const { return moves_; }
  std::exception_ptr failure() const { return failure_; }

 private:
  void Run();
  void RunSegment(int k);
  void SetSpeed(Axis axis, double unit_per_s) {
    if (!(unit_per_s > 0.0)) return;
    station_.SetSpeed(axis, unit_per_s);
    changed_.insert(axis);
  }
  // The axes whose speed the run set back to what the station reported at the start.
  void RestoreSpeeds() {
    for (Axis axis : changed_) station_.SetSpeed(axis, own_speeds_.at(axis).speed);
    changed_.clear();
  }
  // A move that a Ctrl-C stops where it is (false).
  bool MoveUnlessStopped(const StationPosition& target) {
    return station_.MoveToUnless(target, [] { return StopRequested().load(); });
  }
  static void SleepMs(double ms) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double, std::milli>(ms);
    while (!StopRequested().load() && std::chrono::steady_clock::now() < end) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

  Station& station_;
  const TrackRecipe& recipe_;
  std::map<Axis, AxisSpeed> own_speeds_;
  std::set<Axis> changed_;
  std::vector<CommandedMove> moves_;
  std::atomic<bool> done_{false};
  std::atomic<int> segment_{-1};
  std::exception_ptr failure_;
  std::thread thread_;
};

void ProfileRunner::RunSegment(int k) {
  const TrackSegment& s = recipe_.segments[static_cast<std::size_t>(k)];
  RestoreSpeeds();
  if (!MoveUnlessStopped({s.slide_from_mm, s.pan_from_deg, recipe_.tilt_deg})) return;
  SleepMs(recipe_.settle_ms);
  if (StopRequested().load()) return;
  SetSpeed(Axis::kSlide, s.speed_mm_s);
  SetSpeed(Axis::kPan, s.pan_speed_deg_s);
  const auto speeds = station_.Speeds();
  CommandedMove move{s.slide_from_mm, s.slide_to_mm, speeds.at(Axis::kSlide).speed,
                     speeds.at(Axis::kSlide).acceleration, MonotonicNowNs()};
  segment_.store(k);
  moves_.push_back(move);  // the truth of a real rig, also of a move a Ctrl-C cut short
  MoveUnlessStopped({s.slide_to_mm, s.pan_to_deg, recipe_.tilt_deg});
}

void ProfileRunner::Run() {
  try {
    for (int k = 0; k < static_cast<int>(recipe_.segments.size()) && !StopRequested().load();
         ++k) {
      RunSegment(k);
    }
    SleepMs(recipe_.after_ms);
    RestoreSpeeds();
  } catch (...) {
    failure_ = std::current_exception();
    station_.Stop();
  }
  done_.store(true);
}

// One tracked frame as track.csv's row.
TrackFrameRow RowOf(const TrackSample& t, int segment) {
  const MeasureSample& s = t.estimate;
  TrackFrameRow r;
  r.frame = t.frame;
  r.camera_frame_id = t.camera_frame_id;
  r.camera_timestamp_ns = s.camera_timestamp_ns;
  r.utc_ns = s.utc_ns;
  r.exposure_ms = t.exposure_ms;
  r.segment = segment;
  r.ok = s.have_estimate && s.estimate.ok;
  if (r.ok) {
    r.d_mm = s.estimate.d_mm;
    r.d_se_mm = s.estimate.d_std_mm;
    r.theta_deg = s.estimate.theta_deg;
  }
  r.filtered = t.filtered;
  if (t.filtered) {
    r.track_d_mm = t.filter.position_mm.at(0);
    r.track_d_se_mm = t.filter.position_sd_mm.at(0);
    r.v_mm_per_s = t.filter.velocity_mm_per_s.at(0);
    r.v_se_mm_per_s = t.filter.velocity_sd_mm_per_s.at(0);
  }
  r.flags = QualityFlags(s);
  return r;
}

// What the run took: every frame's row and its host arrival time.
struct TrackTaken {
  std::vector<TrackFrameRow> rows;
  std::vector<std::int64_t> monotonic_ns;
  TrackCounters counters;
  bool cut = false;
};

// Tracks frames until the profile is done (or Ctrl-C), each row written as it comes.
TrackTaken TrackWhileMoving(TrackSession& session, ProfileRunner& profile, TrackCsv& csv) {
  TrackTaken taken;
  const auto t0 = std::chrono::steady_clock::now();
  profile.Start();
  while (!profile.done() && !StopRequested().load()) {
    const double time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const TrackSample sample = session.Next(time_s);
    if (sample.frame < 0) continue;  // a bracket check (none is asked for)
    taken.rows.push_back(RowOf(sample, profile.segment()));
    taken.monotonic_ns.push_back(sample.estimate.host_monotonic_ns);
    csv.Append(taken.rows.back());
  }
  taken.cut = StopRequested().load();
  return taken;
}

// The options of the track session: the recipe's exposure and filter on its rig.
MeasureArgs TrackArgsOf(const ValidateArgs& args, const TrackRecipe& recipe) {
  MeasureArgs m;
  m.model = args.model;
  m.rig = recipe.rig_path;
  m.track = true;
  m.exposure_ms = recipe.exposure_ms;
  m.accel_psd_mm2_per_s3 = recipe.accel_psd_mm2_per_s3;
  m.allow_model_mismatch = args.allow_model_mismatch;
  m.time_scale = args.time_scale;
  m.json = args.quiet;  // the camera's notes (LiveCameraOptions::quiet) follow --quiet
  return m;
}

// Places the IRED at the profile's start: homed, the current on and checked.
void PrepareStation(Station& station, const TrackRecipe& recipe, std::ostream& err) {
  station.Identify();
  station.CheckReadyToStart();
  if (!station.homed()) {
    err << "track: homing the station\n";
    station.Home();
  }
  station.SetCurrent(recipe.bias_ma);
  station.MeasureCheckedCurrent();
  const TrackSegment& first = recipe.segments.front();
  station.MoveTo({first.slide_from_mm, first.pan_from_deg, recipe.tilt_deg});
}

std::string Fixed(double value, int decimals) { return FixedText(value, decimals); }

// The figures, on the results' stream.
void ReportTrack(const TrackSummary& s, const std::string& dir, std::ostream& out) {
  out << "Track: " << s.frames << " frames (" << s.estimated << " estimated, " << s.moving
      << " moving with truth); per-frame error rms " << Fixed(s.error_rms_mm, 2) << " mm (mean "
      << Fixed(s.error_mean_mm, 2) << "), one-frame bound rms " << Fixed(s.bound_rms_mm, 2)
      << " mm, rms / bound " << Fixed(s.ratio_to_bound, 2) << " (goal <= "
      << Fixed(s.goal_ratio, 1) << ")\n";
  for (const TrackCruise& c : s.cruises) {
    out << "  segment " << c.segment << " cruise: filter v mean " << Fixed(c.v_mean_mm_per_s, 1)
        << " mm/s (truth " << Fixed(c.truth_v_mm_per_s, 1) << ", se "
        << Fixed(c.v_se_mean_mm_per_s, 1) << "), z mean " << Fixed(c.z_mean, 2) << ", z last "
        << Fixed(c.z_last, 2) << (c.within_3se ? "" : "  (outside 3 se)") << "\n";
  }
  out << "Run folder: " << dir << " (track.csv, summary.yaml)\n";
}

// The truth of every frame, the figures, summary.yaml.
void Summarize(const ValidateArgs& args, const TrackRecipe& recipe, const TrackRig& rig,
               const TrackTaken& taken, const std::vector<CommandedMove>& moves,
               const std::string& dir, CommandIo io) {
  std::vector<TrackTruth> truths;
  if (!rig.trajectory_csv.empty()) {
    truths = VirtualTrackTruths(taken.rows, rig.trajectory_csv, recipe.rig_path, recipe.bias_ma);
  }
  // A composed virtual rig's device emulators (Zaber, PTU) log no trajectory: the commanded
  // profile is its truth, as on hardware.
  const bool virtual_rig = std::any_of(truths.begin(), truths.end(),
                                       [](const TrackTruth& t) { return t.known; });
  if (!virtual_rig) {
    truths = CommandedTrackTruths(taken.rows, taken.monotonic_ns, moves,
                                  recipe.rig.camera.readout_ms, recipe.truth_sd_mm);
  }
  TrackSummary summary = SummarizeTrack(taken.rows, truths, kCruiseSettleS);
  summary.truth_source = virtual_rig ? "virtual rig trajectory at mid-exposure (exact)"
                                     : "commanded profile (stated uncertainty truth_sd_mm)";
  summary.bound_source = virtual_rig
                             ? "Cramer-Rao bound of one frame (the virtual rig's physics)"
                             : "the frame's standard error (no physics to bound on a real rig)";
  TrackSummaryContext context;
  context.context = {{"recipe", recipe.path}, {"model", args.model}, {"rig", recipe.rig_path}};
  const TrackCounters& c = taken.counters;
  context.counters = {{"triggered", c.triggered}, {"received", c.received},
                      {"estimated_by_session", c.estimated}, {"skipped", c.skipped},
                      {"lost", c.lost}, {"wrong_exposure", c.wrong_exposure}};
  context.cut = taken.cut;
  WriteTrackSummary(dir + "/summary.yaml", summary, context);
  ReportTrack(summary, dir, io.out);
}

}  // namespace

void RunTrackRecipe(const ValidateArgs& args, CommandIo io) {
  if (!args.resume_dir.empty()) {
    throw UsageError("a track run is not resumable: its motion is one continuous profile and "
                     "its truth one trajectory; run it again into a new folder (--out NEW_DIR)");
  }
  const TrackRecipe recipe = LoadTrackRecipe(args.recipe);
  const CalibrationModel model = LoadModel(args.model);
  const MeasureArgs track_args = TrackArgsOf(args, recipe);
  TrackExposureMs(track_args, model);  // refused before anything moves
  const TrackRig rig = FindTrackRig(recipe, io.err);
  const std::string dir = MakeTrackFolder(args, recipe);
  io.out << "Track recipe " << recipe.path << ": " << recipe.segments.size()
         << " segment(s) into " << dir << "\n";
  SignalGuard guard;  // Ctrl-C stops the station where it is, keeps what was taken
  LineLog log(dir + "/station.log");
  Station station(recipe.rig.station.composition, StationRunOptions(rig.ports, &log));
  PrepareStation(station, recipe, io.err);
  TrackSession session(track_args, model, io);
  if (!args.quiet) io.err << session.Header() << "\n";
  TrackCsv csv(dir + "/track.csv");
  ProfileRunner profile(station, recipe);
  TrackTaken taken;
  try {
    taken = TrackWhileMoving(session, profile, csv);
  } catch (...) {
    StopRequested().store(true);  // the profile thread stops the station and ends
    profile.Join();
    throw;
  }
  session.Finish();
  taken.counters = session.counters();
  profile.Join();
  taken.cut = taken.cut || profile.failure() != nullptr;
  csv.Close();
  Summarize(args, recipe, rig, taken, profile.moves(), dir, io);  // what was taken, also cut
  if (profile.failure()) std::rethrow_exception(profile.failure());
  if (taken.cut) {
    throw InterruptedError("track run stopped; what was taken is kept in " + dir +
                           " (track.csv, summary.yaml with cut: true). A track run is not "
                           "resumable: run it again into a new folder.");
  }
}

void RunValidateOrTrack(const ValidateArgs& args, CommandIo io) {
  RequireValid(args, "validate");
  RecipeKindOf(args.recipe) == "track" ? RunTrackRecipe(args, io) : RunValidate(args, io);
}

}  // namespace irdist
