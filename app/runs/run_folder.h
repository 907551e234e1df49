#pragma once
// A live run's folder (calibrate, validate; layout in app/runs/run.h): its kind, a new folder made
// (never onto another run's recording or results) or a cut one checked for its resume, its lock
// for the whole run, the earlier sessions' station logs kept, and the advice when a result cannot
// be written (a full disk). The lock and the resume's checks are in app/runs/resume.h.

#include <cstdint>
#include <memory>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "app/runs/resume.h"

namespace irdist {

struct Recipe;
struct Plan;

enum class RunKind { kCalibrate, kValidate };

// "calibrate" or "validate": the command's name in messages, run.lock and recording.yaml.
const char* CommandName(RunKind kind);

// The files a finished run of `recipe` leaves in its folder, the last one written last.
std::vector<std::string> ResultsOf(RunKind kind, const Recipe& recipe);

// The local time as YYYYmmdd-HHMMSS, the suffix of a run folder named by its recipe.
std::string Timestamp();

// A new run folder holds no recording or results of another run (nor a link in their place).
// Throws RunFolderError pointing to --resume or another --out.
void RefuseOtherResults(const std::string& dir, RunKind kind);

// A live run's folder, locked (one run per folder) until this is destroyed.
struct RunFolder {
  std::string dir;
  bool record = true;                // false: the recording to resume is complete already
  std::set<std::int64_t> done_ids;   // a resume: the brackets recorded already
  std::unique_ptr<RunFolderLock> lock;
};

// Where the run of `kind` records: a new folder (`out_dir`, or the recipe's output_dir with a
// Timestamp) or the cut run `resume_dir` (CheckResume against `recipe_text` and the rig file's
// text; a resume's progress written to `err`). Then locked for the whole run (recording and
// processing). Throws RunFolderError, RecipeError.
RunFolder OpenRunFolder(RunKind kind, const std::string& out_dir, const std::string& resume_dir,
                        const Recipe& recipe, const Plan& plan, const std::string& recipe_text,
                        std::ostream& err);

// Moves `dir`/station.log, an earlier session's, to a free station.N.log and returns that name
// ("" when there was none).
std::string KeepEarlierLog(const std::string& dir);

// The advice when a result cannot be written (a full disk): the resume that completes them.
std::string CompleteResultsAdvice(RunKind kind, const std::string& recipe_path,
                                  const std::string& model_path, const std::string& dir);

}  // namespace irdist
