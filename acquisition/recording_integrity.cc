#include "acquisition/recording_integrity.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <tuple>

#include "acquisition/content_hash.h"
#include "acquisition/pixel_format.h"
#include "base/bounds.h"
#include "base/safe_file.h"

namespace irdist {
namespace {

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.10g", value);
  return text;
}

// Whether the longer exposure's signal is clearly below the shorter one's.
bool Contradicts(const FrameSignal& shorter, const FrameSignal& longer) {
  const double tolerance = 0.002 * std::max(shorter.sum, longer.sum) +
                           6.0 * std::sqrt(std::max(0.0, shorter.sum + longer.sum));
  return longer.sum < shorter.sum - tolerance;
}

}  // namespace

std::string LinkedRecordingPart(const std::string& dir) {
  for (const char* part : {"recording.yaml", "frames.csv", "frames", "recipe.yaml", "rig.yaml",
                           "writer.lock"}) {
    if (IsSymlink((std::filesystem::path(dir) / part).string())) return part;
  }
  return "";
}

std::string LinkedPartMessage(const std::string& dir, const std::string& part) {
  return (std::filesystem::path(dir) / part).string() + " is a symbolic link; irdist never "
         "reads or writes a recording through a link. Replace it with the real " +
         std::string(part == "frames" ? "folder" : "file") + " (or remove it) and run `irdist "
         "check` again";
}

void AddCsvHashIssues(const RecordingHeader& header, const std::string& csv_text,
                      RecordingCheck* check) {
  if (header.format_version < 2) {
    check->warnings.push_back({"recording.yaml", 0,
                               "note: format_version " + std::to_string(header.format_version) +
                                   " (before content hashes): frames and frames.csv cannot be "
                                   "verified"});
  } else if (!header.frames_csv_sha256.empty()) {
    const std::string actual = Sha256Hex(csv_text);
    if (actual != header.frames_csv_sha256) {
      check->errors.push_back({"frames.csv", 0,
                               "its SHA-256 is " + actual + ", recording.yaml's "
                               "frames_csv_sha256 is " + header.frames_csv_sha256 +
                                   ": frames.csv was edited after the recording was closed. "
                                   "Restore it from a copy of the recording"});
    }
  } else if (header.completion != Completion::kRunning) {
    check->errors.push_back({"recording.yaml", 0,
                             "completion is '" + std::string(CompletionName(header.completion)) +
                                 "' but frames_csv_sha256 is missing: the header was edited. "
                                 "Restore it from a copy of the recording"});
  }
}

int BitsOfMonoFormat(const std::string& pixel_format) {
  const PixelFormatInfo* format = FindPixelFormat(pixel_format);
  return format == nullptr ? 0 : format->bit_depth;
}

std::vector<RecordingIssue> PixelFormatIssues(const RecordingHeader& header) {
  if (header.pixel_format.empty()) return {};
  const int bits = BitsOfMonoFormat(header.pixel_format);
  if (bits == 0) {
    return {{"recording.yaml", 0,
             "image.pixel_format " + header.pixel_format + " is not a format irdist records (" +
                 SupportedPixelFormatNames() + "): the header was edited or the recording is "
                 "not irdist's. Restore it from a copy of the recording"}};
  }
  std::vector<RecordingIssue> issues;
  if (bits != header.bit_depth) {
    issues.push_back({"recording.yaml", 0,
                      "image.bit_depth " + std::to_string(header.bit_depth) + " contradicts " +
                          "image.pixel_format " + header.pixel_format + ", which delivers " +
                          std::to_string(bits) + " bits; set image.bit_depth: " +
                          std::to_string(bits)});
  }
  const auto camera = header.camera_features.find("PixelFormat");
  if (camera != header.camera_features.end() && camera->second != header.pixel_format) {
    issues.push_back({"recording.yaml", 0,
                      "image.pixel_format " + header.pixel_format + " contradicts the camera's "
                      "camera.features.PixelFormat " + camera->second + " (read back when the "
                      "recording started): the header was edited. Restore it from a copy of the "
                      "recording"});
  }
  return issues;
}

std::vector<RecordingIssue> HeaderFormatIssues(const RecordingHeader& header, bool csv_hashed) {
  const std::string version = "format_version " + std::to_string(header.format_version);
  const std::string fix = ": the header was edited. Restore it from a copy of the recording";
  if (header.format_version < 2 && (csv_hashed || !header.frames_csv_sha256.empty())) {
    return {{"recording.yaml", 0,
             version + " (before content hashes) but " +
                 (csv_hashed ? "frames.csv has format 2's sha256 column"
                             : "it carries a frames_csv_sha256") +
                 fix + " (a downgrade would leave the rows and frames unverified)"}};
  }
  if (header.format_version >= 2 && !csv_hashed) {
    return {{"frames.csv", 1, "has format 1's columns (no sha256) but recording.yaml says " +
                                  version + fix + " or frames.csv"}};
  }
  return {};
}

