#pragma once
// What `irdist check` verifies beyond the format (docs/recording-format.md "irdist check"): that
// no part of the recording is a link, that frames.csv is the one closed, that the header's bit depth is the pixel format's, that no frame holds a value beyond it, and that
// within a bracket a longer exposure never gives a clearly lower signal (frames swapped, or
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

// Significant bits of a GenICam MonoN pixel format (Mono8 -> 8, ..., Mono16 -> 16); 0 for any
// other format (not checked).
int BitsOfMonoFormat(const std::string& pixel_format);

// image.bit_depth against image.pixel_format (an issue on recording.yaml when they differ).
std::vector<RecordingIssue> BitDepthIssues(const RecordingHeader& header);

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
