// libFuzzer target: the recording readers (acquisition/recording_reader.h) on one input cut in
// three at the first two "\n%%\n": recording.yaml's text, frames.csv's text and a frame's PNG
// bytes. Every problem must be a RecordingError (named) or an issue in the parsed result; nothing
// else.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "acquisition/recording_reader.h"

namespace {

std::string Next(const std::string& input, size_t* at) {
  const size_t end = input.find("\n%%\n", *at);
  std::string part = input.substr(*at, end == std::string::npos ? std::string::npos : end - *at);
  *at = end == std::string::npos ? input.size() : end + 4;
  return part;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  size_t at = 0;
  const std::string yaml = Next(input, &at);
  const std::string csv = Next(input, &at);
  const std::string png = input.substr(at);
  try {
    irdist::ParseRecordingHeader(yaml, "recording.yaml");
  } catch (const irdist::RecordingError&) {
  }
  const irdist::FramesCsv parsed = irdist::ParseFramesCsv(csv);
  for (const auto& row : parsed.rows) {
    if (row.line < 2) __builtin_trap();  // every row knows its line
  }
  std::string why;
  const cv::Mat image = irdist::DecodeFramePng(std::vector<unsigned char>(png.begin(), png.end()), &why);
  if (image.empty() && why.empty()) __builtin_trap();  // a refusal always says why
  return 0;
}
