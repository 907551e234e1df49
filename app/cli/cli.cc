#include "app/cli/cli.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <ostream>
#include <sstream>

#include "app/devices/camera_test.h"
#include "app/devices/station_cmd.h"
#include "app/devices/tools.h"
#include "app/live/measure.h"
#include "app/live/track_run.h"
#include "app/live/track_session.h"
#include "app/live/view.h"
#include "app/runs/offline.h"
#include "app/runs/plan_command.h"
#include "app/runs/run.h"
#include "base/bounds.h"
#include "base/version.h"
#include "station/plan.h"
#include "station/serial_transport.h"

namespace irdist {
namespace {

struct SubcommandInfo {
  const char* name;
  const char* summary;
};

// The dispatch table, in help order.
constexpr SubcommandInfo kSubcommands[] = {
    {"calibrate", "Sweep a calibration recipe on a rig, record it and fit model.yaml"},
    {"validate", "Sweep a validation recipe, estimate every bracket against the ground truth"},
    {"fit", "Fit model.yaml offline from a recording"},
    {"playback", "Estimate distances offline from a recording with a model"},
    {"check", "Check a recording for gaps, damaged frames and consistency"},
    {"plan", "Check a recipe and print its grid, order, frame count and duration estimate"},
    {"sim", "Run the virtual rig (camera on 127.0.0.1, station on a pty) until Ctrl-C"},
    {"devices", "List the cameras and stations irdist can see"},
    {"measure", "Measure distance, orientation (and 3D position) live from a calibrated camera"},
    {"snap", "Save one frame to a PNG; print the blob's position and a suggested roi_px"},
    {"view", "Live window on the camera: image, blob, ellipse, levels, estimate with --model"},
    {"station", "Put the station at a pose and current by hand (move, current, off, home, status)"},
    {"station-test", "Check a station board against docs/station-protocol.md (pass/fail table)"},
    {"camera-test", "Check a camera's features against what irdist needs (pass/fail table)"},
};

// A subcommand's summary for the help; a name outside the table is the program's fault.
const char* SummaryOf(const std::string& name) {
  for (const SubcommandInfo& info : kSubcommands) {
    if (name == info.name) return info.summary;
  }
  IRDIST_CHECK(false, "no subcommand ", name);
}

template <typename Args>
void Invoke(const std::function<void(const Args&, CommandIo)>& handler, const std::string& name,
            const Args& args, CommandIo io) {
  IRDIST_CHECK(static_cast<bool>(handler), "the command '", name, "' has no handler");
  handler(args, io);
}

// --time-scale: the virtual rig's range, said in plain numbers (not CLI11's double limits).
CLI::Validator TimeScaleRange() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(text, value) || !(value >= 0.01 && value <= 1000.0)) {
          return "--time-scale " + text +
                 " is outside 0.01..1000 (simulated seconds per host second; 1 = real time)";
        }
        return "";
      },
      "0.01..1000");
}

// A number flag (each value of a list flag): finite and inside (min, max] or [min, max], said
// with the flag's name, the range and an example (the flag with good values), before any device
// is opened.
CLI::Validator NumberIn(const std::string& flag, double min, double max, bool min_open,
                        const std::string& unit, const std::string& example) {
  char range[96];
  std::snprintf(range, sizeof(range), "%s%.10g, %.10g] %s", min_open ? "(" : "[", min, max,
                unit.c_str());
  const std::string range_text = range;
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double value = 0.0;
        const bool parsed = CLI::detail::lexical_cast(text, value);
        const bool inside = min_open ? value > min : value >= min;
        if (parsed && inside && value <= max) return "";
        return flag + " " + text + " is outside " + range_text + "; e.g. " + example;
      },
      range_text);
}

static_assert(kMaxExposureMs == bounds::kExposureMs.max, "one exposure bound (base/bounds.h)");

// A number flag of a quantity of the bounds table (base/bounds.h): finite and inside its range
// ("nan" and "0" refused by the flag's name, the range in plain numbers and an example).
CLI::Validator Bounded(const std::string& flag, const Bound& bound, const std::string& example) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double value = std::nan("");
        if (!CLI::detail::lexical_cast(text, value)) value = std::nan("");
        if (bound.Contains(value)) return "";
        return flag + " " + text + " is outside " + bound.RangeText() + " (" + bound.name + ": " +
               bound.why + "); e.g. " + example;
      },
      bound.RangeText());
}

