#pragma once
// The recording's files and the reading helpers its writer (acquisition/recording_writer.h) and
// check (acquisition/recording_check.h) share with the reader (acquisition/recording_reader.h),
// which defines them. Acquisition-internal: included by those .cc files only.

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "acquisition/recording_types.h"

namespace irdist {

// A recording folder's files (docs/recording-format.md) and the size limit of its texts.
inline constexpr char kRecordingYaml[] = "recording.yaml";
inline constexpr char kFramesCsv[] = "frames.csv";
inline constexpr char kFramesFolder[] = "frames";
inline constexpr char kRecipeCopy[] = "recipe.yaml";
inline constexpr char kRigCopy[] = "rig.yaml";
inline constexpr std::int64_t kMaxRecordingTextBytes = std::int64_t{1} << 30;

// "frames/000042.png": the one file name of frame `index`.
std::string FrameFileName(std::int64_t index);
// A CRC-32 of a text, as 8 hex digits: recording.yaml's check of recipe.yaml and rig.yaml.
std::string TextCrc32Hex(const std::string& text);
// A whole decimal integer (no sign check); false when `text` is not one.
bool ParseCsvInt(const std::string& text, std::int64_t* value);
// Parses one frames.csv data line (`hashed`: format 2, with the time and sha256 columns); on
// failure says which column is wrong.
bool ParseFramesCsvRow(const std::string& line, FrameRecord* r, std::string* why, bool hashed);
// Brackets in order of first appearance; the last row of each (bracket, position) wins (a
// resumed run re-acquires incomplete brackets). The one completeness rule of every reader.
std::vector<RecordedBracket> BracketsOfRows(const std::vector<FrameRecord>& rows);
// Reads and decodes a frame's PNG; an empty Mat and `why` when refused.
cv::Mat LoadFramePng(const std::string& dir, const FrameRecord& row, std::string* why);
// The text of frames.csv (a regular file, read without blocking). Throws RecordingError.
std::string ReadFramesCsvText(const std::string& dir);
// Throws RecordingError when a part of the recording is a symbolic link.
void RefuseLinkedRecordingParts(const std::string& dir);
// Throws RecordingError naming the issue's file:line and `irdist check`.
[[noreturn]] void ThrowRecordingIssue(const std::string& dir, const RecordingIssue& issue);

}  // namespace irdist
