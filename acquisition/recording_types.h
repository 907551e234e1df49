#pragma once
// The recording's plain types (docs/recording-format.md): recording.yaml's header, a frames.csv row,
// a bracket as recorded, what `irdist check` reports, and the error of a recording. Shared by the
// writer, the reader and the check (acquisition/recording_writer.h, recording_reader.h,
// recording_check.h) and the integrity checks (acquisition/recording_integrity.h).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "acquisition/bracket.h"
#include "acquisition/camera.h"
#include "base/check.h"

namespace irdist {

// A recording that cannot be written or read. The message names the file (and line) and the fix.
class RecordingError : public Error {
 public:
  using Error::Error;
};

// Version 2 adds the time columns and the content hashes (frames.csv's utc_time,
// host_monotonic_ns and sha256 columns, recording.yaml's
// frames_csv_sha256); version 1 recordings still load, unverified, with a note from check.
inline constexpr int kRecordingFormatVersion = 2;
inline constexpr int kOldestRecordingFormatVersion = 1;

enum class Completion { kRunning, kComplete, kCut };
const char* CompletionName(Completion completion);  // "running" / "complete" / "cut"

// recording.yaml (see docs/recording-format.md for each key).
struct RecordingHeader {
  int format_version = kRecordingFormatVersion;
  Completion completion = Completion::kRunning;
  std::string software_version;
  std::string start_time;               // ISO 8601 UTC; set by the writer when empty
  std::string end_time;                 // set by Close()
  std::int64_t frame_count = -1;        // set by Close()
  std::vector<std::string> resumed;     // one start time per resumption
  int bit_depth = 16;                   // significant bits of the PNG values
  std::string pixel_format;             // the camera's PixelFormat
  CameraIdentity camera;
  std::map<std::string, std::string> camera_features;  // read back after configuring
  std::string station_identity;
  std::string recipe_path;
  std::string recipe_text;              // the recipe as used, byte for byte (recipe.yaml beside)
  std::string rig_path;
  std::string rig_text;                 // the rig file as used, byte for byte (rig.yaml beside)
  std::string frames_csv_sha256;        // SHA-256 of frames.csv, set by Close() ("" while open)
  // The first rows of frames.csv a resume found with no frames_csv_sha256 to verify them against
  // (their writer died): checked then only against their frames and for consistency. 0 = none.
  std::int64_t unverified_rows = 0;
  std::string run_command;              // the irdist command that made it ("calibrate"; "" unknown)
};

// One problem found in a recording: file relative to the recording, line (0 = not about a line).
struct RecordingIssue {
  std::string file;  // "frames.csv", "frames/000003.png"
  int line = 0;
  std::string message;
};

// One row of frames.csv.
struct FrameRecord {
  std::int64_t index = -1;              // assigned by the writer
  std::string file;                     // assigned by the writer ("frames/000042.png")
  std::int64_t bracket_id = 0;
  int frame_in_bracket = 0;
  int bracket_size = 0;
  FrameRole role = FrameRole::kReference;
  double requested_exposure_us = 0.0;
  double actual_exposure_us = 0.0;
  bool exposure_from_chunk = false;     // column exposure_source: chunk | readback
  double bias_ma_set = 0.0;
  double bias_ma_measured = 0.0;        // NaN = not measured (empty field)
  double slide_mm = 0.0;
  double pan_deg = 0.0;
  double tilt_deg = 0.0;
  double theta_deg = 0.0;
  int repeat = 0;
  std::uint64_t camera_frame_id = 0;
  std::uint64_t camera_timestamp_ns = 0;  // 0 = the camera gave none (empty field)
  std::int64_t host_time_ns = 0;          // wall clock at arrival (column utc_time: the same, UTC)
  std::int64_t host_monotonic_ns = 0;     // monotonic clock at arrival; 0 = not recorded (empty)
  std::string status = "ok";            // ok | retried
  std::string sha256;                   // of the PNG's bytes, set by the writer ("" = format 1)
  int line = 0;                         // line in frames.csv (filled by the reader)
};

// One bracket as recorded: its rows in frame_in_bracket order (the last row of each position wins
// when a resumed run re-acquired it).
struct RecordedBracket {
  std::int64_t bracket_id = 0;
  int bracket_size = 0;
  bool complete = false;                // every position 0..bracket_size-1 present
  std::vector<FrameRecord> frames;      // ordered by frame_in_bracket; only present positions
  const FrameRecord* Reference() const; // first ref frame, nullptr if none
  std::vector<const FrameRecord*> Measurements() const;
};

struct RecordingCheck {
  using Issue = RecordingIssue;
  Completion completion = Completion::kRunning;
  std::int64_t rows = 0;
  std::int64_t brackets = 0;
  std::int64_t complete_brackets = 0;
  std::vector<Issue> errors;    // the recording is damaged: bad rows, missing or bad PNGs, gaps
  std::vector<Issue> warnings;  // expected after a crash: leftovers, partial last line, cut
  std::string live_writer;      // pid of the live process writing it (writer.lock held), or ""
  bool ok() const { return errors.empty(); }
  std::string BriefReport() const;  // one line per issue, "file:line: message"
};

}  // namespace irdist
