#include "app/cli.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <ostream>
#include <sstream>

#include "app/recipe.h"
#include "app/run.h"
#include "app/station_cmd.h"
#include "app/tools.h"
#include "station/plan.h"

namespace irdist {
namespace {

struct SubcommandInfo {
  const char* name;
  const char* summary;
  const char* lands_with;  // what must be integrated before the command runs
};

// The dispatch table, in help order.
constexpr SubcommandInfo kSubcommands[] = {
    {"calibrate", "Sweep a calibration recipe on a rig, record it and fit model.yaml",
     "the station sweep (station/), the recording (acquisition/) and the calibration fit "
     "(estimator/)"},
    {"validate", "Sweep a validation recipe, estimate every bracket against the ground truth",
     "the station sweep (station/), the recording (acquisition/) and Algorithm 1 (estimator/)"},
    {"fit", "Fit model.yaml offline from a recording",
     "the recording reader (acquisition/) and the calibration fit (estimator/)"},
    {"playback", "Estimate distances offline from a recording with a model",
     "the recording reader (acquisition/) and Algorithm 1 (estimator/)"},
    {"check", "Check a recording for gaps, damaged frames and consistency",
     "the recording checker (acquisition/)"},
    {"plan", "Check a recipe and print its grid, order, frame count and duration estimate", ""},
    {"sim", "Run the virtual rig (camera on 127.0.0.1, station on a pty) until Ctrl-C",
     "the virtual rig (sim/)"},
    {"devices", "List the cameras and stations irdist can see",
     "camera discovery (acquisition/) and the station client (station/)"},
    {"station", "Put the station at a pose and current by hand (move, current, off, home, status)",
     "the station composition (station/)"},
    {"station-test", "Check a station board against docs/station-protocol.md (pass/fail table)",
     "the station conformance suite (station/)"},
};

const SubcommandInfo& Info(const std::string& name) {
  for (const SubcommandInfo& info : kSubcommands) {
    if (name == info.name) return info;
  }
  IRDIST_CHECK(false, "no subcommand ", name);
}

[[noreturn]] void ThrowNotAvailable(const std::string& name) {
  throw NotAvailableError("'irdist " + name + "' is not available in this build yet: it lands " +
                          "when " + Info(name).lands_with + " are integrated. Available today: " +
                          "'irdist plan RECIPE' checks a recipe and estimates its duration.");
}

template <typename Args>
void Invoke(const std::function<void(const Args&, CommandIo)>& handler, const std::string& name,
            const Args& args, CommandIo io) {
  if (!handler) ThrowNotAvailable(name);
  handler(args, io);
}

std::string JoinMs(const std::vector<double>& values) {
  std::ostringstream out;
  for (size_t i = 0; i < values.size(); ++i) out << (i > 0 ? ", " : "") << values[i];
  return out.str();
}

void PrintPlan(const Recipe& recipe, const Plan& plan, int show_poses, std::ostream& out) {
  out << "Recipe: " << recipe.path << " (" << recipe.name << ")";
  if (!recipe.description.empty()) out << ": " << recipe.description;
  out << "\nRig: " << recipe.rig.name << " (" << recipe.rig_path << ")\n";
  out << "Output: " << recipe.output_dir
      << "; after recording: " << AfterRecordingName(recipe.after) << "\n";
  const BracketSpec& bracket = recipe.sweep.bracket;
  out << "Bracket: t_ref " << bracket.t_ref_ms << " ms; t_meas " << JoinMs(bracket.t_meas_ms)
      << " ms; " << bracket.repeats << (bracket.repeats == 1 ? " repeat" : " repeats")
      << "; reference " << (bracket.retake_reference ? "retaken before each t_meas" : "taken once")
      << "\n";
  out << plan.summary.BriefReport() << "\n";
  const int total = static_cast<int>(plan.poses.size());
  const int shown = show_poses < 0 ? total : std::min(show_poses, total);
  if (shown == 0) return;
  out << "Order ("
      << (shown == total ? "all " + std::to_string(total)
                         : "first " + std::to_string(shown) + " of " + std::to_string(total))
      << " poses):\n";
  out << "      #  slide_mm   pan_deg  tilt_deg theta_deg   bias_ma  repeat\n";
  for (int i = 0; i < shown; ++i) {
    const Pose& p = plan.poses[static_cast<size_t>(i)];
    char line[160];
    std::snprintf(line, sizeof(line), "  %5d %9.2f %9.2f %9.2f %9.2f %9.2f %7d\n", p.index,
                  p.slide_mm, p.pan_deg, p.tilt_deg, p.theta_deg, p.bias_ma, p.repeat);
    out << line;
  }
}

// `irdist station` and `irdist station-test`.
void AddStationCommands(CLI::App& app, const Handlers& handlers, CommandIo io,
                        StationArgs* station, StationTestArgs* test,
                        std::vector<std::pair<CLI::App*, std::function<void()>>>* table) {
  CLI::App* sub = app.add_subcommand("station", Info("station").summary);
  sub->add_option("--rig", station->rig, "Rig name or rig file")->capture_default_str();
  sub->add_option("action", station->action, "move | current | off | home | status")
      ->required()
      ->check(CLI::IsMember({"move", "current", "off", "home", "status"}));
  sub->add_option("values", station->values,
                  "move: SLIDE_MM PAN_DEG TILT_DEG; current: MA");
  sub->add_option("--port", station->ports,
                  "NAME=PATH: the port of station device NAME (default: the rig file's, or the "
                  "running 'irdist sim' of a virtual rig)");
  table->emplace_back(sub, [=] { Invoke(handlers.station, "station", *station, io); });
  sub = app.add_subcommand("station-test", Info("station-test").summary);
  sub->add_option("port", test->port, "Serial port of the board (e.g. /dev/ttyUSB0)")->required();
  sub->add_option("--baud", test->baud, "Serial speed, bit/s")->capture_default_str();
  table->emplace_back(sub, [=] { Invoke(handlers.station_test, "station-test", *test, io); });
}

}  // namespace

std::vector<std::string> SubcommandNames() {
  std::vector<std::string> names;
  for (const SubcommandInfo& info : kSubcommands) names.emplace_back(info.name);
  return names;
}

void RunPlan(const PlanArgs& args, CommandIo io) {
  if (args.suggest) {
    RunSuggest(args, io);
    return;
  }
  const Recipe recipe = LoadRecipe(args.recipe);
  PrintPlan(recipe, PlanRecipe(recipe), args.show_poses, io.out);
}

Handlers DefaultHandlers() {
  Handlers handlers;
  handlers.plan = RunPlan;
  handlers.calibrate = RunCalibrate;
  handlers.validate = RunValidate;
  handlers.fit = RunFit;
  handlers.playback = RunPlayback;
  handlers.check = RunCheck;
  handlers.sim = RunSim;
  handlers.devices = RunDevices;
  handlers.station = RunStation;
  handlers.station_test = RunStationTest;
  return handlers;
}

int RunIrdist(int argc, const char* const* argv, CommandIo io, const Handlers& handlers) {
  const std::vector<std::string> names = SubcommandNames();
  std::string usage_hint = "Run 'irdist --help' for the commands, 'irdist COMMAND --help' for one.";
  if (argc > 1) {
    const std::string first = argv[1];
    if (!first.empty() && first[0] != '-' &&
        std::find(names.begin(), names.end(), first) == names.end()) {
      std::string message = "unknown command '" + first + "'; valid commands: ";
      for (size_t i = 0; i < names.size(); ++i) message += (i > 0 ? ", " : "") + names[i];
      throw UsageError(message + ". " + usage_hint);
    }
  }

  CLI::App app{
      "irdist: camera-to-IRED distance and orientation from gray levels, independent of the "
      "IRED's radiant intensity.",
      "irdist"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "irdist 0.1.0");

  CalibrateArgs calibrate;
  ValidateArgs validate;
  FitArgs fit;
  PlaybackArgs playback;
  CheckArgs check;
  PlanArgs plan;
  SimArgs sim;
  DevicesArgs devices;
  StationArgs station;
  StationTestArgs station_test;

  std::vector<std::pair<CLI::App*, std::function<void()>>> table;
  auto add = [&](const char* name) { return app.add_subcommand(name, Info(name).summary); };

  CLI::App* sub = add("calibrate");
  sub->add_option("recipe", calibrate.recipe, "Recipe file (recipes/*.yaml)")->required();
  sub->add_option("--out", calibrate.out_dir, "Run folder (overrides the recipe's output)");
  sub->add_option("--resume", calibrate.resume_dir, "Continue the cut run in this folder");
  sub->add_option("--time-scale", calibrate.time_scale,
                  "Virtual rig: simulated seconds per host second (default: the rig file's)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--quiet", calibrate.quiet, "No progress output");
  table.emplace_back(sub, [&] { Invoke(handlers.calibrate, "calibrate", calibrate, io); });

  sub = add("validate");
  sub->add_option("recipe", validate.recipe, "Recipe file (recipes/*.yaml)")->required();
  sub->add_option("--model", validate.model, "model.yaml from a calibration")->required();
  sub->add_option("--out", validate.out_dir, "Run folder (overrides the recipe's output)");
  sub->add_option("--resume", validate.resume_dir, "Continue the cut run in this folder");
  sub->add_option("--time-scale", validate.time_scale,
                  "Virtual rig: simulated seconds per host second (default: the rig file's)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--quiet", validate.quiet, "No progress output");
  table.emplace_back(sub, [&] { Invoke(handlers.validate, "validate", validate, io); });

  sub = add("fit");
  sub->add_option("recording", fit.recording, "Recording folder")->required();
  sub->add_option("--out", fit.out, "Model file to write");
  sub->add_flag("--recover-response", fit.recover_response,
                "Recover the camera's response from the brackets and linearise every pixel");
  table.emplace_back(sub, [&] { Invoke(handlers.fit, "fit", fit, io); });

  sub = add("playback");
  sub->add_option("recording", playback.recording, "Recording folder")->required();
  sub->add_option("--model", playback.model, "model.yaml from a calibration");
  sub->add_option("--out", playback.out_dir,
                  "Folder for features.csv, estimates.csv, summary.yaml");
  sub->add_flag("--show", playback.show, "Step through the frames in a window (needs a display)");
  table.emplace_back(sub, [&] { Invoke(handlers.playback, "playback", playback, io); });

  sub = add("check");
  sub->add_option("recording", check.recording, "Recording folder")->required();
  table.emplace_back(sub, [&] { Invoke(handlers.check, "check", check, io); });

  sub = add("plan");
  sub->add_option("recipe", plan.recipe, "Recipe file (recipes/*.yaml)")->required();
  sub->add_option("--poses", plan.show_poses, "How many poses of the order to print (-1: all)")
      ->capture_default_str()
      ->check(CLI::Range(-1, 1000000));
  sub->add_flag("--suggest", plan.suggest,
                "Take probe frames at the recipe's two ends on its rig and propose t_r, the t_n "
                "and the current");
  sub->add_option("--from", plan.from_summary,
                  "With --suggest: the latest validation's summary.yaml (its best dt)");
  sub->add_option("--out", plan.out_dir, "With --suggest: folder of the probe run");
  sub->add_option("--time-scale", plan.time_scale,
                  "With --suggest on a virtual rig: simulated seconds per second");
  sub->add_flag("--quiet", plan.quiet, "No progress output");
  table.emplace_back(sub, [&] { Invoke(handlers.plan, "plan", plan, io); });

  sub = add("sim");
  sub->add_option("rig", sim.rig, "Rig name or rig file of kind virtual")->capture_default_str();
  sub->add_option("--rig", sim.rig, "Rig name or rig file of kind virtual");
  sub->add_option("--time-scale", sim.time_scale, "Simulated seconds per host second")
      ->check(CLI::PositiveNumber);
  table.emplace_back(sub, [&] { Invoke(handlers.sim, "sim", sim, io); });

  sub = add("devices");
  sub->add_flag("--discover", devices.discover,
                "Also discover GigE/USB cameras (broadcasts on every network interface)");
  table.emplace_back(sub, [&] { Invoke(handlers.devices, "devices", devices, io); });
  AddStationCommands(app, handlers, io, &station, &station_test, &table);

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    return app.exit(e, io.out, io.err);
  } catch (const CLI::ParseError& e) {
    for (const auto& [command, run] : table) {
      if (command->parsed()) {
        const std::string name = command->get_name();
        throw UsageError(name + ": " + e.what() + ". Run 'irdist " + name + " --help' for usage.");
      }
    }
    throw UsageError(std::string(e.what()) + ". " + usage_hint);
  }
  for (const auto& [command, run] : table) {
    if (command->parsed()) {
      run();
      return 0;
    }
  }
  throw UsageError("no command given. " + usage_hint);
}

}  // namespace irdist
