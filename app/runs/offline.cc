#include "app/runs/offline.h"

#include <cmath>
#include <filesystem>
#include <optional>
#include <ostream>
#include <set>

#include "acquisition/recording_check.h"
#include "acquisition/recording_reader.h"
#include "acquisition/recording_writer.h"
#include "app/display/show.h"
#include "app/inputs/provenance.h"
#include "app/processing/bracket_estimates.h"
#include "app/processing/frame_features.h"
#include "app/processing/recording_fit.h"
#include "app/processing/scene_check.h"
#include "app/reports/calibration_report.h"
#include "app/runs/resume.h"
#include "app/runs/run_results.h"
#include "estimator/model_file.h"

namespace irdist {

namespace fs = std::filesystem;

namespace {

// Results are never replaced without being asked: refuses when one of `names` exists in `dir`;
// one that is a symbolic link is refused even with --force (never written through).
void RefuseExistingResults(const std::string& dir, const std::vector<std::string>& names,
                           bool force, const std::string& command) {
  for (const std::string& name : names) {
    const fs::path path = fs::path(dir) / name;
    std::error_code ec;
    if (fs::is_symlink(fs::symlink_status(path, ec))) {
      throw RunFolderError(path.string() + " is a symbolic link: irdist " + command +
                           " never writes through a link. Remove it, or give a new folder with "
                           "--out.");
    }
    if (!force && fs::exists(path, ec)) {
      throw RunFolderError(path.string() + " exists: irdist " + command +
                           " does not replace results. Give a new folder with --out, or pass "
                           "--force to replace them.");
    }
  }
}

std::string ParentOf(const std::string& dir) {
  fs::path path = fs::path(dir).lexically_normal();
  if (path.filename().empty()) path = path.parent_path();
  const fs::path parent = path.parent_path();
  return parent.empty() ? "." : parent.string();
}

// A recording a live process is writing is read once that run has ended, never as a dead one.
void RefuseLiveWriter(const std::string& recording, const std::string& command) {
  const std::string writer = LiveWriterOf(recording);
  if (writer.empty()) return;
  throw RunFolderError(recording + " is being written by process " + writer + " (a live run "
                       "holds its writer.lock); irdist " + command + " reads it once that run "
                       "has ended (or stop it and resume it).");
}

}  // namespace

void RunFit(const FitArgs& args, CommandIo io) {
  RefuseLiveWriter(args.recording, "fit");
  RequireCleanRecording(args.recording);
  const RecordingReader reader(args.recording);
  if (!reader.IsComplete()) {
    io.err << "warning: " << args.recording << " is " << CompletionName(reader.completion())
           << "; fitting its complete brackets.\n";
  }
  const std::string model_path =
      args.out.empty() ? ParentOf(args.recording) + "/model.yaml" : args.out;
  const std::string out_dir = ParentOf(model_path);
  RefuseExistingResults(out_dir, {fs::path(model_path).filename().string(), "features.csv", "report"},
                        args.force, "fit");
  RefuseLiveRun(out_dir, "fit");
  CreateRunFolder(out_dir);
  const std::string again = "irdist fit " + ShellQuoted(args.recording) +
                            (args.out.empty() ? "" : " --out " + ShellQuoted(args.out)) +
                            (args.recover_response ? " --recover-response" : "") +
                            (args.keep_model ? " --keep-model" : "") + " --force";
  WriteResults("complete the results with: " + again, [&] {
    const FeatureOptions options =
        FitFeatureOptions(reader, FeatureOptions{}, args.recover_response, io.out);
    const FeatureMap features = RecordingFeatures(reader, options);
    WriteFeaturesCsv(out_dir + "/features.csv", reader.rows(), features);
    FitRecording(reader, features, options, model_path,
                 CalibrationReportDrawerInto(out_dir + "/report", reader.dir()), io.out,
                 args.keep_model);
  });
}

namespace {

bool HasGroundTruth(const std::vector<EstimateRow>& rows) {
  for (const EstimateRow& row : rows) {
    if (std::isfinite(row.true_d_mm)) return true;
  }
  return false;
}

// estimates.csv of a recording's brackets, and with ground truth summary.yaml and report/.
std::vector<EstimateRow> WritePlaybackEstimates(const RecordingReader& reader,
                                                const FeatureMap& features,
                                                const CalibrationModel& model,
                                                const PlaybackArgs& args,
                                                const std::string& out_dir, std::ostream& out) {
  std::vector<EstimateRow> rows = EstimateRecording(reader, features, model);
  if (HasGroundTruth(rows)) {
    WriteValidation(out_dir, rows,
                    {{"recipe", reader.header().recipe_path},
                     {"model", args.model},
                     {"recording", args.recording}},
                    out);
  } else {  // a recording of `irdist measure`: no ground truth to summarise against
    WriteEstimatesCsv(out_dir + "/estimates.csv", rows);
    out << "Estimates: " << out_dir << "/estimates.csv (no ground truth)\n";
  }
  return rows;
}

// The playback command that replaces what a failed playback wrote.
std::string PlaybackAgain(const PlaybackArgs& args) {
  std::string line = "irdist playback " + ShellQuoted(args.recording);
  if (!args.model.empty()) line += " --model " + ShellQuoted(args.model);
  if (!args.out_dir.empty()) line += " --out " + ShellQuoted(args.out_dir);
  if (args.allow_model_mismatch) line += " --allow-model-mismatch";
  return line + " --force";
}

}  // namespace

void RunPlayback(const PlaybackArgs& args, CommandIo io) {
  RefuseLiveWriter(args.recording, "playback");
  RequireCleanRecording(args.recording);
  const RecordingReader reader(args.recording);
  std::optional<CalibrationModel> model;
  if (!args.model.empty()) {
    model = LoadModel(args.model);
    std::string warning;
    CheckModelProvenance(model->provenance, args.model, ProvenanceOfRecording(reader),
                         "the recording " + args.recording, args.allow_model_mismatch, &warning);
    if (!warning.empty()) io.err << warning << "\n";
    for (const std::string& w : ModelFitnessWarnings(*model, args.model)) io.err << w << "\n";
  }
  const FeatureOptions options = model ? model->features : FeatureOptions{};
  const std::string out_dir = args.out_dir.empty() ? ParentOf(args.recording) : args.out_dir;
  RefuseExistingResults(out_dir, {"features.csv", "estimates.csv", "summary.yaml", "report"},
                        args.force, "playback");
  CreateRunFolder(out_dir);
  FeatureMap features;
  std::vector<EstimateRow> rows;
  WriteResults("complete the results with: " + PlaybackAgain(args), [&] {
    features = RecordingFeatures(reader, options, {}, model ? BlobFitModelOf(*model) : nullptr);
    WriteFeaturesCsv(out_dir + "/features.csv", reader.rows(), features);
    io.out << "Features: " << out_dir << "/features.csv (" << features.size() << " frames)\n";
    if (model) rows = WritePlaybackEstimates(reader, features, *model, args, out_dir, io.out);
  });
  if (args.show) ShowPlayback(reader, features, rows);
}

namespace {

// `irdist check FILE`: an estimates.csv (irdist measure's, also after a crash): every row read, a
// torn last line dropped with a note.
void CheckEstimatesFile(const std::string& path, std::ostream& out) {
  std::string note;
  std::vector<EstimateRow> rows;
  try {
    rows = ReadEstimatesCsv(path, &note);
  } catch (const EstimatesFileError& e) {
    throw CheckFailedError(e.what());
  }
  std::set<int> brackets;
  for (const EstimateRow& row : rows) brackets.insert(row.bracket);
  out << path << ": " << rows.size() << " estimate rows of " << brackets.size() << " brackets";
  if (!brackets.empty()) out << " (" << *brackets.begin() << " to " << *brackets.rbegin() << ")";
  out << ", readable\n";
  if (!note.empty()) out << "note: " << note << "\n";
}

}  // namespace

void RunCheck(const CheckArgs& args, CommandIo io) {
  if (fs::is_regular_file(args.recording)) {
    CheckEstimatesFile(args.recording, io.out);
    return;
  }
  const RecordingCheck check = CheckRecording(args.recording);
  io.out << check.BriefReport() << "\n";
  if (!check.ok()) {
    throw CheckFailedError(args.recording + ": " + std::to_string(check.errors.size()) +
                           " error(s) in the recording (listed above).");
  }
  // The images, once the structure holds: what the scene shows (a report, never an error).
  io.out << CheckScene(RecordingReader(args.recording)).BriefReport() << "\n";
}

}  // namespace irdist