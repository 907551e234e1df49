#pragma once
// What `irdist check` verifies beyond the format (docs/recording-format.md "irdist check"): that
// no part of the recording is a link, that frames.csv is the one closed, that the header's format, pixel format and bit depth
// agree with each other and the rows, that no frame holds a value beyond the bit depth, that every
// row of a bracket has its pose and current, and that within a bracket a longer exposure never gives a clearly lower signal (frames swapped, or
// exposures edited). Each problem is a RecordingIssue naming the file and line.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "acquisition/recording_types.h"

namespace irdist {

// The first part of the recording in `dir` that is a symbolic link (recording.yaml, frames.csv,
// frames, recipe.yaml, rig.yaml, writer.lock), or "" when none: readers and writers never follow
// one out of the folder. LinkedPartMessage says so, naming the path and the fix.
std::string LinkedRecordingPart(const std::string& dir);
std::string LinkedPartMessage(const std::string& dir, const std::string& part);

// frames.csv (its text) against recording.yaml's frames_csv_sha256: an error when they differ or
// when a closed format 2 recording has none; a note (warning) for a format 1 recording.
void AddCsvHashIssues(const RecordingHeader& header, const std::string& csv_text,
                      RecordingCheck* check);

// Significant bits of a pixel format irdist records (Mono8 -> 8, Mono12p -> 12, Mono16 -> 16); 0
// for any other format.
int BitsOfMonoFormat(const std::string& pixel_format);

// image.pixel_format against the formats irdist records, image.bit_depth and the camera's
// read-back camera.features.PixelFormat (issues on recording.yaml; an empty format, as hand-made
// recordings have, is not checked).
std::vector<RecordingIssue> PixelFormatIssues(const RecordingHeader& header);

// A header that contradicts its frames.csv's format: format_version 1 with format 2's columns or
// a frames_csv_sha256 (a downgrade that would drop the hashes), or format 2 without them.
std::vector<RecordingIssue> HeaderFormatIssues(const RecordingHeader& header, bool csv_hashed);

// Rows of a bracket at another pose or current than the bracket's first row (slide_mm, pan_deg,
// tilt_deg, theta_deg, bias_ma_set, repeat): one bracket is taken at one pose. One issue per row.
std::vector<RecordingIssue> BracketPoseIssues(const std::vector<RecordedBracket>& brackets);

// The first number of a parsed frames.csv row outside base/bounds.h's table, as "<column> = <value>
// is outside <range> (<why>)"; "" when all are inside. Checked: index, bracket_id,
// frame_in_bracket, bracket_size, both exposures, both currents (an empty bias_ma_measured is not
// measured), slide_mm, pan_deg, tilt_deg, theta_deg, repeat, host_time_ns, host_monotonic_ns (0 =
// not recorded). camera_frame_id and camera_timestamp_ns are the camera's own 64-bit counters: any
// value is possible.
std::string RowBoundsRefusal(const FrameRecord& row);

// What check measured of one decoded frame.
struct FrameSignal {
  double sum = 0.0;        // of every pixel value
  double max_value = 0.0;  // the largest pixel value
};

// A frame whose largest value needs more bits than image.bit_depth.
std::vector<RecordingIssue> ValueRangeIssues(const std::vector<FrameRecord>& rows,
                                             const std::map<std::int64_t, FrameSignal>& signals,
                                             int bit_depth);

// Brackets whose signal falls while the exposure grows: for two frames of a bracket at actual
// exposures t_i < t_j, the sum of frame j below that of frame i by more than 0.2% plus six times
// the shot noise of the two sums. One issue per bracket, on the later frame's frames.csv line.
std::vector<RecordingIssue> ExposureOrderIssues(const std::vector<RecordedBracket>& brackets,
                                                const std::map<std::int64_t, FrameSignal>& signals);

}  // namespace irdist
