#pragma once
// What the offline commands that write results (fit, playback) check first: where their results
// go by default, that none is replaced unasked, and that no live process is writing the recording.

#include <string>
#include <vector>

namespace irdist {

// The folder that holds `dir` ("." for a bare name): a recording's run folder, a model's folder.
std::string ParentOf(const std::string& dir);

// Results are never replaced without being asked: throws RunFolderError when one of `names`
// exists in `dir` (unless `force`); one that is a symbolic link is refused even with --force
// (never written through). `command` names the command in the message.
void RefuseExistingResults(const std::string& dir, const std::vector<std::string>& names,
                           bool force, const std::string& command);

// A recording a live process is writing is read once that run has ended, never as a dead one:
// throws RunFolderError naming the writer's process.
void RefuseLiveWriter(const std::string& recording, const std::string& command);

}  // namespace irdist
