// The sim's state file lives in a private folder, is created new (never through a planted
// link) and is read back only when it is the user's, its process a live `irdist sim` of the
// user's and its ports the user's ptys; anything else is skipped with a warning, never fatal.
#include "app/inputs/state_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/app/fake_sim.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

class StateFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("irdist-state-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "runtime");
    ASSERT_EQ(setenv("XDG_RUNTIME_DIR", (dir_ / "runtime").c_str(), 1), 0);
  }
  void TearDown() override {
    unsetenv("XDG_RUNTIME_DIR");
    fs::remove_all(dir_);
  }
  std::string Private() const { return (dir_ / "runtime" / "irdist").string(); }
  SimState StateOf(const testing::FakeSim& sim) const {
    SimState state;
    state.pid = sim.pid();
    state.rig = (dir_ / "rig.yaml").string();
    state.camera_id = "Aravis-Fake-LIVE";
    state.camera_address = "127.0.0.1";
    state.serial = "LIVE";
    state.station_port = sim.pty();
    state.time_scale = 5;
    state.ports = {{"slide", sim.pty()}};
    return state;
  }
  fs::path dir_;
};

TEST_F(StateFileTest, RuntimeFolderIsAPrivateSubfolderOfXdgRuntimeDirOrTheTempFolder) {
  EXPECT_EQ(RuntimeStateDir(), Private());
  struct stat st {};
  ASSERT_EQ(::lstat(Private().c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0700u);
  unsetenv("XDG_RUNTIME_DIR");
  ASSERT_EQ(setenv("TMPDIR", dir_.c_str(), 1), 0);
  EXPECT_EQ(RuntimeStateDir(), (dir_ / ("irdist-" + std::to_string(::geteuid()))).string());
  unsetenv("TMPDIR");
}

// Another user could pre-create the folder in /tmp, open or as a link: refused, naming it.
TEST_F(StateFileTest, ARuntimeFolderThatIsALinkOrOpenIsRefused) {
  fs::create_directories(dir_ / "elsewhere");
  fs::create_directory_symlink(dir_ / "elsewhere", Private());
  EXPECT_THROW(RuntimeStateDir(), StateFileError);
  fs::remove(Private());
  fs::create_directories(Private());
  ::chmod(Private().c_str(), 0777);
  try {
    RuntimeStateDir();
    ADD_FAILURE() << "an open runtime folder was accepted";
  } catch (const StateFileError& error) {
    EXPECT_NE(std::string(error.what()).find(Private()), std::string::npos) << error.what();
  }
}

// The emitter quotes what needs quoting: a rig path with '#', ':' and quotes reads back intact.
TEST_F(StateFileTest, StateYamlReadsBackWhateverThePathsHold) {
  SimState state;
  state.pid = 42;
  state.rig = "/home/lab #2/rigs/a: \"b\".yaml";
  state.station_port = "/dev/pts/3";
  state.ports = {{"slide", "/dev/pts/4"}};
  const YAML::Node node = YAML::Load(SimStateYaml(state));
  EXPECT_EQ(node["rig"].as<std::string>(), state.rig);
  EXPECT_EQ(node["pid"].as<long>(), 42);
  EXPECT_EQ(node["port.slide"].as<std::string>(), "/dev/pts/4");
  EXPECT_FALSE(node["trajectory_csv"]);  // not logged: no key
}

// A sim that logs the station's trajectory names its file, so a test or a user can find it.
TEST_F(StateFileTest, StateYamlNamesTheTrajectoryFileWhenLogged) {
  SimState state;
  state.pid = 7;
  state.trajectory_csv = "/run/user/1000/irdist/irdist-sim-7-trajectory.csv";
  const YAML::Node node = YAML::Load(SimStateYaml(state));
  EXPECT_EQ(node["trajectory_csv"].as<std::string>(), state.trajectory_csv);
}

// The attack: a link planted at the state file's name (or its temporary name) to a file
// of the victim's. Writing replaces the link, never the file behind it.
TEST_F(StateFileTest, WritingNeverFollowsAPlantedLink) {
  testing::FakeSim sim(dir_ / "sim");
  const fs::path victim = dir_ / "victim";
  std::ofstream(victim) << "root only";
  RuntimeStateDir();
  const std::string name = "irdist-sim-" + std::to_string(sim.pid()) + ".yaml";
  fs::create_symlink(victim, fs::path(Private()) / name);
  fs::create_symlink(victim, fs::path(Private()) / (name + ".tmp"));
  EXPECT_THROW(WriteSimState(StateOf(sim)), StateFileError);  // the name itself is a link
  fs::remove(fs::path(Private()) / name);
  const std::string path = WriteSimState(StateOf(sim));
  std::ifstream in(victim);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "root only");
  struct stat st {};
  ASSERT_EQ(::lstat(path.c_str(), &st), 0);
  EXPECT_TRUE(S_ISREG(st.st_mode));
  EXPECT_EQ(st.st_mode & 0777, 0600u);
}