// An output folder flag: absent, or a folder; never an existing file (or a path through one).
CLI::Validator FolderPath(const std::string& flag) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        std::error_code error;
        std::filesystem::path path(text);
        while (!path.empty() && !std::filesystem::exists(path, error)) path = path.parent_path();
        if (path.empty() || std::filesystem::is_directory(path, error)) return "";
        return flag + " " + text + ": " + path.string() +
               " is a file, not a folder; give a new or existing folder";
      },
      "FOLDER");
}

}  // namespace

std::vector<std::string> SubcommandNames() {
  std::vector<std::string> names;
  for (const SubcommandInfo& info : kSubcommands) names.emplace_back(info.name);
  return names;
}

Handlers DefaultHandlers() {
  Handlers handlers;
  handlers.plan = RunPlan;
  handlers.calibrate = RunCalibrate;
  handlers.validate = RunValidateOrTrack;  // a track recipe: app/live/track_run.h
  handlers.fit = RunFit;
  handlers.playback = RunPlayback;
  handlers.check = RunCheck;
  handlers.sim = RunSim;
  handlers.devices = RunDevices;
  handlers.measure = RunMeasureOrTrack;  // docs/measure.md "Tracking"
  handlers.snap = RunSnap;
  handlers.view = RunView;
  handlers.station = RunStation;
  handlers.station_test = RunStationTest;
  handlers.camera_test = RunCameraTest;
  return handlers;
}

namespace {

// Every command's arguments, filled by the parser.
struct ParsedArgs {
  CalibrateArgs calibrate;
  ValidateArgs validate;
  FitArgs fit;
  PlaybackArgs playback;
  CheckArgs check;
  PlanArgs plan;
  SimArgs sim;
  DevicesArgs devices;
  MeasureArgs measure;
  SnapArgs snap;
  ViewArgs view;
  StationArgs station;
  StationTestArgs station_test;
  CameraTestArgs camera_test;
};

// The subcommands as they are registered: each with the call that runs it.
class CommandTable {
 public:
  CommandTable(CLI::App& app, ParsedArgs& args, const Handlers& handlers, CommandIo io)
      : app_(app), args_(args), handlers_(handlers), io_(io) {}

  ParsedArgs& args() { return args_; }
  const Handlers& handlers() const { return handlers_; }

  // Adds subcommand `name` whose parsed `args` go to `handler`.
  template <typename Args>
  CLI::App* Add(const char* name, const std::function<void(const Args&, CommandIo)>& handler,
                const Args& args) {
    CLI::App* sub = app_.add_subcommand(name, SummaryOf(name));
    const std::string command = name;
    entries_.emplace_back(sub, [&handler, &args, command, io = io_] {
      Invoke(handler, command, args, io);
    });
    return sub;
  }

  // The parsed subcommand's entry, or nullptr.
  const std::pair<CLI::App*, std::function<void()>>* Parsed() const {
    for (const auto& entry : entries_) {
      if (entry.first->parsed()) return &entry;
    }
    return nullptr;
  }

