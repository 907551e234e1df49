// The PNG files of snap and view: the checks before the camera starts (format, existing file,
// link, folder) and a 16-bit frame written whole, every bit kept.
#include "app/live/png_output.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "app/inputs/errors.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

class PngOutputTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("irdist-png-output-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

// PNG is the one format that keeps a 12- or 16-bit frame: another extension is a usage error,
// naming the flag; the extension's case does not matter.
TEST_F(PngOutputTest, OnlyAPngNameIsAccepted) {
  try {
    CheckPngOutput(Path("frame.jpg"), false, "--out");
    FAIL() << "a .jpg name was accepted";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("--out " + Path("frame.jpg")), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(CheckPngOutput(Path("frame"), false, "--out"), UsageError);
  EXPECT_NO_THROW(CheckPngOutput(Path("frame.PNG"), false, "--out"));
}

TEST_F(PngOutputTest, AnExistingFileIsReplacedOnlyWithForce) {
  std::ofstream(Path("frame.png")) << "a recorded frame";
  try {
    CheckPngOutput(Path("frame.png"), false, "--screenshot");
    FAIL() << "an existing file was accepted without --force";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(CheckPngOutput(Path("frame.png"), true, "--screenshot"));
}

// A link is never written through, even with --force, and even when it points nowhere.
TEST_F(PngOutputTest, ALinkIsRefusedEvenWithForce) {
  fs::create_symlink(Path("elsewhere.png"), Path("link.png"));
  try {
    CheckPngOutput(Path("link.png"), true, "--out");
    FAIL() << "a link was accepted";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("is a symbolic link"), std::string::npos) << e.what();
  }
}

TEST_F(PngOutputTest, AMissingFolderIsRefusedNamingIt) {
  try {
    CheckPngOutput(Path("missing/x.png"), false, "--out");
    FAIL() << "a file in a missing folder was accepted";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("the folder " + Path("missing") + " does not exist"),
              std::string::npos) << e.what();
  }
}

// A 12-bit frame in 16-bit pixels (up to 4095) reads back with every value as written.
TEST_F(PngOutputTest, WritesASixteenBitFrameThatReadsBackExactly) {
  cv::Mat frame(48, 64, CV_16UC1);
  for (int y = 0; y < frame.rows; ++y) {
    for (int x = 0; x < frame.cols; ++x) {
      frame.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>((y * frame.cols + x) * 4095 /
                                                                 (frame.total() - 1));
    }
  }
  WritePng(Path("frame.png"), frame, "frame");
  const cv::Mat read = cv::imread(Path("frame.png"), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(read.type(), CV_16UC1);
  ASSERT_EQ(read.size(), frame.size());
  EXPECT_EQ(cv::norm(read, frame, cv::NORM_INF), 0.0);
  EXPECT_EQ(read.at<std::uint16_t>(47, 63), 4095);
}

TEST_F(PngOutputTest, AFrameThatCannotBeWrittenIsAFolderErrorNamingWhat) {
  const cv::Mat frame(8, 8, CV_16UC1, cv::Scalar(100));
  try {
    WritePng(Path("missing/frame.png"), frame, "preview");
    FAIL() << "a frame was written into a missing folder";
  } catch (const RunFolderError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot write the preview"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace irdist
