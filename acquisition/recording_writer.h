#pragma once
// Writing a recording (docs/recording-format.md is the contract): RecordingWriter appends frames
// crash-safely (PNG to a temp name, rename, then the CSV row appended and flushed), one writer at
// a time (its lock), and resumes a cut recording without deleting a frame.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "acquisition/bracket.h"
#include "acquisition/recording_types.h"

namespace irdist {

// Builds a record from a captured frame (exposures, ids, times, role, status); the caller fills the
// pose, current, bracket id and repeat.
FrameRecord RecordFromFrame(const BracketFrame& frame, int bracket_size);

class RecordingWriter {
 public:
  // Creates `dir` (must not exist, or be empty), frames/, frames.csv and recording.yaml with
  // completion: running. Throws RecordingError.
  static std::unique_ptr<RecordingWriter> Open(const std::string& dir, RecordingHeader header);
  // Reopens a cut (or crashed: completion running) recording to continue it: drops a partial last
  // CSV line, moves leftover temp/orphan files aside (never deletes a frame; set_aside() lists
  // them), appends after the last index and records the resumption in recording.yaml. Throws
  // RecordingError if `dir` is not a recording, is complete, or frames.csv has errors.
  static std::unique_ptr<RecordingWriter> Resume(const std::string& dir);
  // Both hold the recording's lock (flock on <dir>/writer.lock, with the writer's pid) for the
  // writer's lifetime (until Close): a second writer is refused with a RecordingError naming the
  // first's pid.

  ~RecordingWriter();  // without Close(), the recording stays "running" on disk (reads as cut)
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  // Writes the frame's PNG (CV_16UC1 or CV_8UC1, values as delivered) crash-safely, then appends
  // its row and syncs frames.csv (Stage + CommitStaged of one frame; nothing may be staged).
  // Returns the record with index and file filled in. Throws RecordingError.
  FrameRecord Append(const cv::Mat& image, FrameRecord record);
  // A bracket in two steps, so that encoding and writing overlap the capture of the next frames.
  // Stage encodes the frame's PNG and writes it, synced, under a temporary name (frames/N.png.tmp,
  // not part of the recording: a resume moves it aside); returns the index it will have.
  // CommitStaged makes every staged frame part of the recording at once: renames them, syncs
  // frames/ once, then appends their rows (one record per staged frame, in order; index and file
  // are filled in) and syncs frames.csv. A crash at any point leaves whole brackets only: rows
  // are written last. DropStaged removes the staged files (a bracket not kept). Throw
  // RecordingError; after one, the writer refuses further writes.
  std::int64_t Stage(const cv::Mat& image);
  std::vector<FrameRecord> CommitStaged(std::vector<FrameRecord> records);
  void DropStaged();
  std::size_t staged_count() const { return staged_.size(); }
  // Rewrites recording.yaml with the completion state, end time and frame count. Idempotent.
  // After a failed Append (the first error is what the caller reports), Close never throws: if
  // recording.yaml cannot be rewritten the recording stays "running", which reads as cut.
  void Close(Completion completion);
  // Files moved aside by Resume() (relative to the recording), and where to.
  const std::vector<std::string>& set_aside() const { return set_aside_; }
  const std::string& set_aside_dir() const { return set_aside_dir_; }
  bool failed() const { return !first_error_.empty(); }

  const std::string& dir() const { return dir_; }
  std::int64_t next_index() const { return next_index_; }
  const RecordingHeader& header() const { return header_; }

 private:
  RecordingWriter(std::string dir, RecordingHeader header, std::int64_t next_index);
  void WriteHeader();
  void ThrowIfFailed() const;
  std::vector<std::string> StagedRows(std::vector<FrameRecord>* records) const;

  std::string dir_;
  RecordingHeader header_;
  std::int64_t next_index_ = 0;
  int csv_fd_ = -1;
  int lock_fd_ = -1;
  bool hashed_ = true;  // rows carry their PNG's SHA-256 (false: resuming a format 1 recording)
  bool closed_ = false;
  std::string first_error_;
  std::vector<std::string> staged_;  // temporary paths of the staged frames, in index order
  std::vector<std::string> staged_sha256_;  // their PNG bytes' SHA-256
  std::vector<std::string> set_aside_;
  std::string set_aside_dir_;
};

// The pid of the live writer that holds the recording's lock (writer.lock), or "" when no writer
// is live. Never takes the lock.
std::string LiveWriterOf(const std::string& dir);

}  // namespace irdist
