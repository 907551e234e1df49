#pragma once
// Shared by the recording's tests (recording_writer_test.cc, recording_reader_test.cc,
// recording_check_test.cc): a test run whose every pixel tells its frame index, its header and
// rows, and small file utilities.

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "acquisition/recording_reader.h"
#include "acquisition/recording_writer.h"

namespace irdist {

inline constexpr int kBracketSize = 5;

inline std::string TempDir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                       ("irdist_rec_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  return dir.string();
}

inline RecordingHeader TestHeader() {
  RecordingHeader header;
  header.software_version = "irdist test";
  header.bit_depth = 12;
  header.pixel_format = "Mono12";
  header.camera = {"Aravis", "Fake", "GV01", "0.8.26", "127.0.0.1"};
  header.camera_features = {{"PixelFormat", "Mono12"}, {"TriggerSource", "Line1"},
                            {"Width", "64"}, {"DeviceVersion", "0.8: odd # text"}};
  header.station_identity = "IRDIST-STATION 1.0";
  header.recipe_path = "recipes/table3-calibration.yaml";
  header.recipe_text = "name: table3\nexposures_us: [8000, 30000]\n# a comment: kept\n";
  header.rig_path = "recipes/rigs/virtual.yaml";
  header.rig_text = "name: virtual\nkind: virtual\n";
  return header;
}

// Frame `index` of the test run: every pixel tells its index, so a mix-up is visible.
inline cv::Mat TestImage(std::int64_t index) {
  cv::Mat image(24, 32, CV_16UC1, cv::Scalar(static_cast<double>(index % 4096)));
  image.at<std::uint16_t>(0, 0) = 4095;
  return image;
}

inline FrameRecord TestRecord(std::int64_t index) {
  FrameRecord r;
  r.bracket_id = index / kBracketSize;
  r.frame_in_bracket = static_cast<int>(index % kBracketSize);
  r.bracket_size = kBracketSize;
  r.role = r.frame_in_bracket == 0 ? FrameRole::kReference : FrameRole::kMeasurement;
  r.requested_exposure_us = 8000.0 + 2000.0 * r.frame_in_bracket;
  r.actual_exposure_us = r.requested_exposure_us + 0.25;
  r.bias_ma_set = 500.0;
  r.bias_ma_measured = r.frame_in_bracket == 2 ? std::nan("") : 499.75;
  r.slide_mm = 1500.0 + 100.0 * static_cast<double>(r.bracket_id);
  r.pan_deg = 10.0;
  r.tilt_deg = -5.5;
  r.theta_deg = 11.4;
  r.repeat = 1;
  r.camera_frame_id = static_cast<std::uint64_t>(65530 + index) % 65536;
  // Frame 4 of each bracket: a camera that gives no timestamp.
  r.camera_timestamp_ns =
      index % kBracketSize == 4 ? 0 : 1000000000ull * static_cast<std::uint64_t>(index + 1);
  r.host_time_ns = 1700000000000000000ll + 1000 * index;
  r.host_monotonic_ns = 5000000000ll + 1000 * index;
  r.status = index % 7 == 3 ? "retried" : "ok";
  return r;
}

inline void WriteFrames(RecordingWriter& writer, std::int64_t from, std::int64_t to) {
  for (std::int64_t i = from; i < to; ++i) writer.Append(TestImage(i), TestRecord(i));
}

inline int CountCsvRows(const std::string& dir) {
  std::ifstream in(std::filesystem::path(dir) / "frames.csv");
  int lines = 0;
  std::string line;
  while (std::getline(in, line)) ++lines;
  return lines - 1;
}

// The PNG and temporary files in frames/.
inline std::vector<std::string> FramesDirNames(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& entry :
       std::filesystem::directory_iterator(std::filesystem::path(dir) / "frames")) {
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

inline std::string Slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

inline void WriteText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

// Rewrites line `line` (1-based) of frames.csv through `edit`.
inline void EditCsvLine(const std::string& dir, int line,
                        const std::function<std::string(std::string)>& edit) {
  std::istringstream in(Slurp(std::filesystem::path(dir) / "frames.csv"));
  std::string out, text;
  for (int n = 1; std::getline(in, text); ++n) out += (n == line ? edit(text) : text) + "\n";
  WriteText(std::filesystem::path(dir) / "frames.csv", out);
}

inline std::string CompleteRecording(const std::string& name, int frames) {
  const std::string dir = TempDir(name);
  auto writer = RecordingWriter::Open(dir, TestHeader());
  WriteFrames(*writer, 0, frames);
  writer->Close(Completion::kComplete);
  return dir;
}

inline std::string ReaderError(const std::string& dir) {
  try {
    const RecordingReader reader(dir);
    for (const FrameRecord& row : reader.rows()) reader.LoadImage(row);
  } catch (const RecordingError& error) {
    return error.what();
  }
  return "";
}

// frames.csv's line `line` split at commas (an empty last field kept).
inline std::vector<std::string> CsvFields(const std::string& dir, int line) {
  std::istringstream in(Slurp(std::filesystem::path(dir) / "frames.csv"));
  std::string text;
  for (int n = 1; n <= line; ++n) std::getline(in, text);
  std::vector<std::string> fields;
  std::istringstream row(text + ",");
  for (std::string field; std::getline(row, field, ',');) fields.push_back(field);
  return fields;
}

}  // namespace irdist
