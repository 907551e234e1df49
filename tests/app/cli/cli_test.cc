#include "app/cli/cli.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

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
#include "base/process.h"

namespace irdist {
namespace {

const std::string kRecipes = std::string(IRDIST_SOURCE_DIR) + "/recipes";

// Runs RunIrdist on the words of a command line; returns its exit code.
int RunWords(const std::vector<std::string>& words, const Handlers& handlers,
             std::string* out = nullptr, std::string* err = nullptr) {
  std::vector<const char*> argv = {"irdist"};
  for (const std::string& word : words) argv.push_back(word.c_str());
  std::ostringstream out_stream;
  std::ostringstream err_stream;
  const int code =
      RunIrdist(static_cast<int>(argv.size()), argv.data(), {out_stream, err_stream}, handlers);
  if (out != nullptr) *out = out_stream.str();
  if (err != nullptr) *err = err_stream.str();
  return code;
}

TEST(CliTest, DefaultArgsAreUsable) {
  PlanArgs plan;
  EXPECT_GT(plan.show_poses, 0);
  SimArgs sim;
  EXPECT_EQ(sim.rig, "virtual");
  EXPECT_TRUE(static_cast<bool>(DefaultHandlers().plan));
}

// The version is written once, in the top CMakeLists.txt's project(); --version says that one.
TEST(CliTest, VersionIsTheProjectVersionFromCMake) {
  std::ifstream cmake(std::string(IRDIST_SOURCE_DIR) + "/CMakeLists.txt");
  const std::string text{std::istreambuf_iterator<char>(cmake), std::istreambuf_iterator<char>()};
  const std::string key = "project(irdist VERSION ";
  const size_t at = text.find(key);
  ASSERT_NE(at, std::string::npos);
  const std::string version = text.substr(at + key.size(), text.find(' ', at + key.size()) -
                                                               at - key.size());
  std::string out;
  EXPECT_EQ(RunWords({"--version"}, Handlers{}, &out), 0);
  EXPECT_EQ(out, "irdist " + version + "\n");
}

TEST(CliTest, EverySubcommandIsInTheTable) {
  EXPECT_EQ(SubcommandNames(),
            (std::vector<std::string>{"calibrate", "validate", "fit", "playback", "check", "plan",
                                      "sim", "devices", "measure", "snap", "view", "station",
                                      "station-test", "camera-test"}));
}

TEST(CliTest, MeasureTakesItsOptions) {
  Handlers handlers;
  MeasureArgs measure;
  handlers.measure = [&](const MeasureArgs& args, CommandIo) { measure = args; };
  EXPECT_EQ(RunWords({"measure", "--model", "m.yaml", "--rig", "lab", "--count", "5", "--json",
                      "--out", "o", "--record", "--at", "2000,10,0,490", "--t-meas-ms", "30,34",
                      "--allow-model-mismatch"},
                     handlers),
            0);
  EXPECT_EQ(measure.model, "m.yaml");
  EXPECT_EQ(measure.rig, "lab");
  EXPECT_EQ(measure.count, 5);
  EXPECT_TRUE(measure.json && measure.record && measure.allow_model_mismatch);
  EXPECT_EQ(measure.out_dir, "o");
  EXPECT_EQ(measure.at, (std::vector<double>{2000, 10, 0, 490}));
  EXPECT_EQ(measure.t_meas_ms, (std::vector<double>{30, 34}));
  EXPECT_THROW(RunWords({"measure"}, handlers), UsageError);  // --model missing
  EXPECT_THROW(RunWords({"measure", "--model", "m", "--at", "1,2"}, handlers), UsageError);
}

TEST(CliTest, PlaybackAndValidateTakeTheMismatchOverride) {
  Handlers handlers;
  PlaybackArgs playback;
  ValidateArgs validate;
  handlers.playback = [&](const PlaybackArgs& args, CommandIo) { playback = args; };
  handlers.validate = [&](const ValidateArgs& args, CommandIo) { validate = args; };
  EXPECT_EQ(RunWords({"playback", "rec", "--model", "m", "--allow-model-mismatch"}, handlers), 0);
  EXPECT_TRUE(playback.allow_model_mismatch);
  EXPECT_EQ(RunWords({"validate", "r.yaml", "--model", "m"}, handlers), 0);
  EXPECT_FALSE(validate.allow_model_mismatch);
}

TEST(CliTest, UnknownOrMissingCommandIsAUsageError) {
  try {
    RunWords({"frobnicate"}, DefaultHandlers());
    FAIL() << "no error";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown command 'frobnicate'"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("calibrate, validate, fit"), std::string::npos);
  }
  EXPECT_THROW(RunWords({}, DefaultHandlers()), UsageError);
  EXPECT_THROW(RunWords({"plan"}, DefaultHandlers()), UsageError);                // recipe missing
  EXPECT_THROW(RunWords({"plan", "a", "b"}, DefaultHandlers()), UsageError);      // one too many
  EXPECT_THROW(RunWords({"validate", "r.yaml"}, DefaultHandlers()), UsageError);  // --model missing
  EXPECT_THROW(RunWords({"plan", "--bogus", "r.yaml"}, DefaultHandlers()), UsageError);
}

// One table: every command in it has its help and, in this build, its handler; an empty
// Handlers leaves every command of the table without one (each entry names its own slot).
TEST(CliTest, EveryCommandInTheTableHasAHandlerAndHelp) {
  EXPECT_EQ(CommandsWithoutHandler(DefaultHandlers()), std::vector<std::string>{});
  EXPECT_EQ(CommandsWithoutHelp(), std::vector<std::string>{});
  EXPECT_EQ(CommandsWithoutHandler(Handlers{}), SubcommandNames());
  Handlers one;
  one.station_test = [](const StationTestArgs&, CommandIo) {};
  std::vector<std::string> others = SubcommandNames();
  others.erase(std::find(others.begin(), others.end(), "station-test"));
  EXPECT_EQ(CommandsWithoutHandler(one), others);
}

TEST(CliTest, HelpListsTheCommands) {
  std::string out;
  EXPECT_EQ(RunWords({"--help"}, DefaultHandlers(), &out), 0);
  for (const std::string& name : SubcommandNames()) {
    EXPECT_NE(out.find(name), std::string::npos) << name;
  }
}

// The table binds each command to the function of its family that runs it.
template <typename Args>
bool Calls(const std::function<void(const Args&, CommandIo)>& handler,
           void (*function)(const Args&, CommandIo)) {
  using Pointer = void (*)(const Args&, CommandIo);
  const Pointer* target = handler.template target<Pointer>();
  return target != nullptr && *target == function;
}

TEST(CliTest, EveryCommandRunsTheFunctionOfItsFamily) {
  const Handlers h = DefaultHandlers();
  EXPECT_TRUE(Calls(h.calibrate, &RunCalibrate));
  EXPECT_TRUE(Calls(h.validate, &RunValidateOrTrack));  // a track recipe: app/live/track_run.h
  EXPECT_TRUE(Calls(h.fit, &RunFit));
  EXPECT_TRUE(Calls(h.playback, &RunPlayback));
  EXPECT_TRUE(Calls(h.check, &RunCheck));
  EXPECT_TRUE(Calls(h.plan, &RunPlan));
  EXPECT_TRUE(Calls(h.sim, &RunSim));
  EXPECT_TRUE(Calls(h.devices, &RunDevices));
  EXPECT_TRUE(Calls(h.measure, &RunMeasureOrTrack));
  EXPECT_TRUE(Calls(h.snap, &RunSnap));
  EXPECT_TRUE(Calls(h.view, &RunView));
  EXPECT_TRUE(Calls(h.station, &RunStation));
  EXPECT_TRUE(Calls(h.station_test, &RunStationTest));
}

// Handlers that only record the arguments they were called with.
struct Recorder {
  CalibrateArgs calibrate;
  ValidateArgs validate;
  FitArgs fit;
  PlaybackArgs playback;
  CheckArgs check;
  PlanArgs plan;
  SimArgs sim;
  DevicesArgs devices;
  std::vector<std::string> called;
  // A handler that stores its arguments in *slot and notes its command.
  template <typename Args>
  std::function<void(const Args&, CommandIo)> Store(Args* slot, const char* name) {
    return [this, slot, name](const Args& args, CommandIo) {
      *slot = args;
      called.push_back(name);
    };
  }
  Handlers handlers() {
    Handlers h;
    h.calibrate = Store(&calibrate, "calibrate");
    h.validate = Store(&validate, "validate");
    h.fit = Store(&fit, "fit");
    h.playback = Store(&playback, "playback");
    h.check = Store(&check, "check");
    h.plan = Store(&plan, "plan");
    h.sim = Store(&sim, "sim");
    h.devices = Store(&devices, "devices");
    return h;
  }
};

TEST(CliTest, EachCommandParsesEveryFlagIntoItsArgs) {
  Recorder r;
  const Handlers h = r.handlers();
  ASSERT_EQ(RunWords({"validate", "v.yaml", "--model", "m.yaml", "--out", "o", "--resume", "p",
                      "--time-scale", "7.5", "--quiet"},
                     h),
            0);
  EXPECT_EQ(r.validate.recipe, "v.yaml");
  EXPECT_EQ(r.validate.model, "m.yaml");
  EXPECT_EQ(r.validate.out_dir, "o");
  EXPECT_EQ(r.validate.resume_dir, "p");
  EXPECT_EQ(r.validate.time_scale, 7.5);
  EXPECT_TRUE(r.validate.quiet);
  ASSERT_EQ(RunWords({"fit", "rec dir", "--out", "m'x.yaml", "--recover-response"}, h), 0);
  EXPECT_EQ(r.fit.recording, "rec dir");
  EXPECT_EQ(r.fit.out, "m'x.yaml");
  EXPECT_TRUE(r.fit.recover_response);
  ASSERT_EQ(RunWords({"fit", "rec"}, h), 0);
  EXPECT_FALSE(r.fit.recover_response);
  EXPECT_EQ(r.fit.out, "");
  ASSERT_EQ(RunWords({"playback", "rec", "--model", "m.yaml", "--out", "o"}, h), 0);
  EXPECT_EQ(r.playback.recording, "rec");
  EXPECT_EQ(r.playback.model, "m.yaml");
  EXPECT_EQ(r.playback.out_dir, "o");
  EXPECT_FALSE(r.playback.show);
  ASSERT_EQ(RunWords({"check", "rec"}, h), 0);
  EXPECT_EQ(r.check.recording, "rec");
  ASSERT_EQ(RunWords({"plan", "r.yaml", "--poses", "-1", "--suggest", "--from", "s.yaml", "--out",
                      "o", "--time-scale", "3", "--quiet"},
                     h),
            0);
  EXPECT_EQ(r.plan.recipe, "r.yaml");
  EXPECT_EQ(r.plan.show_poses, -1);
  EXPECT_TRUE(r.plan.suggest);
  EXPECT_EQ(r.plan.from_summary, "s.yaml");
  EXPECT_EQ(r.plan.out_dir, "o");
  EXPECT_EQ(r.plan.time_scale, 3.0);
  EXPECT_TRUE(r.plan.quiet);
  ASSERT_EQ(RunWords({"plan", "r.yaml"}, h), 0);
  EXPECT_EQ(r.plan.show_poses, 8);
  EXPECT_FALSE(r.plan.suggest);
  ASSERT_EQ(RunWords({"sim", "rigs/lab.yaml", "--time-scale", "10"}, h), 0);
  EXPECT_EQ(r.sim.rig, "rigs/lab.yaml");
  EXPECT_EQ(r.sim.time_scale, 10.0);
  ASSERT_EQ(RunWords({"sim"}, h), 0);
  EXPECT_EQ(r.sim.rig, "virtual");
  ASSERT_EQ(RunWords({"sim", "--rig", "other"}, h), 0);
  EXPECT_EQ(r.sim.rig, "other");
  EXPECT_EQ(r.called, (std::vector<std::string>{"validate", "fit", "fit", "playback", "check",
                                                "plan", "plan", "sim", "sim", "sim"}));
}

TEST(CliTest, UnknownFlagsAndBadValuesAreUsageErrorsAndRunNothing) {
  Recorder r;
  const Handlers h = r.handlers();
  const std::vector<std::vector<std::string>> bad = {
      {"calibrate", "r.yaml", "--bogus"},
      {"validate", "v.yaml", "--model", "m.yaml", "--bogus"},
      {"fit", "rec", "--model", "m.yaml"},  // fit takes no model
      {"playback", "rec", "--resume", "x"},
      {"check", "rec", "--out", "x"},
      {"check"},
      {"plan", "r.yaml", "--poses", "many"},
      {"plan", "r.yaml", "--poses", "-2"},
      {"sim", "--time-scale", "0"},
      {"sim", "a", "b"},
      {"devices", "--discover=maybe"},
      {"devices", "extra"},
      {"calibrate", "r.yaml", "--time-scale"},
  };
  for (const std::vector<std::string>& words : bad) {
    std::string joined;
    for (const std::string& w : words) joined += w + " ";
    try {
      RunWords(words, h);
      ADD_FAILURE() << joined << ": accepted";
    } catch (const UsageError& e) {
      // The message names the command and points at its help.
      EXPECT_NE(std::string(e.what()).find(words[0]), std::string::npos) << e.what();
    }
  }
  EXPECT_TRUE(r.called.empty()) << r.called.front();
}

TEST(CliTest, OfflineCommandsReportAMissingRecordingAsAnError) {
  const Handlers handlers = DefaultHandlers();
  for (const std::vector<std::string>& command :
       std::vector<std::vector<std::string>>{{"fit", "/nonexistent-recording"},
                                             {"playback", "/nonexistent-recording"},
                                             {"check", "/nonexistent-recording"}}) {
    SCOPED_TRACE(command[0]);
    try {
      RunWords(command, handlers);
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("nonexistent-recording"), std::string::npos) << e.what();
    }
  }
}

TEST(CliTest, CalibrateReportsABadRecipeBeforeAnythingStarts) {
  EXPECT_THROW(RunWords({"calibrate", "/nonexistent.yaml"}, DefaultHandlers()), RecipeError);
  EXPECT_THROW(RunWords({"validate", "/nonexistent.yaml", "--model", "m.yaml"}, DefaultHandlers()),
               RecipeError);
}

TEST(CliTest, HandlersReceiveTheirArguments) {
  Handlers handlers;
  CalibrateArgs calibrate;
  ValidateArgs validate;
  handlers.calibrate = [&](const CalibrateArgs& args, CommandIo io) {
    calibrate = args;
    io.out << "calibrated";
  };
  handlers.validate = [&](const ValidateArgs& args, CommandIo) { validate = args; };
  std::string out;
  EXPECT_EQ(
      RunWords({"calibrate", "r.yaml", "--out", "runs/x", "--resume", "runs/y"}, handlers, &out),
      0);
  EXPECT_EQ(out, "calibrated");
  EXPECT_EQ(calibrate.recipe, "r.yaml");
  EXPECT_EQ(calibrate.out_dir, "runs/x");
  EXPECT_EQ(calibrate.resume_dir, "runs/y");
  EXPECT_EQ(RunWords({"validate", "v.yaml", "--model", "m.yaml"}, handlers), 0);
  EXPECT_EQ(validate.recipe, "v.yaml");
  EXPECT_EQ(validate.model, "m.yaml");
  EXPECT_EQ(validate.out_dir, "");
  EXPECT_EQ(validate.time_scale, 0.0);
  EXPECT_EQ(RunWords({"calibrate", "r.yaml", "--time-scale", "25", "--quiet"}, handlers), 0);
  EXPECT_EQ(calibrate.time_scale, 25.0);
  EXPECT_TRUE(calibrate.quiet);
  EXPECT_THROW(RunWords({"calibrate", "r.yaml", "--time-scale", "-1"}, handlers), UsageError);
  PlaybackArgs playback;
  handlers.playback = [&](const PlaybackArgs& args, CommandIo) { playback = args; };
  EXPECT_EQ(RunWords({"playback", "rec", "--show"}, handlers), 0);
  EXPECT_TRUE(playback.show);
  EXPECT_EQ(playback.model, "");
  DevicesArgs devices;
  handlers.devices = [&](const DevicesArgs& args, CommandIo) { devices = args; };
  EXPECT_EQ(RunWords({"devices"}, handlers), 0);
  EXPECT_FALSE(devices.discover);
  EXPECT_EQ(RunWords({"devices", "--discover"}, handlers), 0);
  EXPECT_TRUE(devices.discover);
  // A command without a handler is the program's own fault, never a user's.
  EXPECT_THROW(RunWords({"plan", "r.yaml"}, handlers), CheckError);
}

TEST(CliTest, StationCommandsParseTheirArguments) {
  Handlers handlers;
  StationArgs station;
  handlers.station = [&](const StationArgs& args, CommandIo) { station = args; };
  EXPECT_EQ(RunWords({"station", "--rig", "virtual-lab", "move", "2000", "10", "-5", "--port",
                      "slide=/dev/pts/3", "--port", "head=/dev/pts/4"},
                     handlers),
            0);
  EXPECT_EQ(station.rig, "virtual-lab");
  EXPECT_EQ(station.action, "move");
  EXPECT_EQ(station.values, (std::vector<double>{2000.0, 10.0, -5.0}));
  EXPECT_EQ(station.ports, (std::vector<std::string>{"slide=/dev/pts/3", "head=/dev/pts/4"}));
  EXPECT_THROW(RunWords({"station", "jump"}, handlers), UsageError);
  StationTestArgs test;
  handlers.station_test = [&](const StationTestArgs& args, CommandIo) { test = args; };
  EXPECT_EQ(RunWords({"station-test", "/dev/ttyUSB0", "--baud", "57600"}, handlers), 0);
  EXPECT_EQ(test.port, "/dev/ttyUSB0");
  EXPECT_EQ(test.baud, 57600);
  CameraTestArgs camera;
  handlers.camera_test = [&](const CameraTestArgs& args, CommandIo) { camera = args; };
  EXPECT_EQ(RunWords({"camera-test", "192.0.2.40"}, handlers), 0);
  EXPECT_EQ(camera.camera, "192.0.2.40");
  EXPECT_EQ(RunWords({"camera-test", "--rig", "virtual-lab"}, handlers), 0);
  EXPECT_EQ(camera.camera, "");
  EXPECT_EQ(camera.rig, "virtual-lab");
}

TEST(CliTest, PlanPrintsCountsOrderAndDuration) {
  std::string out;
  EXPECT_EQ(RunWords({"plan", kRecipes + "/table3-calibration.yaml"}, DefaultHandlers(), &out), 0);
  EXPECT_NE(out.find("64 poses"), std::string::npos) << out;
  EXPECT_NE(out.find("320 in all"), std::string::npos) << out;
  EXPECT_NE(out.find("256 differences"), std::string::npos) << out;
  EXPECT_NE(out.find("Estimated duration"), std::string::npos) << out;
  EXPECT_NE(out.find("motion"), std::string::npos) << out;
  EXPECT_NE(out.find("readout"), std::string::npos) << out;
  EXPECT_NE(out.find("Physical bound"), std::string::npos) << out;
  EXPECT_NE(out.find("first 8 of 64 poses"), std::string::npos) << out;

  EXPECT_EQ(RunWords({"plan", kRecipes + "/smoke-calibration.yaml", "--poses", "-1"},
                     DefaultHandlers(), &out),
            0);
  EXPECT_NE(out.find("all 24 poses"), std::string::npos) << out;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Regression: plan accepted rig values sim refuses (crosstalk NaN or 5.0001); plan loads
// the rig exactly as sim and calibrate do, refusing at the rig file's line.
TEST(CliSafety, PlanRefusesAVirtualRigThatSimRefuses) {
  const std::string dir = ::testing::TempDir() + "cli_plan_rig_" + std::to_string(::getpid());
  std::filesystem::create_directories(dir);
  const std::string rig = ReadText(kRecipes + "/rigs/virtual-crosstalk.yaml");
  const std::string key = "crosstalk_sigma_px: 0.6";
  ASSERT_NE(rig.find(key), std::string::npos);
  std::string recipe = ReadText(kRecipes + "/smoke-calibration.yaml");
  const size_t at = recipe.find("rig: virtual\n");
  ASSERT_NE(at, std::string::npos);
  recipe.replace(at, 13, "rig: " + dir + "/bad-rig.yaml\n");
  std::ofstream(dir + "/recipe.yaml") << recipe;
  for (const char* value : {"5.0001", ".nan"}) {
    SCOPED_TRACE(value);
    std::string bad = rig;
    bad.replace(bad.find(key), key.size(), std::string("crosstalk_sigma_px: ") + value);
    std::ofstream(dir + "/bad-rig.yaml") << bad;
    try {
      RunWords({"plan", dir + "/recipe.yaml"}, DefaultHandlers());
      ADD_FAILURE() << "planned";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(dir + "/bad-rig.yaml:"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("crosstalk_sigma_px"), std::string::npos) << e.what();
    }
  }
  std::ofstream(dir + "/bad-rig.yaml") << rig;
  EXPECT_EQ(RunWords({"plan", dir + "/recipe.yaml"}, DefaultHandlers()), 0);
}

// The built binary: typed errors become exit codes and one message on stderr (no shell: an
// argument vector; stdout and stderr into one file).
int RunBinary(const std::vector<std::string>& arguments, std::string* output) {
  const std::string log = ::testing::TempDir() + "irdist_cli_test_" + std::to_string(::getpid());
  ProcessSpec spec;
  spec.argv = {std::string(IRDIST_BINARY_DIR) + "/app/irdist"};
  spec.argv.insert(spec.argv.end(), arguments.begin(), arguments.end());
  spec.stdout_path = log + ".out";
  spec.stderr_path = log + ".err";
  const ProcessResult result = RunProgram(spec);
  output->clear();
  for (const std::string& path : {spec.stdout_path, spec.stderr_path}) {
    std::ifstream in(path);
    output->append(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  std::remove(spec.stdout_path.c_str());
  std::remove(spec.stderr_path.c_str());
  return result.exited ? result.exit_code : -1;
}

TEST(CliTest, BinaryExitCodes) {
  std::string output;
  EXPECT_EQ(RunBinary({"plan", kRecipes + "/smoke-calibration.yaml"}, &output), 0) << output;
  EXPECT_NE(output.find("96 in all"), std::string::npos) << output;

  EXPECT_EQ(RunBinary({"frobnicate"}, &output), 2) << output;
  EXPECT_EQ(output.rfind("irdist: unknown command", 0), 0u) << output;

  EXPECT_EQ(RunBinary({"fit", "/nonexistent-recording"}, &output), 1) << output;
  EXPECT_NE(output.find("/nonexistent-recording"), std::string::npos) << output;
  EXPECT_EQ(output.find("not available"), std::string::npos) << output;

  EXPECT_EQ(RunBinary({"plan", "/nonexistent/recipe.yaml"}, &output), 1) << output;
  EXPECT_NE(output.find("/nonexistent/recipe.yaml: cannot open"), std::string::npos) << output;
  // One line, no stack of noise.
  EXPECT_EQ(output.find('\n'), output.size() - 1) << output;

  EXPECT_EQ(RunBinary({"--help"}, &output), 0) << output;
}


TEST(CliSafety, TimeScaleZeroIsRefusedInPlainNumbers) {
  for (const char* command : {"calibrate", "sim"}) {
    try {
      RunWords({command, kRecipes + "/smoke-calibration.yaml", "--time-scale", "0"},
               DefaultHandlers());
      FAIL() << command << " accepted --time-scale 0";
    } catch (const UsageError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("0.01..1000"), std::string::npos) << what;
      EXPECT_EQ(what.find("e+308"), std::string::npos) << what;
      EXPECT_LT(what.size(), 300u) << what;
    }
  }
}

// A command line that must be refused, and what its usage error must say.
struct BadCommandLine {
  std::vector<std::string> words;
  std::string message;
};

// Flags out of their range, and an --out that names `file`, a file.
std::vector<BadCommandLine> OutOfRangeCommandLines(const std::string& file) {
  return {
      {{"measure", "--model", "m.yaml", "--t-meas-ms", "-5"},
       "--t-meas-ms -5 is outside (0, 100000] ms"},
      {{"measure", "--model", "m.yaml", "--t-meas-ms", "30,0"}, "--t-meas-ms 0 is outside"},
      {{"measure", "--model", "m.yaml", "--t-meas-ms", "nan"}, "--t-meas-ms nan is outside"},
      {{"measure", "--model", "m.yaml", "--t-meas-ms", "1e308"}, "--t-meas-ms 1e308 is outside"},
      {{"measure", "--model", "m.yaml", "--t-ref-ms", "inf"}, "--t-ref-ms inf is outside"},
      {{"measure", "--model", "m.yaml", "--at", "nan,0,0,500"}, "--at nan is outside"},
      {{"snap", "--out", "a.png", "--at", "2000,0,0,-5"}, "--at (its BIAS_MA) -5 is outside [0, "},
      {{"view", "--at", "2000,inf,0,500"}, "--at inf is outside"},
      {{"station-test", "/dev/null", "--baud", "0"}, "--baud 0 is outside [1, 4000000] bit/s"},
      {{"station-test", "/dev/null", "--baud", "-9600"}, "--baud -9600 is outside"},
      // Regression: NaN passed --duration and --max-disk-gb (a measure that never ends);
      // --count 0 printed a 309-digit range; snap --exposure-ms nan moved the station first.
      {{"measure", "--model", "m.yaml", "--duration", "nan"},
       "--duration nan is outside (0, 86400] s"},
      {{"measure", "--model", "m.yaml", "--duration", "1e9"}, "--duration 1e9 is outside"},
      {{"measure", "--model", "m.yaml", "--max-disk-gb", "nan"},
       "--max-disk-gb nan is outside (0, 1000000] GB"},
      {{"measure", "--model", "m.yaml", "--count", "0"}, "--count 0 is outside [1, 1000000000]"},
      {{"snap", "--out", "a.png", "--exposure-ms", "nan"}, "--exposure-ms nan is outside (0, "},
      {{"view", "--exposure-ms", "-1"}, "--exposure-ms -1 is outside (0, 100000] ms"},
      {{"measure", "--model", "m.yaml", "--out", file}, "is a file, not a folder"},
      {{"measure", "--model", "m.yaml", "--out", file + "/sub"}, "is a file, not a folder"},
  };
}

// Flags that would reach an internal check (bracket.cc, station_client.cc, serial_transport.cc)
// or a raw filesystem error are usage errors naming the flag and the valid range; nothing runs.
TEST(CliTest, OutOfRangeFlagsNameTheFlagAndTheRangeAndRunNothing) {
  const std::string file = ::testing::TempDir() + "cli_test_file_" + std::to_string(::getpid());
  { std::ofstream(file) << "x"; }
  const std::vector<BadCommandLine> bad = OutOfRangeCommandLines(file);
  int called = 0;
  Handlers h;
  h.measure = [&called](const MeasureArgs&, CommandIo) { ++called; };
  h.snap = [&called](const SnapArgs&, CommandIo) { ++called; };
  h.view = [&called](const ViewArgs&, CommandIo) { ++called; };
  h.station_test = [&called](const StationTestArgs&, CommandIo) { ++called; };
  for (const BadCommandLine& b : bad) {
    SCOPED_TRACE(b.message);
    try {
      RunWords(b.words, h);
      ADD_FAILURE() << "accepted";
    } catch (const UsageError& e) {
      EXPECT_NE(std::string(e.what()).find(b.message), std::string::npos) << e.what();
      EXPECT_LT(std::string(e.what()).size(), 400u) << e.what();  // never a 309-digit range
    }
  }
  EXPECT_EQ(called, 0);
  // In range: accepted as given.
  MeasureArgs got;
  h.measure = [&got](const MeasureArgs& a, CommandIo) { got = a; };
  ASSERT_EQ(RunWords({"measure", "--model", "m.yaml", "--t-ref-ms", "8", "--t-meas-ms",
                      "30,100000", "--at", "2000,-10,0,0", "--out", ::testing::TempDir()},
                     h),
            0);
  EXPECT_EQ(got.t_meas_ms, (std::vector<double>{30.0, 100000.0}));
  EXPECT_EQ(got.at, (std::vector<double>{2000.0, -10.0, 0.0, 0.0}));
  std::remove(file.c_str());
}

}  // namespace
}  // namespace irdist
