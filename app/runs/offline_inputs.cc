#include "app/runs/offline_inputs.h"

#include <filesystem>

#include "acquisition/recording_writer.h"
#include "app/inputs/errors.h"

namespace irdist {

namespace fs = std::filesystem;

std::string ParentOf(const std::string& dir) {
  fs::path path = fs::path(dir).lexically_normal();
  if (path.filename().empty()) path = path.parent_path();
  const fs::path parent = path.parent_path();
  return parent.empty() ? "." : parent.string();
}

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

void RefuseLiveWriter(const std::string& recording, const std::string& command) {
  const std::string writer = LiveWriterOf(recording);
  if (writer.empty()) return;
  throw RunFolderError(recording + " is being written by process " + writer + " (a live run "
                       "holds its writer.lock); irdist " + command + " reads it once that run "
                       "has ended (or stop it and resume it).");
}

}  // namespace irdist
