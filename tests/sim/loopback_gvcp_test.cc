// tests/loopback_gvcp.h, the lock every GigE test takes in the shared /tmp: a symbolic link or a
// FIFO planted under its name is refused, never followed.
#include "tests/loopback_gvcp.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <string>

namespace irdist::testing {
namespace {

class LoopbackGvcpLockTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char dir_template[] = "/tmp/irdist_gvcp_lock_XXXXXX";
    ASSERT_NE(mkdtemp(dir_template), nullptr);
    dir_ = dir_template;
  }
  void TearDown() override {
    for (const char* name : {"/lock", "/target", "/fifo"}) unlink((dir_ + name).c_str());
    rmdir(dir_.c_str());
  }
  std::string dir_;
};

TEST_F(LoopbackGvcpLockTest, APlantedLinkIsNotFollowed) {
  const std::string lock = dir_ + "/lock", target = dir_ + "/target";
  ASSERT_EQ(symlink(target.c_str(), lock.c_str()), 0);
  try {
    LoopbackGvcpLock held(lock);
    FAIL() << "the lock followed a symbolic link";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(lock), std::string::npos) << e.what();
  }
  struct stat st {};
  EXPECT_NE(lstat(target.c_str(), &st), 0) << "the link's target was created";
}

TEST_F(LoopbackGvcpLockTest, APlantedFifoIsRefused) {
  const std::string lock = dir_ + "/lock";
  ASSERT_EQ(mkfifo(lock.c_str(), 0600), 0);
  EXPECT_THROW(LoopbackGvcpLock held(lock), std::runtime_error);
}

TEST_F(LoopbackGvcpLockTest, ARegularFileIsLocked) {
  const std::string lock = dir_ + "/lock";
  LoopbackGvcpLock held(lock);
  struct stat st {};
  ASSERT_EQ(lstat(lock.c_str(), &st), 0);
  EXPECT_TRUE(S_ISREG(st.st_mode));
}

}  // namespace
}  // namespace irdist::testing
