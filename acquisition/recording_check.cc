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

namespace irdist {

namespace fs = std::filesystem;

// --- CheckRecording ---------------------------------------------------------------------------

std::string RecordingCheck::BriefReport() const {
  std::ostringstream out;
  out << "recording " << CompletionName(completion)
      << (completion == Completion::kRunning ? " (the writer did not finish: treat as cut)" : "")
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

// Every row's PNG: its recorded content (SHA-256), readable, 16-bit gray, all of one size.
// Returns each decoded frame's signal.
std::map<std::int64_t, FrameSignal> CheckFrames(const std::string& dir,
                                                const std::vector<FrameRecord>& rows,
                                                RecordingCheck* check) {
  std::map<std::int64_t, FrameSignal> signals;
  cv::Size size;
  for (const FrameRecord& row : rows) {
    std::string why;
    const cv::Mat image = LoadFramePng(dir, row, &why);
    const std::string at = " (row at frames.csv:" + std::to_string(row.line) + ")";
    if (image.empty()) {
      check->errors.push_back({row.file, 0, why + at});
      continue;
    }
    if (size.area() == 0) {
      size = image.size();
    } else if (image.size() != size) {
      check->errors.push_back({row.file, 0, "size differs from the first frame" + at});
    }
    double max_value = 0.0;
    cv::minMaxLoc(image, nullptr, &max_value);
    signals[row.index] = {cv::sum(image)[0], max_value};
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

void CheckCompletion(const RecordingHeader& header, RecordingCheck* check) {
  switch (check->completion) {
    case Completion::kRunning:
      check->warnings.push_back(
          {kRecordingYaml, 0, "completion is 'running': the writer died; the run is cut"});
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
  if (!header_ok) return check;
  CheckCompletion(header, &check);
  AddCsvHashIssues(header, csv_text, &check);
  AddIssues(BitDepthIssues(header), &check.errors);
  AddIssues(ValueRangeIssues(csv.rows, signals, header.bit_depth), &check.errors);
  return check;
}

}  // namespace irdist
