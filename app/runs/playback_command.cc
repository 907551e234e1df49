#include "app/runs/playback_command.h"

#include <cmath>
#include <optional>
#include <ostream>
#include <utility>

#include "acquisition/recording_reader.h"
#include "app/display/show.h"
#include "app/inputs/provenance.h"
#include "app/processing/bracket_estimates.h"
#include "app/processing/frame_features.h"
#include "app/runs/offline_inputs.h"
#include "app/runs/resume.h"
#include "app/runs/run_results.h"
#include "estimator/model_file.h"

namespace irdist {

namespace {

bool HasGroundTruth(const std::vector<EstimateRow>& rows) {
  for (const EstimateRow& row : rows) {
    if (std::isfinite(row.true_d_mm)) return true;
  }
  return false;
}

// estimates.csv of a recording's brackets, and with ground truth summary.yaml and report/; the
// recording's warnings on io.err.
std::vector<EstimateRow> WritePlaybackEstimates(const RecordingReader& reader,
                                                const FeatureMap& features,
                                                const CalibrationModel& model,
                                                const PlaybackArgs& args,
                                                const std::string& out_dir, CommandIo io) {
  RecordingEstimates estimates = EstimateRecording(reader, features, model);
  for (const std::string& warning : estimates.warnings) io.err << warning << "\n";
  if (HasGroundTruth(estimates.rows)) {
    WriteValidation(out_dir, estimates.rows,
                    {{"recipe", reader.header().recipe_path},
                     {"model", args.model},
                     {"recording", args.recording}},
                    io.out);
  } else {  // a recording of `irdist measure`: no ground truth to summarise against
    WriteEstimatesCsv(out_dir + "/estimates.csv", estimates.rows);
    io.out << "Estimates: " << out_dir << "/estimates.csv (no ground truth)\n";
  }
  return std::move(estimates.rows);
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
    if (model) rows = WritePlaybackEstimates(reader, features, *model, args, out_dir, io);
  });
  if (args.show) ShowPlayback(reader, features, rows);
}

}  // namespace irdist
