#pragma once
// Reading a recording (docs/recording-format.md is the contract): RecordingReader gives back its
// header and brackets, refusing a recording with a bad row, a link or an edited text; the
// parsers of frames.csv and recording.yaml every reader shares (the check and a resume too), and
// the one decoder of a frame's PNG.

#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "acquisition/recording_types.h"

namespace irdist {

// Largest frame the readers decode (checked on the PNG header, before decoding).
inline constexpr std::int64_t kMaxFrameSidePx = 16384;
inline constexpr std::int64_t kMaxFramePixels = std::int64_t{1} << 26;  // 64 Mpx, 128 MB at 16 bit

// The frames.csv header line (without '\n').
const std::string& FramesCsvHeader();

class RecordingReader {
 public:
  // Reads recording.yaml and frames.csv. A partial last line (crash mid-write) is ignored; any
  // other unreadable row throws RecordingError naming frames.csv:line (use CheckRecording for a full
  // report instead of the first problem).
  explicit RecordingReader(const std::string& dir);

  const std::string& dir() const { return dir_; }
  const RecordingHeader& header() const { return header_; }
  // Completion as written: kRunning is a live writer's (LiveWriterOf names it) or, with none
  // alive, a writer's that died (treat as cut).
  Completion completion() const { return header_.completion; }
  bool IsComplete() const { return header_.completion == Completion::kComplete; }
  const std::vector<FrameRecord>& rows() const { return rows_; }
  // Brackets in order of first appearance.
  std::vector<RecordedBracket> Brackets() const;
  std::set<std::int64_t> CompleteBracketIds() const;
  // Loads a frame's PNG as CV_16UC1 (a regular file inside the recording, never a FIFO or a
  // link; its header checked against the size limits before decoding). Throws RecordingError
  // naming the file, its frames.csv line and the fix.
  cv::Mat LoadImage(const FrameRecord& row) const;

 private:
  std::string dir_;
  RecordingHeader header_;
  std::vector<FrameRecord> rows_;
};

// frames.csv parsed once for every reader: the header line, each row (its `file` must be
// frames/<index>.png of its own index), duplicates, gaps and order. A partial last line is a
// warning and left out. Used by RecordingReader (first error thrown) and CheckRecording (all).
struct FramesCsv {
  bool hashed = false;            // the header has the sha256 column (format 2)
  std::vector<FrameRecord> rows;  // the readable complete rows, line filled
  std::vector<RecordingIssue> errors, warnings;
  std::uint64_t complete_bytes = 0;  // bytes up to and including the last '\n'
  bool partial_last = false;
};
FramesCsv ParseFramesCsv(const std::string& text);

// recording.yaml's text parsed strictly (unknown keys are errors; bit_depth 1..16 required).
// The recipe and rig text are read from recipe.yaml / rig.yaml by ReadRecordingHeader. `file`
// names the file in messages. Throws RecordingError naming file:line and the fix.
RecordingHeader ParseRecordingHeader(const std::string& text, const std::string& file);
RecordingHeader ReadRecordingHeader(const std::string& dir);

// Decodes a frame's PNG bytes as CV_16UC1 after checking its header (signature, IHDR, 16-bit
// gray, sides within the limits). Returns an empty Mat and sets `why` when refused.
cv::Mat DecodeFramePng(const std::vector<unsigned char>& bytes, std::string* why);

}  // namespace irdist
