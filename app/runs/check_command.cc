#include "app/runs/check_command.h"

#include <filesystem>
#include <ostream>
#include <set>

#include "acquisition/recording_check.h"
#include "acquisition/recording_reader.h"
#include "app/processing/estimates_csv.h"
#include "app/processing/scene_check.h"

namespace irdist {

namespace fs = std::filesystem;

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
