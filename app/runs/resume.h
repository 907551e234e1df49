#pragma once
// One run per run folder, and a resume continues only what it started: the folder's lock (a
// second run or resume beside a live one is refused, naming its pid), and the checks that the
// recipe, the rig file and the camera settings are the ones the recording was made with.

#include <cstdint>
#include <set>
#include <string>
#include <vector>

namespace irdist {

// Holds <run>/run.lock (flock) while a run records into the folder. The file keeps the pid and
// the command that made the folder ("calibrate", "validate"). Throws RunFolderError naming the
// pid of the live run. Creates the folder when needed.
class RunFolderLock {
 public:
  RunFolderLock(const std::string& run_dir, const std::string& command);
  ~RunFolderLock();
  RunFolderLock(const RunFolderLock&) = delete;
  RunFolderLock& operator=(const RunFolderLock&) = delete;

 private:
  int fd_ = -1;
};

// Creates the run folder `run_dir` (and its parents) when missing; throws RunFolderError naming
// the path and the fix when it is a file, a link or cannot be created.
void CreateRunFolder(const std::string& run_dir);

// Refuses (RunFolderError naming the pid and command) while a live run holds `run_dir`'s lock;
// `command` is the one refused ("fit"). Never takes the lock; a folder without run.lock is free.
void RefuseLiveRun(const std::string& run_dir, const std::string& command);

// What the resumed run uses; each must match the recording (the texts byte for byte).
struct ResumeExpectation {
  std::string recipe_path, recipe_text;
  std::string rig_path, rig_text;
  std::string pixel_format;
  int roi_offset_x = 0, roi_offset_y = 0, roi_width = 0, roi_height = 0;  // width 0: whole sensor
  // The files a finished run leaves in its folder, the last one written last (model.yaml and
  // report/index.html for calibrate): a complete recording missing one was cut during the
  // processing, which a resume then runs.
  std::vector<std::string> results;
};

struct Recipe;
// The expectation of a run of `recipe` (its rig's camera settings), with the texts as read.
ResumeExpectation ResumeExpectationOf(const Recipe& recipe, const std::string& recipe_text,
                                      const std::string& rig_text);

struct ResumeState {
  bool complete = false;       // the recording is complete: only the processing is left to do
  std::string missing_result;  // then: the first of ResumeExpectation::results that is missing
  std::set<std::int64_t> complete_brackets;
};

// Checks that `run_dir` can be resumed by `command` with `expected`: a recording is there, made
// by the same command (run.lock's, and recording.yaml's `command`), with the same recipe and rig
// bytes, pixel format and ROI, no error of `irdist check` in the recording (CheckFailedError
// listing them: a resume never hashes rows or frames edited since), and no part of the folder
// (recording, frames/, recording.yaml, model.yaml, ...) is a symbolic link. A cut
// recording is continued; a complete one only when one of its results is missing (the run was
// killed while processing); with every result there they stand and the resume is refused.
// Throws RunFolderError or RecipeError (InputError) naming the file and what differs.
ResumeState CheckResume(const std::string& run_dir, const std::string& command,
                        const ResumeExpectation& expected);

// "irdist calibrate RECIPE --resume RUN" (with --model MODEL for validate), each word quoted for
// a POSIX shell when it needs it (ShellQuoted).
std::string ResumeCommand(const std::string& command, const std::string& recipe_path,
                          const std::string& model_path, const std::string& run_dir);

// `word` as one word of a POSIX shell command: as is when it has only letters, digits and
// `_./:=,+@%-`, else in single quotes (a quote inside as '\'').
std::string ShellQuoted(const std::string& word);

}  // namespace irdist
