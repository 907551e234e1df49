#include <sys/stat.h>
#include <unistd.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "acquisition/content_hash.h"
#include "acquisition/recording_files.h"
#include "acquisition/recording_reader.h"

// A frame's PNG as every reader decodes it (acquisition/recording_png.cc): a 16-bit gray PNG
// written by OpenCV reads back bit-exactly; anything else (another kind of file, another depth or
// colour type, a header claiming an absurd size, damaged data, a swapped file) is refused with
// the reason. The PNG header's layout is the PNG specification's: the 8-byte signature, then the
// IHDR chunk (length, "IHDR", width and height big-endian at bytes 16 and 20, bit depth at 24,
// colour type at 25, 0 = gray).

namespace irdist {
namespace {

namespace fs = std::filesystem;

std::vector<unsigned char> Encode(const cv::Mat& image) {
  std::vector<unsigned char> bytes;
  EXPECT_TRUE(cv::imencode(".png", image, bytes));
  return bytes;
}

// A 16-bit frame using every bit: 0, 65535, and a ramp with odd steps.
cv::Mat TestFrame(int rows, int cols) {
  cv::Mat frame(rows, cols, CV_16UC1);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      frame.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>((r * 7919 + c * 104729) & 0xffff);
    }
  }
  frame.at<std::uint16_t>(0, 0) = 0;
  frame.at<std::uint16_t>(rows - 1, cols - 1) = 65535;
  return frame;
}

bool SameFrame(const cv::Mat& a, const cv::Mat& b) {
  return a.type() == b.type() && a.size() == b.size() && cv::countNonZero(a != b) == 0;
}

class RecordingPngTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("irdist-recording-png-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "frames");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes `bytes` as frames/<name> and returns its row.
  FrameRecord WriteFrame(const std::string& name, const std::vector<unsigned char>& bytes) {
    std::ofstream out(dir_ / "frames" / name, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    FrameRecord row;
    row.index = 0;
    row.file = "frames/" + name;
    row.sha256 = Sha256Hex(std::string(bytes.begin(), bytes.end()));
    return row;
  }

  fs::path dir_;
};

TEST_F(RecordingPngTest, AFrameWrittenByOpenCvReadsBackBitExactly) {
  const cv::Mat frame = TestFrame(37, 53);
  const FrameRecord row = WriteFrame("000000.png", Encode(frame));
  std::string why;
  const cv::Mat loaded = LoadFramePng(dir_.string(), row, &why);
  ASSERT_FALSE(loaded.empty()) << why;
  EXPECT_EQ(loaded.type(), CV_16UC1);
  EXPECT_TRUE(SameFrame(loaded, frame));
  // And as cv::imread itself reads the file.
  EXPECT_TRUE(SameFrame(cv::imread((dir_ / row.file).string(), cv::IMREAD_UNCHANGED), loaded));
  // A row without a hash (format 1) is read too.
  FrameRecord unhashed = row;
  unhashed.sha256.clear();
  EXPECT_TRUE(SameFrame(LoadFramePng(dir_.string(), unhashed, &why), frame)) << why;
}

// Two frames swapped on disk: each file is a valid PNG, but not its row's.
TEST_F(RecordingPngTest, AFileWhoseBytesAreNotItsRowsIsRefusedNamingBothHashes) {
  const std::vector<unsigned char> first = Encode(TestFrame(8, 8));
  const std::vector<unsigned char> second = Encode(TestFrame(8, 9));
  FrameRecord row = WriteFrame("000000.png", first);
  const std::string expected = row.sha256;
  WriteFrame("000000.png", second);
  std::string why;
  EXPECT_TRUE(LoadFramePng(dir_.string(), row, &why).empty());
  EXPECT_NE(why.find(expected), std::string::npos) << why;
  EXPECT_NE(why.find(Sha256Hex(std::string(second.begin(), second.end()))), std::string::npos)
      << why;
  EXPECT_NE(why.find("frames.csv"), std::string::npos) << why;
}

TEST_F(RecordingPngTest, AMissingFileOrAFolderInItsPlaceIsRefused) {
  FrameRecord row;
  row.file = "frames/000007.png";
  std::string why;
  EXPECT_TRUE(LoadFramePng(dir_.string(), row, &why).empty());
  EXPECT_NE(why.find("No such file"), std::string::npos) << why;
  fs::create_directory(dir_ / row.file);
  why.clear();
  EXPECT_TRUE(LoadFramePng(dir_.string(), row, &why).empty());
  EXPECT_NE(why.find("not a regular file"), std::string::npos) << why;
}

TEST(DecodeFramePng, BytesThatAreNotAPngAreRefused) {
  std::string why;
  const std::string text = "width,height\n640,480\n and some more text to pass 33 bytes";
  EXPECT_TRUE(DecodeFramePng({text.begin(), text.end()}, &why).empty());
  EXPECT_NE(why.find("not a PNG"), std::string::npos) << why;
  std::vector<unsigned char> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", cv::Mat(8, 8, CV_8UC1, cv::Scalar(9)), jpeg));
  why.clear();
  EXPECT_TRUE(DecodeFramePng(jpeg, &why).empty());
  EXPECT_NE(why.find("not a PNG"), std::string::npos) << why;
  why.clear();
  EXPECT_TRUE(DecodeFramePng({}, &why).empty());
  EXPECT_FALSE(why.empty());
}

// An 8-bit gray PNG and a 16-bit colour PNG are PNGs but not frames: depth 8, colour type 2.
TEST(DecodeFramePng, PngsOfAnotherDepthOrColourTypeAreRefusedSayingWhich) {
  std::string why;
  EXPECT_TRUE(DecodeFramePng(Encode(cv::Mat(4, 4, CV_8UC1, cv::Scalar(7))), &why).empty());
  EXPECT_NE(why.find("bit depth 8"), std::string::npos) << why;
  why.clear();
  EXPECT_TRUE(DecodeFramePng(Encode(cv::Mat(4, 4, CV_16UC3, cv::Scalar(1, 2, 3))), &why).empty());
  EXPECT_NE(why.find("colour type 2"), std::string::npos) << why;
}

// A header claiming 20000 x 10 px (over 16384 a side) is refused before any decoding.
TEST(DecodeFramePng, AHeaderClaimingAnAbsurdSizeIsRefusedBeforeDecoding) {
  std::vector<unsigned char> bytes = Encode(TestFrame(10, 10));
  ASSERT_GT(bytes.size(), 33u);
  bytes[16] = 0x00;
  bytes[17] = 0x00;
  bytes[18] = 0x4e;  // 20000 = 0x4e20
  bytes[19] = 0x20;
  std::string why;
  EXPECT_TRUE(DecodeFramePng(bytes, &why).empty());
  EXPECT_NE(why.find("20000 x 10"), std::string::npos) << why;
  // 16384 x 16384 is within a side but over 64 Mpx.
  bytes = Encode(TestFrame(10, 10));
  for (int at : {16, 20}) {
    bytes[at] = 0;
    bytes[at + 1] = 0;
    bytes[at + 2] = 0x40;
    bytes[at + 3] = 0x00;
  }
  why.clear();
  EXPECT_TRUE(DecodeFramePng(bytes, &why).empty());
  EXPECT_NE(why.find("16384 x 16384"), std::string::npos) << why;
}

// A PNG cut short (a copy interrupted) has a good header but no image data.
TEST(DecodeFramePng, ATruncatedPngIsRefusedAsDamaged) {
  const cv::Mat frame = TestFrame(32, 32);
  std::vector<unsigned char> bytes = Encode(frame);
  std::string why;
  EXPECT_TRUE(SameFrame(DecodeFramePng(bytes, &why), frame)) << why;
  bytes.resize(bytes.size() / 2);
  why.clear();
  EXPECT_TRUE(DecodeFramePng(bytes, &why).empty());
  EXPECT_NE(why.find("damaged PNG"), std::string::npos) << why;
}

}  // namespace
}  // namespace irdist
