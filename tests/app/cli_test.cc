#include "app/cli.h"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

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

TEST(CliTest, EverySubcommandIsInTheTable) {
  EXPECT_EQ(SubcommandNames(), (std::vector<std::string>{"calibrate", "validate", "fit", "playback",
                                                         "check", "plan", "sim", "devices",
                                                         "station", "station-test"}));
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

TEST(CliTest, HelpListsTheCommands) {
  std::string out;
  EXPECT_EQ(RunWords({"--help"}, DefaultHandlers(), &out), 0);
  for (const std::string& name : SubcommandNames()) {
    EXPECT_NE(out.find(name), std::string::npos) << name;
  }
}

TEST(CliTest, EveryCommandHasAHandler) {
  const Handlers h = DefaultHandlers();
  EXPECT_TRUE(h.calibrate && h.validate && h.fit && h.playback && h.check && h.plan && h.sim &&
              h.devices);
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
    } catch (const NotAvailableError&) {
      ADD_FAILURE() << "the command is integrated";
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
  // An empty handler is "not available".
  EXPECT_THROW(RunWords({"plan", "r.yaml"}, handlers), NotAvailableError);
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

// The built binary: typed errors become exit codes and one message on stderr.
int RunBinary(const std::string& arguments, std::string* output) {
  const std::string command = std::string(IRDIST_BINARY_DIR) + "/app/irdist " + arguments + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return -1;
  std::array<char, 4096> buffer{};
  output->clear();
  size_t n = 0;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) output->append(buffer.data(), n);
  const int status = pclose(pipe);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(CliTest, BinaryExitCodes) {
  std::string output;
  EXPECT_EQ(RunBinary("plan " + kRecipes + "/smoke-calibration.yaml", &output), 0) << output;
  EXPECT_NE(output.find("96 in all"), std::string::npos) << output;

  EXPECT_EQ(RunBinary("frobnicate", &output), 2) << output;
  EXPECT_EQ(output.rfind("irdist: unknown command", 0), 0u) << output;

  EXPECT_EQ(RunBinary("fit /nonexistent-recording", &output), 1) << output;
  EXPECT_NE(output.find("/nonexistent-recording"), std::string::npos) << output;
  EXPECT_EQ(output.find("not available"), std::string::npos) << output;

  EXPECT_EQ(RunBinary("plan /nonexistent/recipe.yaml", &output), 1) << output;
  EXPECT_NE(output.find("/nonexistent/recipe.yaml: cannot open"), std::string::npos) << output;
  // One line, no stack of noise.
  EXPECT_EQ(output.find('\n'), output.size() - 1) << output;

  EXPECT_EQ(RunBinary("--help", &output), 0) << output;
}

}  // namespace
}  // namespace irdist
