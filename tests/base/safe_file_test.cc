// Files created new and replaced whole never write through a link someone planted; a private
// folder is the user's own, 0700, and not a link.
#include "base/safe_file.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace irdist {
namespace {

namespace fs = std::filesystem;

class SafeFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("irdist-safe-file-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static std::string Read(const fs::path& path) {
    std::ifstream in(path);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
  }
  fs::path dir_;
};

TEST_F(SafeFileTest, CreateNewFileRefusesAnExistingNameAndALink) {
  std::string why;
  const fs::path victim = dir_ / "victim";
  std::ofstream(victim) << "secret";
  fs::create_symlink(victim, dir_ / "planted");
  EXPECT_LT(CreateNewFile((dir_ / "planted").string(), 0600, &why), 0);
  EXPECT_NE(why.find("exists"), std::string::npos) << why;
  EXPECT_LT(CreateNewFile(victim.string(), 0600, &why), 0);
  EXPECT_EQ(Read(victim), "secret");
  const int fd = CreateNewFile((dir_ / "new").string(), 0600, &why);
  ASSERT_GE(fd, 0) << why;
  ::close(fd);
  struct stat st {};
  ASSERT_EQ(::stat((dir_ / "new").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
}

// A stale temporary name that is a link to another file: unlinked, never written through.
TEST_F(SafeFileTest, AtomicWriteRemovesAPlantedTemporaryLinkAndNeverFollowsIt) {
  const fs::path victim = dir_ / "victim";
  std::ofstream(victim) << "secret";
  const fs::path target = dir_ / "model.yaml";
  fs::create_symlink(victim, dir_ / "model.yaml.tmp");
  std::string why;
  ASSERT_TRUE(WriteFileAtomically(target.string(), "new: 1\n", 0644, &why)) << why;
  EXPECT_EQ(Read(victim), "secret");
  EXPECT_EQ(Read(target), "new: 1\n");
  EXPECT_FALSE(fs::is_symlink(target));
  EXPECT_FALSE(fs::exists(fs::symlink_status(dir_ / "model.yaml.tmp")));
}

TEST_F(SafeFileTest, AtomicWriteReplacesAFileWhole) {
  const std::string path = (dir_ / "features.csv").string();
  std::string why;
  ASSERT_TRUE(WriteFileAtomically(path, "first\n", 0644, &why)) << why;
  ASSERT_TRUE(WriteFileAtomically(path, "second\n", 0644, &why)) << why;
  EXPECT_EQ(Read(path), "second\n");
  EXPECT_FALSE(fs::exists(path + ".tmp"));
}

// A write that fails half way (a full disk, simulated by a file size limit) leaves the old file
// as it was, no temporary file, and says the system's reason.
TEST_F(SafeFileTest, AtomicWriteCutByAFullDiskLeavesTheOldFileAndSaysWhy) {
  const std::string path = (dir_ / "index.html").string();
  std::string why;
  ASSERT_TRUE(WriteFileAtomically(path, "old", 0644, &why)) << why;
  rlimit saved{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &saved), 0);
  auto* old_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit limit = saved;
  limit.rlim_cur = 1000;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &limit), 0);
  const bool ok = WriteFileAtomically(path, std::string(5000, 'x'), 0644, &why);
  ::setrlimit(RLIMIT_FSIZE, &saved);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_FALSE(ok);
  EXPECT_NE(why.find("cannot be written: File too large"), std::string::npos) << why;
  EXPECT_EQ(Read(path), "old");
  EXPECT_FALSE(fs::exists(path + ".tmp"));
}

TEST_F(SafeFileTest, AtomicWriteRefusesATargetThatIsALink) {
  const fs::path victim = dir_ / "victim";
  std::ofstream(victim) << "secret";
  fs::create_symlink(victim, dir_ / "recording.yaml");
  std::string why;
  EXPECT_FALSE(WriteFileAtomically((dir_ / "recording.yaml").string(), "x", 0644, &why));
  EXPECT_NE(why.find("symbolic link"), std::string::npos) << why;
  EXPECT_EQ(Read(victim), "secret");
  EXPECT_TRUE(fs::is_symlink(dir_ / "recording.yaml"));
}

TEST_F(SafeFileTest, WriteNewFileSyncedReplacesAStaleFileWithoutOpeningIt) {
  const fs::path path = dir_ / "000001.png.tmp";
  const fs::path victim = dir_ / "victim";
  std::ofstream(victim) << "secret";
  fs::create_symlink(victim, path);
  std::string why;
  ASSERT_TRUE(WriteNewFileSynced(path.string(), "png", 0644, &why)) << why;
  EXPECT_EQ(Read(path), "png");
  EXPECT_EQ(Read(victim), "secret");
}

TEST_F(SafeFileTest, PrivateDirIsCreated0700AndChecked) {
  std::string why;
  const fs::path mine = dir_ / "irdist";
  ASSERT_TRUE(EnsurePrivateDir(mine.string(), &why)) << why;
  struct stat st {};
  ASSERT_EQ(::lstat(mine.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0700u);
  EXPECT_TRUE(EnsurePrivateDir(mine.string(), &why)) << why;  // again: the same folder

  ASSERT_EQ(::chmod(mine.c_str(), 0755), 0);
  EXPECT_FALSE(EnsurePrivateDir(mine.string(), &why));
  EXPECT_NE(why.find("755"), std::string::npos) << why;

  const fs::path link = dir_ / "linked";
  fs::create_directories(dir_ / "elsewhere");
  ::chmod((dir_ / "elsewhere").c_str(), 0700);
  fs::create_directory_symlink(dir_ / "elsewhere", link);
  EXPECT_FALSE(EnsurePrivateDir(link.string(), &why));
  EXPECT_NE(why.find("symbolic link"), std::string::npos) << why;

  std::ofstream(dir_ / "file") << "x";
  EXPECT_FALSE(EnsurePrivateDir((dir_ / "file").string(), &why));
  EXPECT_NE(why.find("not a folder"), std::string::npos) << why;
}

// A folder of another user: only root can make one here; skipped otherwise.
TEST_F(SafeFileTest, PrivateDirOfAnotherUserIsRefused) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to give a folder to another user";
  const fs::path theirs = dir_ / "theirs";
  fs::create_directories(theirs);
  ASSERT_EQ(::chmod(theirs.c_str(), 0700), 0);
  ASSERT_EQ(::chown(theirs.c_str(), 65534, 65534), 0);
  std::string why;
  EXPECT_FALSE(EnsurePrivateDir(theirs.string(), &why));
  EXPECT_NE(why.find("not to you"), std::string::npos) << why;
}

}  // namespace
}  // namespace irdist
