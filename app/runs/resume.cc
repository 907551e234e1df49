#include "app/runs/resume.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <map>
#include <sstream>

#include "acquisition/recording_reader.h"
#include "app/inputs/errors.h"
#include "app/inputs/recipe.h"
#include "app/runs/run_results.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

// "<pid> <command>" from run.lock; {"", ""} when the folder has none.
std::pair<std::string, std::string> LockHolder(int fd) {
  char text[128] = {0};
  const ssize_t n = ::pread(fd, text, sizeof(text) - 1, 0);
  std::istringstream in(std::string(text, n > 0 ? static_cast<size_t>(n) : 0));
  std::pair<std::string, std::string> holder;
  in >> holder.first >> holder.second;
  return holder;
}

std::string CommandOfFolder(const std::string& run_dir) {
  const std::string path = (fs::path(run_dir) / "run.lock").string();
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return "";  // a folder from before run.lock: no command recorded
  const std::string command = LockHolder(fd).second;
  ::close(fd);
  return command;
}

void CheckSameText(const std::string& what, const std::string& path, const std::string& used,
                   const std::string& recorded, const std::string& recording_dir) {
  if (used == recorded) return;
  throw RecipeError(path, 0, 0,
                    "differs from the " + what + " recorded in " + recording_dir + " (" +
                        std::to_string(recorded.size()) + " bytes there, " +
                        std::to_string(used.size()) + " here); resume with the " + what +
                        " the run started with (a copy is in " + recording_dir + "/" +
                        (what == "recipe" ? "recipe.yaml" : "rig.yaml") + ").");
}

// The camera settings the recording was made with (read back from the camera).
void CheckCameraSettings(const RecordingHeader& header, const ResumeExpectation& expected,
                         const std::string& recording_dir) {
  std::string differs;
  if (header.pixel_format != expected.pixel_format) {
    differs = "pixel format " + expected.pixel_format + " (recorded: " + header.pixel_format + ")";
  }
  const std::map<std::string, int> roi = {{"OffsetX", expected.roi_offset_x},
                                          {"OffsetY", expected.roi_offset_y},
                                          {"Width", expected.roi_width},
                                          {"Height", expected.roi_height}};
  for (const auto& [feature, value] : roi) {
    const auto recorded = header.camera_features.find(feature);
    if (expected.roi_width <= 0 || recorded == header.camera_features.end()) continue;
    if (recorded->second != std::to_string(value)) {
      differs += (differs.empty() ? "" : ", ") + feature + " " + std::to_string(value) +
                 " (recorded: " + recorded->second + ")";
    }
  }
  if (!differs.empty()) {
    throw RecipeError(expected.rig_path, 0, 0,
                      "the camera settings differ from the recording in " + recording_dir + ": " +
                          differs + "; a recording holds one kind of frame. Resume with the rig "
                          "file the run started with, or start a new run.");
  }
}

// The parts of a run folder irdist writes or reads: none may be a symbolic link.
void RefuseLinkedRunParts(const std::string& run_dir) {
  for (const char* part : {"recording", "recording/frames", "recording/recording.yaml",
                           "recording/frames.csv", "model.yaml", "features.csv", "estimates.csv",
                           "summary.yaml", "report", "station.log", "run.lock"}) {
    const fs::path path = fs::path(run_dir) / part;
    std::error_code ec;
    if (fs::is_symlink(fs::symlink_status(path, ec))) {
      throw RunFolderError(path.string() + " is a symbolic link; a resume never writes through "
                           "a link. Replace it with the real file or folder (or remove it), or "
                           "start a new run.");
    }
  }
}

// `made_by` is the command that made the folder (run.lock's, or recording.yaml's command), ""
// when not recorded.
void RefuseOtherCommand(const std::string& run_dir, const std::string& command,
                        const std::string& made_by) {
  if (made_by.empty() || made_by == command) return;
  throw RunFolderError(run_dir + " is the folder of an `irdist " + made_by + "` run; `irdist " +
                       command + " --resume` continues only its own runs. Resume it with "
                       "`irdist " + made_by + "`, or start a new run.");
}

// The first of `results` missing from `run_dir` ("" when every one is there).
std::string FirstMissing(const std::string& run_dir, const std::vector<std::string>& results) {
  for (const std::string& name : results) {
    std::error_code ec;
    if (!fs::exists(fs::path(run_dir) / name, ec)) return name;
  }
  return "";
}

}  // namespace

void RefuseLiveRun(const std::string& run_dir, const std::string& command) {
  const std::string path = (fs::path(run_dir) / "run.lock").string();
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return;  // no run ever locked the folder (or it is gone)
  const bool live = ::flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK;
  const auto holder = LockHolder(fd);
  ::close(fd);
  if (live) {
    throw RunFolderError(run_dir + " is in use by a live run (irdist " + holder.second +
                         ", process " + holder.first + "); irdist " + command +
                         " would write into it. Wait for that run to end, or give another "
                         "folder with --out.");
  }
}

