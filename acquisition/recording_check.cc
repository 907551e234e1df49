#include "acquisition/recording_check.h"

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include <opencv2/core.hpp>

#include "acquisition/recording_files.h"
#include "acquisition/recording_integrity.h"
#include "acquisition/recording_reader.h"
#include "acquisition/recording_writer.h"

namespace irdist {

namespace fs = std::filesystem;

// --- CheckRecording ---------------------------------------------------------------------------

std::string RecordingCheck::BriefReport() const {
  std::ostringstream out;
  out << "recording " << CompletionName(completion)
      << (completion != Completion::kRunning ? ""
          : live_writer.empty() ? " (the writer died: treat as cut, its rows unverified)"
                                : " (being written by process " + live_writer + ")")
      << ", " << rows << " frames, " << complete_brackets << "/" << brackets
      << " brackets complete, " << errors.size() << " errors, " << warnings.size()
      << " warnings\n";
  auto print = [&out](const char* kind, const Issue& issue) {
    out << kind << ": " << issue.file;
    if (issue.line > 0) out << ":" << issue.line;
    out << ": " << issue.message << "\n";
  };
  for (const auto& issue : errors) print("error", issue);
  for (const auto& issue : warnings) print("warning", issue);
  return out.str();
}

namespace {

std::string SizeText(const cv::Size& size) {
  return std::to_string(size.width) + " x " + std::to_string(size.height) + " px";
}

// The size most frames have (the first of those with the most frames on a tie).
cv::Size CommonSize(const std::vector<std::pair<const FrameRecord*, cv::Size>>& sizes) {
  std::map<std::pair<int, int>, int> count;
  cv::Size common;
  int best = 0;
  for (const auto& [row, size] : sizes) {
    const int n = ++count[{size.width, size.height}];
    if (n > best) {
      best = n;
      common = size;
    }
  }
  return common;
}

// Every row's PNG: its recorded content (SHA-256), readable, 16-bit gray, all of one size (a frame
// of another size than most is the one blamed). Returns each decoded frame's signal.
std::map<std::int64_t, FrameSignal> CheckFrames(const std::string& dir,
                                                const std::vector<FrameRecord>& rows,
                                                RecordingCheck* check) {
  std::map<std::int64_t, FrameSignal> signals;
  std::vector<std::pair<const FrameRecord*, cv::Size>> sizes;
  for (const FrameRecord& row : rows) {
    std::string why;
    const cv::Mat image = LoadFramePng(dir, row, &why);
    if (image.empty()) {
      check->errors.push_back({row.file, 0, why + " (row at frames.csv:" +
                                                std::to_string(row.line) + ")"});
      continue;
    }
    sizes.emplace_back(&row, image.size());
    double max_value = 0.0;
    cv::minMaxLoc(image, nullptr, &max_value);
    signals[row.index] = {cv::sum(image)[0], max_value};
  }
  const cv::Size common = CommonSize(sizes);
  for (const auto& [row, size] : sizes) {
    if (size == common) continue;
    check->errors.push_back({row->file, 0, "its size " + SizeText(size) + " differs from the " +
                                               SizeText(common) + " of the recording's other "
                                               "frames (row at frames.csv:" +
                                               std::to_string(row->line) + ")"});
  }
  return signals;
}

// Files in frames/ without a row, and temp files.
void CheckLeftovers(const std::string& dir, const std::vector<FrameRecord>& rows,
                    RecordingCheck* check) {
  std::set<std::string> files;
  for (const FrameRecord& row : rows) files.insert(row.file);
  std::error_code ec;
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(fs::path(dir) / kFramesFolder, ec)) {
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  for (const std::string& name : names) {
    const std::string relative = std::string(kFramesFolder) + "/" + name;
    if (name.size() > 4 && name.substr(name.size() - 4) == ".tmp") {
      check->warnings.push_back({relative, 0, "leftover temporary file of a frame in flight"});
    } else if (files.count(relative) == 0) {
      check->warnings.push_back({relative, 0, "orphan file: no row in frames.csv refers to it"});
    }
  }
}

void CheckBrackets(const std::vector<FrameRecord>& rows, RecordingCheck* check) {
  const std::vector<RecordedBracket> brackets = BracketsOfRows(rows);
  check->brackets = static_cast<std::int64_t>(brackets.size());
  for (const RecordedBracket& bracket : brackets) {
    if (bracket.complete) {
      ++check->complete_brackets;
    } else {
      check->warnings.push_back({kFramesCsv, 0, "bracket " + std::to_string(bracket.bracket_id) +
                                              " is incomplete (" +
                                              std::to_string(bracket.frames.size()) + " of " +
                                              std::to_string(bracket.bracket_size) + " frames)"});
    }
  }
}

void AddIssues(const std::vector<RecordingIssue>& issues, std::vector<RecordingIssue>* to) {
  to->insert(to->end(), issues.begin(), issues.end());
}

void CheckRunning(const RecordingHeader& header, RecordingCheck* check) {
  if (!check->live_writer.empty()) {
    check->warnings.push_back({kRecordingYaml, 0,
                               "completion is 'running': the recording is being written by "
                               "process " + check->live_writer + " (a live run holds its "
                               "writer.lock); check it again once that run has ended"});
  } else if (!header.end_time.empty() || header.frame_count >= 0) {
    check->errors.push_back({kRecordingYaml, 0,
                             "completion is 'running' but end_time and frame_count are set, as "
                             "only a close sets them: the header was edited (its hash dropped). "
                             "Restore it from a copy of the recording"});
  } else {
    check->warnings.push_back(
        {kRecordingYaml, 0,
         "completion is 'running': the writer died; the run is cut. UNVERIFIED: frames.csv has no "
         "hash, so an edit of its rows (poses, currents, exposures) cannot be detected; only each "
         "frame's hash and the rows' consistency were checked. Resume the run to close it"});
  }
}

void CheckCompletion(const RecordingHeader& header, RecordingCheck* check) {
  switch (check->completion) {
    case Completion::kRunning:
      CheckRunning(header, check);
      break;
    case Completion::kCut:
      check->warnings.push_back(
          {kRecordingYaml, 0, "completion is 'cut': the run was stopped early"});
      break;
    case Completion::kComplete:
      if (header.frame_count != check->rows) {
        check->errors.push_back({kRecordingYaml, 0,
                                 "frame_count " + std::to_string(header.frame_count) +
                                     " but frames.csv has " + std::to_string(check->rows) +
                                     " rows"});
      }
      break;
  }
  if (header.unverified_rows > 0) {
    check->warnings.push_back(
        {kRecordingYaml, 0,
         "UNVERIFIED: the first " + std::to_string(header.unverified_rows) + " rows of frames.csv "
         "(lines 2 to " + std::to_string(header.unverified_rows + 1) + ") were written by a "
         "writer that died; the resume that continued them could check them only against their "
         "frames and for consistency, so an edit of them made before it cannot be detected"});
  }
}

}  // namespace

RecordingCheck CheckRecording(const std::string& dir) {
  RecordingCheck check;
  const std::string linked = LinkedRecordingPart(dir);
  if (!linked.empty()) {
    check.errors.push_back({linked, 0, LinkedPartMessage(dir, linked)});
    return check;
  }
  if (!fs::exists(fs::path(dir) / kRecordingYaml) && !fs::exists(fs::path(dir) / kFramesCsv)) {
    throw RecordingError(dir + " is not a recording (no recording.yaml, no frames.csv).");
  }
  RecordingHeader header;
  check.completion = Completion::kRunning;
  check.live_writer = LiveWriterOf(dir);
  bool header_ok = true;
  try {
    header = ReadRecordingHeader(dir);
    check.completion = header.completion;
  } catch (const RecordingError& error) {
    check.errors.push_back({kRecordingYaml, 0, error.what()});
    header_ok = false;
  }
  FramesCsv csv;
  std::string csv_text;
  try {
    csv_text = ReadFramesCsvText(dir);
    csv = ParseFramesCsv(csv_text);
  } catch (const RecordingError& error) {
    check.errors.push_back({kFramesCsv, 0, error.what()});
    return check;
  }
  check.errors.insert(check.errors.end(), csv.errors.begin(), csv.errors.end());
  check.warnings.insert(check.warnings.end(), csv.warnings.begin(), csv.warnings.end());
  check.rows = static_cast<std::int64_t>(csv.rows.size());
  const std::map<std::int64_t, FrameSignal> signals = CheckFrames(dir, csv.rows, &check);
  CheckLeftovers(dir, csv.rows, &check);
  CheckBrackets(csv.rows, &check);
  AddIssues(ExposureOrderIssues(BracketsOfRows(csv.rows), signals), &check.errors);
  AddIssues(BracketPoseIssues(BracketsOfRows(csv.rows)), &check.errors);
  if (!header_ok) return check;
  CheckCompletion(header, &check);
  AddCsvHashIssues(header, csv_text, &check);
  const bool csv_header_ok = std::none_of(csv.errors.begin(), csv.errors.end(),
                                          [](const RecordingIssue& e) { return e.line == 1; });
  if (csv_header_ok) AddIssues(HeaderFormatIssues(header, csv.hashed), &check.errors);
  AddIssues(PixelFormatIssues(header), &check.errors);
  AddIssues(ValueRangeIssues(csv.rows, signals, header.bit_depth), &check.errors);
  return check;
}

}  // namespace irdist
