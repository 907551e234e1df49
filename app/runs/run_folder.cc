#include "app/runs/run_folder.h"

#include <ctime>
#include <filesystem>
#include <system_error>

#include "app/inputs/errors.h"
#include "app/inputs/recipe.h"
#include "base/yaml_fields.h"
#include "station/plan.h"

namespace irdist {

namespace fs = std::filesystem;

std::string Timestamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  localtime_r(&now, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof(buffer), "%Y%m%d-%H%M%S", &tm);
  return buffer;
}

const char* CommandName(RunKind kind) {
  return kind == RunKind::kCalibrate ? "calibrate" : "validate";
}

// The files a finished run of `recipe` leaves in its folder, the last one written last.
std::vector<std::string> ResultsOf(RunKind kind, const Recipe& recipe) {
  if (recipe.after == AfterRecording::kNone) return {"features.csv"};
  if (kind == RunKind::kCalibrate) return {"model.yaml", "report/index.html"};
  return {"estimates.csv", "summary.yaml", "report/index.html"};
}

// A new run folder holds no recording or results of another run (nor a link in their place).
void RefuseOtherResults(const std::string& dir, RunKind kind) {
  for (const char* name : {"recording", "model.yaml", "features.csv", "estimates.csv",
                           "summary.yaml", "report"}) {
    const fs::path path = fs::path(dir) / name;
    std::error_code ec;
    if (fs::exists(fs::symlink_status(path, ec))) {
      throw RunFolderError(path.string() + " exists already: irdist " + CommandName(kind) +
                           " never replaces a run's recording or results. Continue that run "
                           "with --resume " + ShellQuoted(dir) + ", or choose a new --out "
                           "folder.");
    }
  }
}

RunFolder OpenRunFolder(RunKind kind, const std::string& out_dir, const std::string& resume_dir,
                        const Recipe& recipe, const Plan& plan, const std::string& recipe_text,
                        std::ostream& err) {
  RunFolder folder;
  if (resume_dir.empty()) {
    folder.dir = out_dir.empty() ? recipe.output_dir + "-" + Timestamp() : out_dir;
    RefuseOtherResults(folder.dir, kind);
    CreateRunFolder(folder.dir);
  } else {
    folder.dir = resume_dir;
    ResumeExpectation expected =
        ResumeExpectationOf(recipe, recipe_text, yaml_fields::ReadFile(recipe.rig_path));
    expected.results = ResultsOf(kind, recipe);
    const ResumeState state = CheckResume(folder.dir, CommandName(kind), expected);
    if (state.complete) {
      err << "Resuming " << folder.dir << ": the recording is complete but "
          << state.missing_result << " is missing (the run was stopped while processing); "
          << "processing it now.\n";
      folder.record = false;
    } else {
      folder.done_ids = state.complete_brackets;
      err << "Resuming " << folder.dir << ": " << folder.done_ids.size() << " of "
          << plan.poses.size() << " brackets already recorded.\n";
    }
  }
  // One run per folder, for the whole run (recording and processing).
  folder.lock = std::make_unique<RunFolderLock>(folder.dir, CommandName(kind));
  return folder;
}

// A free station.N.log name for the log of an earlier session.
std::string KeepEarlierLog(const std::string& dir) {
  const std::string current = dir + "/station.log";
  if (!fs::exists(current)) return "";
  for (int n = 1;; ++n) {
    std::string kept = dir + "/station." + std::to_string(n) + ".log";
    if (!fs::exists(kept)) {
      fs::rename(current, kept);
      return kept;
    }
  }
}

std::string CompleteResultsAdvice(RunKind kind, const std::string& recipe_path,
                                  const std::string& model_path, const std::string& dir) {
  return "complete the results with: " +
         ResumeCommand(CommandName(kind), recipe_path, model_path, dir);
}

}  // namespace irdist