TEST_F(StateFileTest, ALiveSimOfTheUserIsRead) {
  testing::FakeSim sim(dir_ / "sim");
  ASSERT_FALSE(sim.pty().empty());
  WriteSimState(StateOf(sim));
  std::ostringstream warn;
  const std::vector<RunningSim> sims = LiveSims(warn);
  ASSERT_EQ(sims.size(), 1u) << warn.str();
  EXPECT_EQ(sims[0].pid, sim.pid());
  EXPECT_EQ(sims[0].values.at("serial"), "LIVE");
  EXPECT_EQ(sims[0].values.at("port.slide"), sim.pty());
  EXPECT_EQ(warn.str(), "");
}

// Planted files: pid 1 (alive, not an irdist sim), this test's own process (not a sim), a port
// that is not a pty, a file that is not YAML, a link. Each skipped with one warning; a dead
// process's stale file silently.
TEST_F(StateFileTest, EveryOtherStateFileIsSkippedWithOneWarning) {
  testing::FakeSim sim(dir_ / "sim");
  const fs::path dir = RuntimeStateDir();
  const auto plant = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / ("irdist-sim-" + name + ".yaml")) << text;
  };
  plant("1", "pid: 1\nstation_port: \"" + sim.pty() + "\"\n");
  plant("self", "pid: " + std::to_string(::getpid()) + "\n");
  plant("port", "pid: " + std::to_string(sim.pid()) + "\nstation_port: \"/etc/passwd\"\n");
  plant("dotdot", "pid: " + std::to_string(sim.pid()) + "\nport.slide: \"/dev/pts/../tty\"\n");
  plant("garbage", "pid: [1, 2\n");
  plant("999999999", "pid: 999999999\n");
  fs::create_symlink(dir_ / "victim", dir / "irdist-sim-link.yaml");
  std::ostringstream warn;
  EXPECT_TRUE(LiveSims(warn).empty()) << warn.str();
  const std::string text = warn.str();
  for (const char* name : {"-1.yaml", "-self.yaml", "-port.yaml", "-dotdot.yaml", "-garbage.yaml",
                           "-link.yaml"}) {
    EXPECT_NE(text.find(name), std::string::npos) << name << "\n" << text;
  }
  EXPECT_EQ(text.find("999999999"), std::string::npos) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 6) << text;
}

TEST_F(StateFileTest, AFileOfAnotherUserIsSkipped) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to give a file to another user";
  testing::FakeSim sim(dir_ / "sim");
  const std::string path = WriteSimState(StateOf(sim));
  ASSERT_EQ(::chown(path.c_str(), 65534, 65534), 0);
  std::ostringstream warn;
  EXPECT_TRUE(LiveSims(warn).empty());
  EXPECT_NE(warn.str().find("not to you"), std::string::npos) << warn.str();
}

TEST_F(StateFileTest, PtysAreCheckedForKindAndOwner) {
  testing::FakeSim sim(dir_ / "sim");
  EXPECT_EQ(NotOwnPty(sim.pty()), "");
  EXPECT_NE(NotOwnPty("/dev/ttyS0"), "");
  EXPECT_NE(NotOwnPty("/dev/pts/999999"), "");
  EXPECT_NE(NotOwnPty("/dev/pts/ptmx"), "");
  EXPECT_TRUE(IsOwnIrdistSim(sim.pid()));
  EXPECT_FALSE(IsOwnIrdistSim(::getpid()));
  EXPECT_FALSE(IsOwnIrdistSim(1));
}

}  // namespace
}  // namespace irdist
