#include "app/cli/cli.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <ostream>
#include <sstream>

#include "app/devices/camera_test.h"
#include "app/devices/devices_command.h"
#include "app/devices/sim_command.h"
#include "app/devices/station_cmd.h"
#include "app/live/measure.h"
#include "app/live/snap_command.h"
#include "app/live/track_run.h"
#include "app/live/track_session.h"
#include "app/live/view.h"
#include "app/runs/check_command.h"
#include "app/runs/fit_command.h"
#include "app/runs/plan_command.h"
#include "app/runs/playback_command.h"
#include "app/runs/run.h"
#include "base/bounds.h"
#include "base/version.h"
#include "station/plan.h"
#include "station/serial_transport.h"

namespace irdist {
namespace {

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
        if (!CLI::detail::lexical_cast(text, value) || !bounds::kTimeScale.Contains(value)) {
          return "--time-scale " + text + " is outside " + BoundNumber(bounds::kTimeScale.min) +
                 ".." + BoundNumber(bounds::kTimeScale.max) +
                 " (simulated seconds per host second; 1 = real time)";
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

void CalibrateFlags(CLI::App* sub, CalibrateArgs& a) {
  sub->add_option("recipe", a.recipe, "Recipe file (recipes/*.yaml)")->required();
  sub->add_option("--out", a.out_dir, "Run folder (overrides the recipe's output)");
  sub->add_option("--resume", a.resume_dir, "Continue the cut run in this folder");
  AddTimeScale(sub, a.time_scale);
  sub->add_flag("--quiet", a.quiet, "No progress output");
  sub->add_flag("--allow-nonlinear", a.allow_nonlinear,
                "Go on when the first pose's linearity error is above 1% (docs/devices/README.md)");
  sub->add_flag("--keep-model", a.keep_model, kKeepModelHelp);
}

void ValidateFlags(CLI::App* sub, ValidateArgs& a) {
  sub->add_option("recipe", a.recipe, "Recipe file (recipes/*.yaml)")->required();
  sub->add_option("--model", a.model, "model.yaml from a calibration")->required();
  sub->add_option("--out", a.out_dir, "Run folder (overrides the recipe's output)");
  sub->add_option("--resume", a.resume_dir, "Continue the cut run in this folder");
  AddTimeScale(sub, a.time_scale);
  sub->add_flag("--quiet", a.quiet, "No progress output");
  sub->add_flag("--allow-model-mismatch", a.allow_model_mismatch,
                "Use a model calibrated with another camera serial, pixel format or ROI");
}

void FitFlags(CLI::App* sub, FitArgs& f) {
  sub->add_option("recording", f.recording, "Recording folder")->required();
  sub->add_option("--out", f.out, "Model file to write");
  sub->add_flag("--recover-response", f.recover_response,
                "Recover the camera's response from the brackets and linearise every pixel");
  sub->add_flag("--force", f.force, "Replace an existing model.yaml, features.csv and report");
  sub->add_flag("--keep-model", f.keep_model, kKeepModelHelp);
}

void PlaybackFlags(CLI::App* sub, PlaybackArgs& p) {
  sub->add_option("recording", p.recording, "Recording folder")->required();
  sub->add_option("--model", p.model, "model.yaml from a calibration");
  sub->add_option("--out", p.out_dir, "Folder for features.csv, estimates.csv, summary.yaml");
  sub->add_flag("--show", p.show, "Step through the frames in a window (needs a display)");
  sub->add_flag("--force", p.force,
                "Replace existing features.csv, estimates.csv, summary.yaml and report");
  sub->add_flag("--allow-model-mismatch", p.allow_model_mismatch,
                "Use a model calibrated with another camera serial, pixel format or ROI");
}

void CheckFlags(CLI::App* sub, CheckArgs& c) {
  sub->add_option("recording", c.recording, "Recording folder, or an estimates.csv")->required();
}

void PlanFlags(CLI::App* sub, PlanArgs& p) {
  sub->add_option("recipe", p.recipe, "Recipe file (recipes/*.yaml)")->required();
  sub->add_option("--poses", p.show_poses, "How many poses of the order to print (-1: all)")
      ->capture_default_str()
      ->check(CLI::Range(-1, kMaxShownPoses));
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

void SimFlags(CLI::App* sub, SimArgs& s) {
  sub->add_option("rig", s.rig, "Rig name or rig file of kind virtual")->capture_default_str();
  sub->add_option("--rig", s.rig, "Rig name or rig file of kind virtual");
  sub->add_option("--time-scale", s.time_scale, "Simulated seconds per host second")
      ->check(TimeScaleRange());
}

void DevicesFlags(CLI::App* sub, DevicesArgs& d) {
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
      ->check(NumberIn("--at", -kMaxAtValue, kMaxAtValue, false, "(mm, deg, deg, mA)",
                       "--at 2000,10,0,500"))
      ->check(NumberIn("--at (its BIAS_MA)", 0.0, kMaxAtValue, false, "mA", "--at 2000,10,0,500")
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

void MeasureFlags(CLI::App* sub, MeasureArgs& a) {
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

void SnapFlags(CLI::App* sub, SnapArgs& s) {
  sub->add_option("--rig", s.rig, "Rig name or rig file")->capture_default_str();
  sub->add_option("--out", s.out, "PNG file to write")->required();
  sub->add_flag("--force", s.force, "Replace an existing --out file");
  sub->add_option("--exposure-ms", s.exposure_ms, "Exposure")
      ->check(Bounded("--exposure-ms", bounds::kExposureMs, "--exposure-ms 8"));
  AddAt(sub, s.at);
  AddTimeScale(sub, s.time_scale);
}

void ViewFlags(CLI::App* sub, ViewArgs& v) {
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

// `irdist station`, `irdist station-test` and `irdist camera-test`.
void StationFlags(CLI::App* sub, StationArgs& station) {
  sub->add_option("--rig", station.rig, "Rig name or rig file")->capture_default_str();
  sub->add_option("action", station.action, "move | current | off | home | status")
      ->required()
      ->check(CLI::IsMember({"move", "current", "off", "home", "status"}));
  sub->add_option("values", station.values, "move: SLIDE_MM PAN_DEG TILT_DEG; current: MA");
  sub->add_option("--port", station.ports,
                  "NAME=PATH: the port of station device NAME (default: the rig file's, or the "
                  "running 'irdist sim' of a virtual rig)");
}

void StationTestFlags(CLI::App* sub, StationTestArgs& test) {
  sub->add_option("port", test.port, "Serial port of the board (e.g. /dev/ttyUSB0)")->required();
  sub->add_option("--baud", test.baud, "Serial speed, bit/s")
      ->capture_default_str()
      ->check(NumberIn("--baud", 1, kMaxBaud, false, "bit/s", "--baud 115200"));
}

void CameraTestFlags(CLI::App* sub, CameraTestArgs& camera) {
  sub->add_option("camera", camera.camera,
                  "IP address, Aravis id or serial (default: the running `irdist sim` camera)");
  sub->add_option("--rig", camera.rig,
                  "Rig file whose camera settings a run uses (and, without CAMERA, whose running "
                  "sim to test; default virtual)");
}

// One command of the table: what `irdist --help` lists, and how it is wired.
struct Command {
  const char* name;
  const char* help;
  // Adds the command's flags to `sub` over Args of its own; returns the call that runs the
  // command's handler in `handlers` with them.
  std::function<void()> (*add)(CLI::App* sub, const Handlers& handlers, CommandIo io);
  void (*set_default)(Handlers* handlers);  // this build's handler, the engine's entry point
  bool (*has_handler)(const Handlers& handlers);
};

// A command's wiring from its Args, its slot in Handlers, its flags and its entry point.
template <typename Args, CommandHandler<Args> Handlers::*kSlot, void (*kFlags)(CLI::App*, Args&),
          void (*kRun)(const Args&, CommandIo)>
struct Wiring {
  static std::function<void()> Add(CLI::App* sub, const Handlers& handlers, CommandIo io) {
    auto args = std::make_shared<Args>();
    kFlags(sub, *args);
    const CommandHandler<Args>& handler = handlers.*kSlot;
    return [args, &handler, name = sub->get_name(), io] { Invoke(handler, name, *args, io); };
  }
  static void SetDefault(Handlers* handlers) { handlers->*kSlot = kRun; }
  static bool HasHandler(const Handlers& handlers) { return static_cast<bool>(handlers.*kSlot); }
};

template <typename Args, CommandHandler<Args> Handlers::*kSlot, void (*kFlags)(CLI::App*, Args&),
          void (*kRun)(const Args&, CommandIo)>
constexpr Command Entry(const char* name, const char* help) {
  using W = Wiring<Args, kSlot, kFlags, kRun>;
  return Command{name, help, &W::Add, &W::SetDefault, &W::HasHandler};
}

// The commands, in help order: adding one is one entry (and its Args, flags and slot).
const Command kCommands[] = {
    Entry<CalibrateArgs, &Handlers::calibrate, CalibrateFlags, RunCalibrate>(
        "calibrate", "Sweep a calibration recipe on a rig, record it and fit model.yaml"),
    // A track recipe: app/live/track_run.h.
    Entry<ValidateArgs, &Handlers::validate, ValidateFlags, RunValidateOrTrack>(
        "validate", "Sweep a validation recipe, estimate every bracket against the ground truth"),
    Entry<FitArgs, &Handlers::fit, FitFlags, RunFit>("fit",
                                                     "Fit model.yaml offline from a recording"),
    Entry<PlaybackArgs, &Handlers::playback, PlaybackFlags, RunPlayback>(
        "playback", "Estimate distances offline from a recording with a model"),
    Entry<CheckArgs, &Handlers::check, CheckFlags, RunCheck>(
        "check", "Check a recording for gaps, damaged frames and consistency"),
    Entry<PlanArgs, &Handlers::plan, PlanFlags, RunPlan>(
        "plan", "Check a recipe and print its grid, order, frame count and duration estimate"),
    Entry<SimArgs, &Handlers::sim, SimFlags, RunSim>(
        "sim", "Run the virtual rig (camera on 127.0.0.1, station on a pty) until Ctrl-C"),
    Entry<DevicesArgs, &Handlers::devices, DevicesFlags, RunDevices>(
        "devices", "List the cameras and stations irdist can see"),
    // --track: docs/measure.md "Tracking".
    Entry<MeasureArgs, &Handlers::measure, MeasureFlags, RunMeasureOrTrack>(
        "measure", "Measure distance, orientation (and 3D position) live from a calibrated camera"),
    Entry<SnapArgs, &Handlers::snap, SnapFlags, RunSnap>(
        "snap", "Save one frame to a PNG; print the blob's position and a suggested roi_px"),
    Entry<ViewArgs, &Handlers::view, ViewFlags, RunView>(
        "view", "Live window on the camera: image, blob, ellipse, levels, estimate with --model"),
    Entry<StationArgs, &Handlers::station, StationFlags, RunStation>(
        "station",
        "Put the station at a pose and current by hand (move, current, off, home, status)"),
    Entry<StationTestArgs, &Handlers::station_test, StationTestFlags, RunStationTest>(
        "station-test", "Check a station board against docs/station-protocol.md (pass/fail table)"),
    Entry<CameraTestArgs, &Handlers::camera_test, CameraTestFlags, RunCameraTest>(
        "camera-test", "Check a camera's features against what irdist needs (pass/fail table)"),
};

// The registered subcommands, each with the call that runs it.
using Registered = std::vector<std::pair<CLI::App*, std::function<void()>>>;

Registered AddCommands(CLI::App& app, const Handlers& handlers, CommandIo io) {
  Registered registered;
  for (const Command& command : kCommands) {
    CLI::App* sub = app.add_subcommand(command.name, command.help);
    registered.emplace_back(sub, command.add(sub, handlers, io));
  }
  return registered;
}

// The parsed subcommand's entry, or nullptr.
const Registered::value_type* ParsedOf(const Registered& registered) {
  for (const auto& entry : registered) {
    if (entry.first->parsed()) return &entry;
  }
  return nullptr;
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
int ParseAndRun(CLI::App& app, const Registered& registered, int argc, const char* const* argv,
                CommandIo io) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    return app.exit(e, io.out, io.err);
  } catch (const CLI::ParseError& e) {
    if (const auto* entry = ParsedOf(registered)) {
      const std::string name = entry->first->get_name();
      throw UsageError(name + ": " + e.what() + ". Run 'irdist " + name + " --help' for usage.");
    }
    throw UsageError(std::string(e.what()) + ". " + kUsageHint);
  }
  const auto* entry = ParsedOf(registered);
  if (entry == nullptr) throw UsageError(std::string("no command given. ") + kUsageHint);
  entry->second();
  return 0;
}

}  // namespace

std::vector<std::string> SubcommandNames() {
  std::vector<std::string> names;
  for (const Command& command : kCommands) names.emplace_back(command.name);
  return names;
}

Handlers DefaultHandlers() {
  Handlers handlers;
  for (const Command& command : kCommands) command.set_default(&handlers);
  return handlers;
}

std::vector<std::string> CommandsWithoutHandler(const Handlers& handlers) {
  std::vector<std::string> names;
  for (const Command& command : kCommands) {
    if (!command.has_handler(handlers)) names.emplace_back(command.name);
  }
  return names;
}

std::vector<std::string> CommandsWithoutHelp() {
  std::vector<std::string> names;
  for (const Command& command : kCommands) {
    if (command.help == nullptr || command.help[0] == '\0') names.emplace_back(command.name);
  }
  return names;
}

int RunIrdist(int argc, const char* const* argv, CommandIo io, const Handlers& handlers) {
  CheckCommandName(argc, argv);
  CLI::App app{
      "irdist: camera-to-IRED distance and orientation from gray levels, independent of the "
      "IRED's radiant intensity.",
      "irdist"};
  app.require_subcommand(1);
  app.set_version_flag("--version", kSoftwareVersion);
  const Registered registered = AddCommands(app, handlers, io);
  return ParseAndRun(app, registered, argc, argv, io);
}

}  // namespace irdist
