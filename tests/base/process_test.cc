#include "base/process.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace irdist {
namespace {

namespace fs = std::filesystem;

std::string Slurp(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

class ProcessTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("irdist_process_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  fs::path root_;
};

TEST_F(ProcessTest, ArgumentsReachTheProgramVerbatimAndNoShellRuns) {
  const std::string hostile = "x'; touch INJECTED; echo '$HOME `id` \"q\" a b";
  const fs::path dir = root_ / "lab's run; $HOME";
  fs::create_directories(dir);
  ProcessSpec spec;
  spec.argv = {"printf", "%s|%s", hostile, "two words"};
  spec.working_dir = dir.string();
  spec.stdout_path = (dir / "out's.txt").string();
  const ProcessResult result = RunProgram(spec);
  EXPECT_TRUE(result.Succeeded());
  EXPECT_EQ(Slurp(dir / "out's.txt"), hostile + "|two words");
  EXPECT_FALSE(fs::exists(dir / "INJECTED"));
  EXPECT_FALSE(fs::exists("INJECTED"));
}

TEST_F(ProcessTest, RunsInTheWorkingFolder) {
  const fs::path dir = root_ / "a $b ; 'c'";
  fs::create_directories(dir);
  ProcessSpec spec;
  spec.argv = {"pwd"};
  spec.working_dir = dir.string();
  spec.stdout_path = (root_ / "pwd.txt").string();
  ASSERT_TRUE(RunProgram(spec).Succeeded());
  EXPECT_EQ(Slurp(root_ / "pwd.txt"), fs::canonical(dir).string() + "\n");
}

TEST_F(ProcessTest, ExitStatusAndStderrAreReported) {
  ProcessSpec spec;
  spec.argv = {"ls", (root_ / "no such file").string()};
  spec.stderr_path = (root_ / "err.log").string();
  const ProcessResult result = RunProgram(spec);
  EXPECT_TRUE(result.exited);
  EXPECT_NE(result.exit_code, 0);
  EXPECT_FALSE(result.Succeeded());
  EXPECT_NE(Slurp(root_ / "err.log").find("no such file"), std::string::npos);
}

TEST_F(ProcessTest, MissingProgramOrFolderIsANamedError) {
  ProcessSpec spec;
  spec.argv = {"irdist-no-such-program"};
  EXPECT_THROW(RunProgram(spec), ProcessError);
  EXPECT_EQ(FindProgram("irdist-no-such-program"), "");
  EXPECT_NE(FindProgram("ls"), "");
  spec.argv = {"true"};
  spec.working_dir = (root_ / "missing").string();
  EXPECT_THROW(RunProgram(spec), ProcessError);
}

}  // namespace
}  // namespace irdist