 private:
  CLI::App& app_;
  ParsedArgs& args_;
  const Handlers& handlers_;
  CommandIo io_;
  std::vector<std::pair<CLI::App*, std::function<void()>>> entries_;
};

constexpr const char* kUsageHint =
    "Run 'irdist --help' for the commands, 'irdist COMMAND --help' for one.";

void AddTimeScale(CLI::App* sub, double& time_scale) {
  sub->add_option("--time-scale", time_scale,
                  "Virtual rig: simulated seconds per host second (default: the rig file's)")
      ->check(TimeScaleRange());
}

// fit's and calibrate's --keep-model (app/processing/recording_fit.h FitnessError).
constexpr const char* kKeepModelHelp =
    "Write model.yaml even when the fit misses its own frames beyond their noise (its fitness, "
    "docs/estimator.md); without it such a model goes to model.rejected.yaml and the exit is 1";

void AddCalibrate(CommandTable& table) {
  CalibrateArgs& a = table.args().calibrate;
  CLI::App* sub = table.Add("calibrate", table.handlers().calibrate, a);
  sub->add_option("recipe", a.recipe, "Recipe file (recipes/*.yaml)")->required();
  sub->add_option("--out", a.out_dir, "Run folder (overrides the recipe's output)");
  sub->add_option("--resume", a.resume_dir, "Continue the cut run in this folder");
  AddTimeScale(sub, a.time_scale);
  sub->add_flag("--quiet", a.quiet, "No progress output");
  sub->add_flag("--allow-nonlinear", a.allow_nonlinear,
                "Go on when the first pose's linearity error is above 1% (docs/devices/README.md)");
  sub->add_flag("--keep-model", a.keep_model, kKeepModelHelp);
}

void AddValidate(CommandTable& table) {
  ValidateArgs& a = table.args().validate;
  CLI::App* sub = table.Add("validate", table.handlers().validate, a);
  sub->add_option("recipe", a.recipe, "Recipe file (recipes/*.yaml)")->required();
  sub->add_option("--model", a.model, "model.yaml from a calibration")->required();
  sub->add_option("--out", a.out_dir, "Run folder (overrides the recipe's output)");
  sub->add_option("--resume", a.resume_dir, "Continue the cut run in this folder");
  AddTimeScale(sub, a.time_scale);
  sub->add_flag("--quiet", a.quiet, "No progress output");
  sub->add_flag("--allow-model-mismatch", a.allow_model_mismatch,
                "Use a model calibrated with another camera serial, pixel format or ROI");
}

void AddFitAndPlayback(CommandTable& table) {
  FitArgs& f = table.args().fit;
  CLI::App* sub = table.Add("fit", table.handlers().fit, f);
  sub->add_option("recording", f.recording, "Recording folder")->required();
  sub->add_option("--out", f.out, "Model file to write");
  sub->add_flag("--recover-response", f.recover_response,
                "Recover the camera's response from the brackets and linearise every pixel");
  sub->add_flag("--force", f.force, "Replace an existing model.yaml, features.csv and report");
  sub->add_flag("--keep-model", f.keep_model, kKeepModelHelp);

  PlaybackArgs& p = table.args().playback;
  sub = table.Add("playback", table.handlers().playback, p);
  sub->add_option("recording", p.recording, "Recording folder")->required();
  sub->add_option("--model", p.model, "model.yaml from a calibration");
  sub->add_option("--out", p.out_dir, "Folder for features.csv, estimates.csv, summary.yaml");
  sub->add_flag("--show", p.show, "Step through the frames in a window (needs a display)");
  sub->add_flag("--force", p.force,
                "Replace existing features.csv, estimates.csv, summary.yaml and report");
  sub->add_flag("--allow-model-mismatch", p.allow_model_mismatch,
                "Use a model calibrated with another camera serial, pixel format or ROI");
}

void AddCheckAndPlan(CommandTable& table) {
  CheckArgs& c = table.args().check;
  CLI::App* sub = table.Add("check", table.handlers().check, c);
  sub->add_option("recording", c.recording, "Recording folder, or an estimates.csv")->required();

  PlanArgs& p = table.args().plan;
  sub = table.Add("plan", table.handlers().plan, p);
  sub->add_option("recipe", p.recipe, "Recipe file (recipes/*.yaml)")->required();
  sub->add_option("--poses", p.show_poses, "How many poses of the order to print (-1: all)")
      ->capture_default_str()
      ->check(CLI::Range(-1, 1000000));
  sub->add_flag("--suggest", p.suggest,
                "Take probe frames at the recipe's two ends on its rig and propose t_r, the t_n "
                "and the current");
  sub->add_option("--from", p.from_summary,
                  "With --suggest: the latest validation's summary.yaml (its best dt)");
  sub->add_option("--out", p.out_dir, "With --suggest: folder of the probe run");
  sub->add_option("--time-scale", p.time_scale,
                  "With --suggest on a virtual rig: simulated seconds per second")
      ->check(TimeScaleRange());
  sub->add_flag("--quiet", p.quiet, "No progress output");
}

void AddSimAndDevices(CommandTable& table) {
  SimArgs& s = table.args().sim;
  CLI::App* sub = table.Add("sim", table.handlers().sim, s);
  sub->add_option("rig", s.rig, "Rig name or rig file of kind virtual")->capture_default_str();
  sub->add_option("--rig", s.rig, "Rig name or rig file of kind virtual");
  sub->add_option("--time-scale", s.time_scale, "Simulated seconds per host second")
      ->check(TimeScaleRange());

  DevicesArgs& d = table.args().devices;
  sub = table.Add("devices", table.handlers().devices, d);
  sub->add_flag("--discover", d.discover,
                "Also discover GigE/USB cameras (broadcasts on every network interface)");
}

void AddAt(CLI::App* sub, std::vector<double>& at) {
  sub->add_option("--at", at,
                  "Virtual rig started by this command only (not with 'irdist sim' running: use "
                  "'irdist station'): place the IRED through the station at "
                  "SLIDE_MM,PAN_DEG,TILT_DEG,BIAS_MA first")
      ->delimiter(',')
      ->expected(4)
      ->check(NumberIn("--at", -1e6, 1e6, false, "(mm, deg, deg, mA)", "--at 2000,10,0,500"))
      ->check(NumberIn("--at (its BIAS_MA)", 0.0, 1e6, false, "mA", "--at 2000,10,0,500")
                  .application_index(3));
}

// measure --track and its options (docs/measure.md "Tracking").
void AddTrack(CLI::App* sub, MeasureArgs& a) {
  sub->add_flag("--track", a.track,
                "An estimate per frame at one exposure, with a constant-velocity track "
                "(--count counts frames)");
  sub->add_option("--exposure-ms", a.exposure_ms,
                  "With --track: the exposure (default: the model's reference exposure)")
      ->check(Bounded("--exposure-ms", bounds::kExposureMs, "--exposure-ms 8"));
  sub->add_option("--accel-psd", a.accel_psd_mm2_per_s3,
                  "With --track: the filter's acceleration noise density, mm^2/s^3 (default 1e5)")
      ->check(Bounded("--accel-psd", bounds::kAccelPsd, "--accel-psd 1e5"));
  sub->add_option("--check-every", a.check_every_s,
                  "With --track: a full bracket every S seconds, checked against the track")
      ->check(Bounded("--check-every", bounds::kDurationS, "--check-every 5"));
}

void AddMeasure(CommandTable& table) {
  MeasureArgs& a = table.args().measure;
  CLI::App* sub = table.Add("measure", table.handlers().measure, a);
  sub->add_option("--model", a.model, "model.yaml from a calibration")->required();
  sub->add_option("--rig", a.rig, "Rig name or rig file")->capture_default_str();
  sub->add_option("--t-ref-ms", a.t_ref_ms, "Reference exposure (default: the model's)")
      ->check(Bounded("--t-ref-ms", bounds::kExposureMs, "--t-ref-ms 8"));
  sub->add_option("--t-meas-ms", a.t_meas_ms, "Measurement exposures (default: the model's)")
      ->delimiter(',')
      ->check(Bounded("--t-meas-ms", bounds::kExposureMs, "--t-meas-ms 30,32,34,36"));
  sub->add_option("--count", a.count, "Stop after N brackets")
      ->check(Bounded("--count", bounds::kCount, "--count 100"));
  sub->add_option("--duration", a.duration_s, "Stop after S seconds")
      ->check(Bounded("--duration", bounds::kDurationS, "--duration 60"));
  sub->add_flag("--json", a.json, "One JSON object per bracket on stdout (docs/measure.md)");
  sub->add_option("--out", a.out_dir, "Folder for estimates.csv (and recording/ with --record)")
      ->check(FolderPath("--out"));
  sub->add_flag("--record", a.record, "With --out: record the frames (playable by playback)");
  sub->add_option("--max-disk-gb", a.max_disk_gb,
                  "With --record: stop before the recording exceeds this many GB (default: stop "
                  "before the disk's free space falls below min(1 GiB, 5% of the disk))")
      ->check(Bounded("--max-disk-gb", bounds::kDiskGb, "--max-disk-gb 20"));
  AddAt(sub, a.at);
  AddTimeScale(sub, a.time_scale);
  sub->add_flag("--allow-model-mismatch", a.allow_model_mismatch,
                "Use a model calibrated with another camera serial, pixel format or ROI");
  AddTrack(sub, a);
}

void AddSnapAndView(CommandTable& table) {
  SnapArgs& s = table.args().snap;
  CLI::App* sub = table.Add("snap", table.handlers().snap, s);
  sub->add_option("--rig", s.rig, "Rig name or rig file")->capture_default_str();
  sub->add_option("--out", s.out, "PNG file to write")->required();
  sub->add_flag("--force", s.force, "Replace an existing --out file");
  sub->add_option("--exposure-ms", s.exposure_ms, "Exposure")
      ->check(Bounded("--exposure-ms", bounds::kExposureMs, "--exposure-ms 8"));
  AddAt(sub, s.at);
  AddTimeScale(sub, s.time_scale);

  ViewArgs& v = table.args().view;
  sub = table.Add("view", table.handlers().view, v);
  sub->add_option("--rig", v.rig, "Rig name or rig file")->capture_default_str();
  sub->add_option("--model", v.model, "model.yaml: show the live estimate");
  sub->add_option("--exposure-ms", v.exposure_ms,
                  "Exposure of single frames: without a model, and of the whole sensor")
      ->check(Bounded("--exposure-ms", bounds::kExposureMs, "--exposure-ms 8"));
  sub->add_flag("--whole-sensor", v.whole_sensor,
                "Start on the whole sensor with the ROI drawn (the w key toggles)");
  AddAt(sub, v.at);
  sub->add_option("--frames", v.frames, "Quit after N frames (0: at q or Esc)");
  sub->add_option("--screenshot", v.screenshot, "Save the last window image to this PNG");
  sub->add_flag("--force", v.force, "Replace an existing --screenshot file");
  AddTimeScale(sub, v.time_scale);
}

// Unknown first words get the list of valid commands (CLI11 would only say "extra argument").
void CheckCommandName(int argc, const char* const* argv) {
  if (argc <= 1) return;
  const std::vector<std::string> names = SubcommandNames();
  const std::string first = argv[1];
  if (first.empty() || first[0] == '-' ||
      std::find(names.begin(), names.end(), first) != names.end()) {
    return;
  }
  std::string message = "unknown command '" + first + "'; valid commands: ";
  for (size_t i = 0; i < names.size(); ++i) message += (i > 0 ? ", " : "") + names[i];
  throw UsageError(message + ". " + kUsageHint);
}

// Parses; a parse error names the subcommand it happened in.
int ParseAndRun(CLI::App& app, const CommandTable& table, int argc, const char* const* argv,
                CommandIo io) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    return app.exit(e, io.out, io.err);
  } catch (const CLI::ParseError& e) {
    if (const auto* entry = table.Parsed()) {
      const std::string name = entry->first->get_name();
      throw UsageError(name + ": " + e.what() + ". Run 'irdist " + name + " --help' for usage.");
    }
    throw UsageError(std::string(e.what()) + ". " + kUsageHint);
  }
  const auto* entry = table.Parsed();
  if (entry == nullptr) throw UsageError(std::string("no command given. ") + kUsageHint);
  entry->second();
  return 0;
}

}  // namespace

