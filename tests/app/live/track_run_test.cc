// `irdist validate TRACK_RECIPE`: which recipes take the track run, and its refusals, each before
// the station moves or a run folder is written (a track run is one continuous profile: never
// resumed, never into another run's folder, on the virtual rig only against a running sim that
// logs the truth). The whole run against a running sim is tested in
// tests/integration/track_recipe_test.cc.
#include "app/live/track_run.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "app/inputs/errors.h"
#include "app/inputs/state_file.h"
#include "estimator/model_file.h"
#include "tests/app/fake_sim.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

// A track recipe on `rig`: the slide 1500 -> 3000 mm at 0.3 m/s, tracked at `exposure_ms`.
std::string TrackRecipeText(const std::string& rig, double exposure_ms) {
  std::ostringstream text;
  text << "kind: track\nname: track-test\nrig: \"" << rig << "\"\ntrack:\n  bias_ma: 490\n"
       << "  exposure_ms: " << exposure_ms << "\n  settle_ms: 100\n  after_ms: 100\n"
       << "  segments:\n    - {slide_mm: [1500, 3000], speed_mm_s: 300}\n";
  return text.str();
}

class TrackRunTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("irdist-track-run-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "runtime");
    // The sims this test sees are its own (another user's session runs sims of its own).
    ASSERT_EQ(setenv("XDG_RUNTIME_DIR", (dir_ / "runtime").c_str(), 1), 0);
    const fs::path rigs = fs::path(IRDIST_SOURCE_DIR) / "recipes/rigs";
    fs::copy_file(rigs / "virtual.yaml", dir_ / "virtual.yaml");
    fs::copy_file(rigs / "example-hardware.yaml", dir_ / "hardware.yaml");
    SaveModel(Model(), (dir_ / "model.yaml").string());
  }
  void TearDown() override {
    unsetenv("XDG_RUNTIME_DIR");
    fs::remove_all(dir_);
  }

  // A model calibrated over 1500-3000 mm with an 8 ms reference and 30-36 ms measurement
  // exposures.
  static CalibrationModel Model() {
    CalibrationModel model;
    for (ModelKind kind : {ModelKind::kFreeE, ModelKind::kFreeSigma}) {  // what every model has
      FittedModel m;
      m.kind = kind;
      m.coefficients.assign(GetModelSpec(kind).num_coefficients(), 0.0);
      m.coefficients[0] = 1.0;
      model.models.push_back(m);
    }
    model.geometric.alpha_px2 = 16.0;
    model.geometric.beta_px2 = 0.5;
    model.provenance.t_ref_ms = 8.0;
    model.provenance.t_meas_ms = {30.0, 36.0};
    CalibratedRanges& r = model.ranges;
    r.d_min_mm = 1500.0;
    r.d_max_mm = 3000.0;
    r.theta_max_deg = 35.0;
    r.t_ref_min_ms = r.t_ref_max_ms = 8.0;
    r.t_min_ms = 30.0;
    r.t_max_ms = 36.0;
    r.bias_min_ma = 475.0;
    r.bias_max_ma = 500.0;
    return model;
  }

  ValidateArgs Args(const std::string& rig, double exposure_ms = 8.0) {
    std::ofstream(dir_ / "track.yaml") << TrackRecipeText((dir_ / rig).string(), exposure_ms);
    ValidateArgs args;
    args.recipe = (dir_ / "track.yaml").string();
    args.model = (dir_ / "model.yaml").string();
    args.out_dir = (dir_ / "out").string();
    return args;
  }

  // What RunValidateOrTrack refuses `args` with ("" when it did not throw UsageError).
  std::string UsageMessage(const ValidateArgs& args) {
    std::ostringstream out;
    try {
      RunValidateOrTrack(args, {out, err_});
    } catch (const UsageError& e) {
      return e.what();
    }
    return "";
  }

  fs::path dir_;
  std::ostringstream err_;
};

