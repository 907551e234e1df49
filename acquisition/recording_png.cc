// A frame's PNG, read and decoded for every reader (RecordingReader, check, the writer's
// resume): its size and format checked on the header before decoding, its bytes against the
// row's SHA-256.
#include "acquisition/recording_reader.h"

#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "acquisition/content_hash.h"
#include "acquisition/recording_files.h"
#include "base/regular_file.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

constexpr std::int64_t kMaxPngBytes = std::int64_t{1} << 28;

std::uint32_t BigEndian32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

}  // namespace

cv::Mat LoadFramePng(const std::string& dir, const FrameRecord& row, std::string* why) {
  std::string bytes;
  if (!ReadRegularFile((fs::path(dir) / row.file).string(), kMaxPngBytes, &bytes, why)) {
    return cv::Mat();
  }
  cv::Mat image = DecodeFramePng(std::vector<unsigned char>(bytes.begin(), bytes.end()), why);
  if (!image.empty() && !row.sha256.empty() && Sha256Hex(bytes) != row.sha256) {
    *why = "its content is not the frame recorded in its row (SHA-256 " + Sha256Hex(bytes) +
           ", frames.csv says " + row.sha256 + "): the file was replaced, swapped or edited. "
           "Restore it from a copy of the recording";
    return cv::Mat();
  }
  return image;
}

cv::Mat DecodeFramePng(const std::vector<unsigned char>& bytes, std::string* why) {
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (bytes.size() < 33 || std::memcmp(bytes.data(), kSignature, 8) != 0 ||
      std::memcmp(bytes.data() + 12, "IHDR", 4) != 0) {
    *why = "not a PNG file (no PNG signature and IHDR header)";
    return cv::Mat();
  }
  const std::int64_t width = BigEndian32(bytes.data() + 16);
  const std::int64_t height = BigEndian32(bytes.data() + 20);
  if (width < 1 || height < 1 || width > kMaxFrameSidePx || height > kMaxFrameSidePx ||
      width * height > kMaxFramePixels) {
    *why = "PNG header claims " + std::to_string(width) + " x " + std::to_string(height) +
           " px, beyond the limit of " + std::to_string(kMaxFrameSidePx) + " px a side and " +
           std::to_string(kMaxFramePixels) + " px; the file is damaged or not a frame";
    return cv::Mat();
  }
  if (bytes[24] != 16 || bytes[25] != 0) {
    *why = "not a single-channel 16-bit PNG (bit depth " + std::to_string(bytes[24]) +
           ", colour type " + std::to_string(bytes[25]) + ")";
    return cv::Mat();
  }
  cv::Mat image;
  try {
    image = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& error) {
    image = cv::Mat();
  }
  if (image.empty() || image.type() != CV_16UC1) {
    *why = "damaged PNG: its image data cannot be decoded as 16-bit gray";
    return cv::Mat();
  }
  return image;
}

}  // namespace irdist
