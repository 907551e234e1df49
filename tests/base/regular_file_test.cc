#include "base/regular_file.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace irdist {
namespace {

namespace fs = std::filesystem;

std::string Slurp(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

class RegularFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("irdist_regular_file_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(RegularFileTest, WritesWholeFilesAndReadsThemBack) {
  const std::string path = (dir_ / "a.txt").string();
  std::string why;
  ASSERT_TRUE(WriteRegularFile(path, "first\n", &why)) << why;
  ASSERT_TRUE(WriteRegularFile(path, "second\n", &why)) << why;  // replaces
  std::string back;
  ASSERT_TRUE(ReadRegularFile(path, kMaxInputTextBytes, &back, &why)) << why;
  EXPECT_EQ(back, "second\n");
  EXPECT_FALSE(fs::exists(path + ".tmp"));
}

// A stale temporary file that is a link to another file is removed, never written through.
TEST_F(RegularFileTest, AStaleTemporaryLinkIsNotFollowed) {
  const fs::path victim = dir_ / "victim.txt";
  std::ofstream(victim) << "keep me";
  const std::string path = (dir_ / "out.txt").string();
  fs::create_symlink(victim, path + ".tmp");
  std::string why;
  ASSERT_TRUE(WriteRegularFile(path, "result", &why)) << why;
  EXPECT_EQ(Slurp(victim), "keep me");
  EXPECT_EQ(Slurp(path), "result");
  EXPECT_FALSE(fs::is_symlink(path));
}

// A write that fails half way (a full disk, simulated by a file size limit) leaves the old file
// as it was and says the system's reason.
TEST_F(RegularFileTest, AFailedWriteLeavesTheOldFileAndSaysWhy) {
  const std::string path = (dir_ / "b.txt").string();
  std::string why;
  ASSERT_TRUE(WriteRegularFile(path, "old", &why)) << why;
  rlimit saved{};
  ::getrlimit(RLIMIT_FSIZE, &saved);
  auto* old_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit limit = saved;
  limit.rlim_cur = 1000;
  ::setrlimit(RLIMIT_FSIZE, &limit);
  const bool ok = WriteRegularFile(path, std::string(5000, 'x'), &why);
  ::setrlimit(RLIMIT_FSIZE, &saved);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_FALSE(ok);
  EXPECT_NE(why.find("cannot be written: File too large"), std::string::npos) << why;
  EXPECT_EQ(Slurp(path), "old");
  EXPECT_FALSE(fs::exists(path + ".tmp"));
}

TEST_F(RegularFileTest, AFifoIsRefusedWithoutBlocking) {
  const std::string path = (dir_ / "fifo").string();
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  std::string text, why;
  EXPECT_FALSE(ReadRegularFile(path, kMaxInputTextBytes, &text, &why));
  EXPECT_NE(why.find("not a regular file"), std::string::npos) << why;
}

}  // namespace
}  // namespace irdist
