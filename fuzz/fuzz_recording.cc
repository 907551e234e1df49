// libFuzzer target: the recording readers (acquisition/recording_reader.h) on one input cut in
// three at the first two "\n%%\n": recording.yaml's text, frames.csv's text and a frame's PNG
// bytes. Every problem must be a RecordingError (named) or an issue in the parsed result; nothing
// else. What the readers accept has every number inside base/bounds.h's table (asserted here
// against the table itself, not through the reader's own check).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "acquisition/recording_reader.h"
#include "base/bounds.h"

namespace {

namespace b = irdist::bounds;

std::string Next(const std::string& input, size_t* at) {
  const size_t end = input.find("\n%%\n", *at);
  std::string part = input.substr(*at, end == std::string::npos ? std::string::npos : end - *at);
  *at = end == std::string::npos ? input.size() : end + 4;
  return part;
}

bool HeaderInBounds(const irdist::RecordingHeader& h) {
  if (!b::kBitDepth.Contains(h.bit_depth)) return false;
  if (h.frame_count != -1 && !b::kFrameNumber.Contains(static_cast<double>(h.frame_count))) {
    return false;
  }
  return b::kFrameNumber.Contains(static_cast<double>(h.unverified_rows));
}

bool RowInBounds(const irdist::FrameRecord& r) {
  const bool counts = b::kFrameNumber.Contains(static_cast<double>(r.index)) &&
                      b::kFrameNumber.Contains(static_cast<double>(r.bracket_id)) &&
                      b::kFrameNumber.Contains(r.frame_in_bracket) &&
                      b::kFrameNumber.Contains(r.bracket_size) &&
                      b::kFrameNumber.Contains(r.repeat);
  const bool pose = b::kSlideMm.Contains(r.slide_mm) && b::kAngleDeg.Contains(r.pan_deg) &&
                    b::kAngleDeg.Contains(r.tilt_deg) && b::kAngleDeg.Contains(r.theta_deg);
  const bool light = b::kExposureUs.Contains(r.requested_exposure_us) &&
                     b::kExposureUs.Contains(r.actual_exposure_us) &&
                     b::kCurrentMa.Contains(r.bias_ma_set) &&
                     (std::isnan(r.bias_ma_measured) || b::kCurrentMa.Contains(r.bias_ma_measured));
  const bool times = b::kUtcTimeNs.Contains(static_cast<double>(r.host_time_ns)) &&
                     b::kMonotonicNs.Contains(static_cast<double>(r.host_monotonic_ns));
  return counts && pose && light && times;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  size_t at = 0;
  const std::string yaml = Next(input, &at);
  const std::string csv = Next(input, &at);
  const std::string png = input.substr(at);
  try {
    const irdist::RecordingHeader header = irdist::ParseRecordingHeader(yaml, "recording.yaml");
    if (!HeaderInBounds(header)) __builtin_trap();  // accepted implies in the table
  } catch (const irdist::RecordingError&) {
  }
  const irdist::FramesCsv parsed = irdist::ParseFramesCsv(csv);
  for (const auto& row : parsed.rows) {
    if (row.line < 2) __builtin_trap();  // every row knows its line
    if (!RowInBounds(row)) __builtin_trap();  // accepted implies in the table
  }
  std::string why;
  const cv::Mat image = irdist::DecodeFramePng(std::vector<unsigned char>(png.begin(), png.end()), &why);
  if (image.empty() && why.empty()) __builtin_trap();  // a refusal always says why
  return 0;
}