// `irdist station`, `irdist station-test` and `irdist camera-test`.
void AddStationCommands(CommandTable& table) {
  StationArgs& station = table.args().station;
  CLI::App* sub = table.Add("station", table.handlers().station, station);
  sub->add_option("--rig", station.rig, "Rig name or rig file")->capture_default_str();
  sub->add_option("action", station.action, "move | current | off | home | status")
      ->required()
      ->check(CLI::IsMember({"move", "current", "off", "home", "status"}));
  sub->add_option("values", station.values, "move: SLIDE_MM PAN_DEG TILT_DEG; current: MA");
  sub->add_option("--port", station.ports,
                  "NAME=PATH: the port of station device NAME (default: the rig file's, or the "
                  "running 'irdist sim' of a virtual rig)");
  StationTestArgs& test = table.args().station_test;
  sub = table.Add("station-test", table.handlers().station_test, test);
  sub->add_option("port", test.port, "Serial port of the board (e.g. /dev/ttyUSB0)")->required();
  sub->add_option("--baud", test.baud, "Serial speed, bit/s")
      ->capture_default_str()
      ->check(NumberIn("--baud", 1, kMaxBaud, false, "bit/s", "--baud 115200"));
  CameraTestArgs& camera = table.args().camera_test;
  sub = table.Add("camera-test", table.handlers().camera_test, camera);
  sub->add_option("camera", camera.camera,
                  "IP address, Aravis id or serial (default: the running `irdist sim` camera)");
  sub->add_option("--rig", camera.rig,
                  "Rig file whose camera settings a run uses (and, without CAMERA, whose running "
                  "sim to test; default virtual)");
}

int RunIrdist(int argc, const char* const* argv, CommandIo io, const Handlers& handlers) {
  CheckCommandName(argc, argv);
  CLI::App app{
      "irdist: camera-to-IRED distance and orientation from gray levels, independent of the "
      "IRED's radiant intensity.",
      "irdist"};
  app.require_subcommand(1);
  app.set_version_flag("--version", kSoftwareVersion);
  ParsedArgs args;
  CommandTable table(app, args, handlers, io);
  AddCalibrate(table);
  AddValidate(table);
  AddFitAndPlayback(table);
  AddCheckAndPlan(table);
  AddSimAndDevices(table);
  AddMeasure(table);
  AddSnapAndView(table);
  AddStationCommands(table);
  return ParseAndRun(app, table, argc, argv, io);
}

}  // namespace irdist
