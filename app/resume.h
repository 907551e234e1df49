#pragma once
// One run per run folder, and a resume continues only what it started: the folder's lock (a
// second run or resume beside a live one is refused, naming its pid), and the checks that the
// recipe, the rig file and the camera settings are the ones the recording was made with.

#include <cstdint>
#include <set>
#include <string>

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

// What the resumed run uses; each must match the recording (the texts byte for byte).
struct ResumeExpectation {
  std::string recipe_path, recipe_text;
  std::string rig_path, rig_text;
  std::string pixel_format;
  int roi_offset_x = 0, roi_offset_y = 0, roi_width = 0, roi_height = 0;  // width 0: whole sensor
};

struct Recipe;
// The expectation of a run of `recipe` (its rig's camera settings), with the texts as read.
ResumeExpectation ResumeExpectationOf(const Recipe& recipe, const std::string& recipe_text,
                                      const std::string& rig_text);

struct ResumeState {
  bool complete = false;  // never true on return: a complete recording is refused
  std::set<std::int64_t> complete_brackets;
};

// Checks that `run_dir` can be resumed by `command` with `expected`: a recording is there, cut
// (not complete: its results stand, nothing is refitted), made by the same command, with the same
// recipe and rig bytes, pixel format and ROI. Throws RunFolderError or RecipeError (InputError)
// naming the file and what differs.
ResumeState CheckResume(const std::string& run_dir, const std::string& command,
                        const ResumeExpectation& expected);

// "irdist calibrate RECIPE --resume RUN" (with --model MODEL for validate).
std::string ResumeCommand(const std::string& command, const std::string& recipe_path,
                          const std::string& model_path, const std::string& run_dir);

}  // namespace irdist
