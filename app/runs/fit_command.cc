#include "app/runs/fit_command.h"

#include <filesystem>
#include <ostream>

#include "acquisition/recording_reader.h"
#include "app/processing/frame_features.h"
#include "app/processing/recording_fit.h"
#include "app/reports/calibration_report.h"
#include "app/runs/offline_inputs.h"
#include "app/runs/resume.h"
#include "app/runs/run_results.h"

namespace irdist {

namespace fs = std::filesystem;

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
  RefuseExistingResults(out_dir,
                        {fs::path(model_path).filename().string(), "features.csv", "report"},
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

}  // namespace irdist