void CreateRunFolder(const std::string& run_dir) {
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(run_dir, ec);
  if (fs::exists(status) && !fs::is_directory(status)) {
    throw RunFolderError(run_dir + " exists and is not a folder (" +
                         (fs::is_symlink(status) ? "a symbolic link" : "a file") +
                         "); a run writes its recording and results into a folder of its own. "
                         "Give a new folder (or an existing one) with --out.");
  }
  fs::create_directories(run_dir, ec);
  if (ec) {
    throw RunFolderError("cannot create the run folder " + run_dir + ": " + ec.message() +
                         "; give a folder you may write in with --out.");
  }
}

RunFolderLock::RunFolderLock(const std::string& run_dir, const std::string& command) {
  CreateRunFolder(run_dir);
  const std::string path = (fs::path(run_dir) / "run.lock").string();
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd_ < 0) throw RunFolderError("cannot create " + path + ": " + std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int saved = errno;
    const auto holder = LockHolder(fd_);
    ::close(fd_);
    if (saved != EWOULDBLOCK) {
      throw RunFolderError("cannot lock " + path + ": " + std::strerror(saved));
    }
    throw RunFolderError(run_dir + " is in use by a live run (irdist " + holder.second +
                         ", process " + holder.first + "); wait for it to end or stop it, or "
                         "choose another --out folder.");
  }
  const std::string text = std::to_string(::getpid()) + " " + command + "\n";
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, text.data(), text.size(), 0) < 0) {
    // The lock holds without the note; a refused run then names no pid.
  }
}

RunFolderLock::~RunFolderLock() {
  if (fd_ >= 0) ::close(fd_);
}

ResumeExpectation ResumeExpectationOf(const Recipe& recipe, const std::string& recipe_text,
                                      const std::string& rig_text) {
  ResumeExpectation expected;
  expected.recipe_path = recipe.path;
  expected.recipe_text = recipe_text;
  expected.rig_path = recipe.rig_path;
  expected.rig_text = rig_text;
  expected.pixel_format = recipe.rig.camera.pixel_format;
  expected.roi_offset_x = recipe.rig.camera.roi_offset_x;
  expected.roi_offset_y = recipe.rig.camera.roi_offset_y;
  expected.roi_width = recipe.rig.camera.roi_width;
  expected.roi_height = recipe.rig.camera.roi_height;
  return expected;
}

ResumeState CheckResume(const std::string& run_dir, const std::string& command,
                        const ResumeExpectation& expected) {
  const std::string recording_dir = run_dir + "/recording";
  RefuseLinkedRunParts(run_dir);
  if (!fs::exists(recording_dir + "/recording.yaml")) {
    throw RunFolderError(recording_dir + ": no recording to resume (recording.yaml missing); "
                         "pass the folder of a cut run to --resume.");
  }
  RefuseOtherCommand(run_dir, command, CommandOfFolder(run_dir));
  // What check finds is refused before anything is appended: a resume hashes frames.csv again
  // at its close and must not vouch for rows or frames edited since.
  RequireCleanRecording(recording_dir, "it is not resumed (a resume would append to it and "
                                       "close it with a new hash over the edit)");
  const RecordingReader reader(recording_dir);
  RefuseOtherCommand(run_dir, command, reader.header().run_command);
  CheckSameText("recipe", expected.recipe_path, expected.recipe_text, reader.header().recipe_text,
                recording_dir);
  CheckSameText("rig file", expected.rig_path, expected.rig_text, reader.header().rig_text,
                recording_dir);
  CheckCameraSettings(reader.header(), expected, recording_dir);
  ResumeState state;
  if (reader.IsComplete()) {
    state.missing_result = FirstMissing(run_dir, expected.results);
    if (state.missing_result.empty()) {
      throw RunFolderError(recording_dir + " is complete and its results are in " + run_dir +
                           ": there is nothing to resume, and they stand. Start a new run with "
                           "--out.");
    }
    state.complete = true;
  }
  state.complete_brackets = reader.CompleteBracketIds();
  return state;
}

std::string ResumeCommand(const std::string& command, const std::string& recipe_path,
                          const std::string& model_path, const std::string& run_dir) {
  std::string line = "irdist " + command + " " + ShellQuoted(recipe_path);
  if (!model_path.empty()) line += " --model " + ShellQuoted(model_path);
  return line + " --resume " + ShellQuoted(run_dir);
}

std::string ShellQuoted(const std::string& word) {
  static const char kPlain[] =
      "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_./:=,+@%-";
  if (!word.empty() && word.find_first_not_of(kPlain) == std::string::npos) return word;
  std::string quoted = "'";
  for (const char c : word) {
    if (c == '\'') {
      quoted += "'\\''";
    } else {
      quoted += c;
    }
  }
  return quoted + "'";
}

}  // namespace irdist