// A track run is one continuous profile with one trajectory as its truth: --resume is refused,
// saying to run it again into a new folder.
TEST_F(TrackRunTest, ATrackRecipeIsNeverResumed) {
  ValidateArgs args = Args("virtual.yaml");
  args.resume_dir = (dir_ / "out").string();
  const std::string message = UsageMessage(args);
  EXPECT_NE(message.find("not resumable"), std::string::npos) << message;
  EXPECT_NE(message.find("--out NEW_DIR"), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// A recipe without `kind: track` is the validation sweep's: its --resume looks for the run to
// resume, where a track recipe's is refused.
TEST_F(TrackRunTest, ASweepRecipeIsNotTakenForATrackRun) {
  std::ofstream(dir_ / "sweep.yaml")
      << "name: sweep\nrig: \"" << (dir_ / "virtual.yaml").string() << "\"\naxes:\n"
      << "  slide_mm: [1500, 3000]\n  theta_deg: [0]\n  bias_ma: [490]\n"
      << "bracket:\n  t_ref_ms: 8\n  t_meas_ms: [30]\n";
  ValidateArgs args;
  args.recipe = (dir_ / "sweep.yaml").string();
  args.model = (dir_ / "model.yaml").string();
  args.resume_dir = (dir_ / "no-such-run").string();
  std::ostringstream out;
  try {
    RunValidateOrTrack(args, {out, err_});
    ADD_FAILURE() << "a resume of a folder that does not exist was accepted";
  } catch (const RunFolderError& e) {  // the sweep's resume, which looks for the folder
    EXPECT_NE(std::string(e.what()).find(args.resume_dir), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find("not resumable"), std::string::npos) << e.what();
  }
}

// On the virtual rig the truth of every frame is the running sim's trajectory: without a sim of
// the recipe's rig the run is refused with the command that starts one, and nothing is written.
TEST_F(TrackRunTest, AVirtualRigWithoutARunningSimIsRefusedWithTheCommandThatStartsIt) {
  const std::string message = UsageMessage(Args("virtual.yaml"));
  EXPECT_NE(message.find("irdist sim " + (dir_ / "virtual.yaml").string()), std::string::npos)
      << message;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// A running sim that logs no trajectory (an older irdist) gives no truth: refused, naming its
// process, before the station moves or a folder is made.
TEST_F(TrackRunTest, ARunningSimWithoutATrajectoryIsRefused) {
  testing::FakeSim sim(dir_ / "sim");
  ASSERT_FALSE(sim.pty().empty());
  SimState state;
  state.pid = sim.pid();
  state.rig = (dir_ / "virtual.yaml").string();
  state.camera_id = "Aravis-Fake-TRACK";
  state.camera_address = "127.0.0.1";
  state.serial = "TRACK";
  state.station_port = sim.pty();
  WriteSimState(state);
  const std::string message = UsageMessage(Args("virtual.yaml"));
  EXPECT_NE(message.find("logs no trajectory"), std::string::npos) << message << err_.str();
  EXPECT_NE(message.find("pid " + std::to_string(sim.pid())), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// An exposure outside the model's calibration (20 ms: neither the 8 ms reference nor within
// 30-36 ms) is refused before anything else is looked for.
TEST_F(TrackRunTest, AnExposureOutsideTheCalibrationIsRefusedFirst) {
  const std::string message = UsageMessage(Args("virtual.yaml", 20.0));
  EXPECT_NE(message.find("20"), std::string::npos) << message;
  EXPECT_EQ(message.find("irdist sim"), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// A track run writes a new folder: an existing one with files in it is refused and left as it
// was (on hardware, where no sim is needed, before any port is opened).
TEST_F(TrackRunTest, AnExistingRunFolderIsRefusedAndLeftAsItWas) {
  fs::create_directories(dir_ / "out");
  std::ofstream(dir_ / "out" / "track.csv") << "an earlier run's rows\n";
  std::ostringstream out;
  try {
    RunValidateOrTrack(Args("hardware.yaml"), {out, err_});
    ADD_FAILURE() << "an existing run folder was accepted";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("--out NEW_DIR"), std::string::npos) << e.what();
  }
  std::ifstream kept(dir_ / "out" / "track.csv");
  std::string line;
  std::getline(kept, line);
  EXPECT_EQ(line, "an earlier run's rows");
  EXPECT_FALSE(fs::exists(dir_ / "out" / "recipe.yaml"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "station.log"));
}

}  // namespace
}  // namespace irdist
