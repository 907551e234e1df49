#include "base/regular_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace irdist {
namespace {

namespace fs = std::filesystem;

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

TEST_F(RegularFileTest, ReadsARegularFileWholeAndRefusesOneOverTheLimit) {
  const std::string path = (dir_ / "recipe.yaml").string();
  std::ofstream(path) << "name: a\n";
  std::string text, why;
  ASSERT_TRUE(ReadRegularFile(path, kMaxInputTextBytes, &text, &why)) << why;
  EXPECT_EQ(text, "name: a\n");
  EXPECT_FALSE(ReadRegularFile(path, 3, &text, &why));
  EXPECT_NE(why.find("over the limit of 3"), std::string::npos) << why;
}

TEST_F(RegularFileTest, ASymbolicLinkIsRefused) {
  const std::string path = (dir_ / "rig.yaml").string();
  std::ofstream(dir_ / "elsewhere.yaml") << "x: 1\n";
  fs::create_symlink(dir_ / "elsewhere.yaml", path);
  std::string text, why;
  EXPECT_FALSE(ReadRegularFile(path, kMaxInputTextBytes, &text, &why));
  EXPECT_NE(why.find("symbolic link"), std::string::npos) << why;
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