std::vector<RecordingIssue> BracketPoseIssues(const std::vector<RecordedBracket>& brackets) {
  std::vector<RecordingIssue> issues;
  for (const RecordedBracket& bracket : brackets) {
    if (bracket.frames.empty()) continue;
    const FrameRecord& first = bracket.frames.front();
    const auto pose = [](const FrameRecord& r) {
      return std::make_tuple(r.slide_mm, r.pan_deg, r.tilt_deg, r.theta_deg, r.bias_ma_set,
                             r.repeat);
    };
    for (const FrameRecord& row : bracket.frames) {
      if (pose(row) == pose(first)) continue;
      issues.push_back({"frames.csv", row.line,
                        "bracket " + std::to_string(bracket.bracket_id) + ": " + row.file +
                            " is at slide " + Number(row.slide_mm) + " mm, pan " +
                            Number(row.pan_deg) + " deg, tilt " + Number(row.tilt_deg) +
                            " deg, theta " + Number(row.theta_deg) + " deg, " +
                            Number(row.bias_ma_set) + " mA, repeat " +
                            std::to_string(row.repeat) + ", not at its bracket's pose and "
                            "current (those of " + first.file + " at frames.csv:" +
                            std::to_string(first.line) + "): a bracket is taken at one pose. "
                            "Restore frames.csv from a copy of the recording"});
    }
  }
  return issues;
}

std::vector<RecordingIssue> ValueRangeIssues(const std::vector<FrameRecord>& rows,
                                             const std::map<std::int64_t, FrameSignal>& signals,
                                             int bit_depth) {
  std::vector<RecordingIssue> issues;
  const double limit = std::ldexp(1.0, bit_depth) - 1.0;
  for (const FrameRecord& row : rows) {
    const auto found = signals.find(row.index);
    if (found == signals.end() || found->second.max_value <= limit) continue;
    issues.push_back({row.file, 0,
                      "holds the value " + Number(found->second.max_value) +
                          ", beyond image.bit_depth " + std::to_string(bit_depth) +
                          " (at most " + Number(limit) + "; row at frames.csv:" +
                          std::to_string(row.line) + ")"});
  }
  return issues;
}

std::vector<RecordingIssue> ExposureOrderIssues(
    const std::vector<RecordedBracket>& brackets,
    const std::map<std::int64_t, FrameSignal>& signals) {
  std::vector<RecordingIssue> issues;
  for (const RecordedBracket& bracket : brackets) {
    std::vector<const FrameRecord*> frames;
    for (const FrameRecord& row : bracket.frames) {
      if (signals.count(row.index) > 0) frames.push_back(&row);
    }
    std::sort(frames.begin(), frames.end(), [](const FrameRecord* a, const FrameRecord* b) {
      return a->actual_exposure_us < b->actual_exposure_us;
    });
    bool found = false;
    for (std::size_t j = 1; j < frames.size() && !found; ++j) {
      for (std::size_t i = 0; i < j && !found; ++i) {
        const FrameRecord& a = *frames[i];
        const FrameRecord& b = *frames[j];
        if (b.actual_exposure_us <= a.actual_exposure_us * 1.001) continue;
        found = Contradicts(signals.at(a.index), signals.at(b.index));
        if (!found) continue;
        issues.push_back(
            {"frames.csv", b.line,
             "bracket " + std::to_string(bracket.bracket_id) + ": " + b.file + " (exposure " +
                 Number(b.actual_exposure_us) + " us) has less signal (sum " +
                 Number(signals.at(b.index).sum) + ") than " + a.file + " (exposure " +
                 Number(a.actual_exposure_us) + " us, sum " + Number(signals.at(a.index).sum) +
                 "): the frames are swapped or their exposures are wrong"});
      }
    }
  }
  return issues;
}

std::string RowBoundsRefusal(const FrameRecord& row) {
  const std::string fix = "frames.csv rows are written by irdist; restore the file from a copy";
  const struct {
    const char* column;
    double value;
    const Bound& bound;
  } numbers[] = {
      {"index", static_cast<double>(row.index), bounds::kFrameNumber},
      {"bracket_id", static_cast<double>(row.bracket_id), bounds::kFrameNumber},
      {"frame_in_bracket", static_cast<double>(row.frame_in_bracket), bounds::kFrameNumber},
      {"bracket_size", static_cast<double>(row.bracket_size), bounds::kFrameNumber},
      {"requested_exposure_us", row.requested_exposure_us, bounds::kExposureUs},
      {"actual_exposure_us", row.actual_exposure_us, bounds::kExposureUs},
      {"bias_ma_set", row.bias_ma_set, bounds::kCurrentMa},
      {"slide_mm", row.slide_mm, bounds::kSlideMm},
      {"pan_deg", row.pan_deg, bounds::kAngleDeg},
      {"tilt_deg", row.tilt_deg, bounds::kAngleDeg},
      {"theta_deg", row.theta_deg, bounds::kAngleDeg},
      {"repeat", static_cast<double>(row.repeat), bounds::kFrameNumber},
      {"host_time_ns", static_cast<double>(row.host_time_ns), bounds::kUtcTimeNs},
      {"host_monotonic_ns", static_cast<double>(row.host_monotonic_ns), bounds::kMonotonicNs},
  };
  for (const auto& number : numbers) {
    const std::string refusal = number.bound.Refusal(number.column, number.value, fix);
    if (!refusal.empty()) return refusal;
  }
  if (!std::isnan(row.bias_ma_measured)) {
    return bounds::kCurrentMa.Refusal("bias_ma_measured", row.bias_ma_measured, fix);
  }
  return "";
}

}  // namespace irdist
