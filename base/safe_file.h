#pragma once
// Writing files that nobody else can redirect: a file is created new (O_CREAT | O_EXCL |
// O_NOFOLLOW, so a planted name or symbolic link is never followed), a whole-file write goes to a
// temporary name that is unlinked first and renamed into place, and a private folder is checked
// to be the user's own. The writing side of base/regular_file.h. Functions return false and say
// why; the caller throws its module's typed error naming the file and the fix.

#include <sys/types.h>

#include <string>
#include <string_view>

namespace irdist {

// Creates `path`, which must not exist (a symbolic link there counts as existing): returns the
// open fd (O_WRONLY, close-on-exec) or -1 and `why`.
int CreateNewFile(const std::string& path, mode_t mode, std::string* why);

// Writes `bytes` to `path` and syncs it. A stale `path` (a leftover temporary file, or a link
// someone planted) is unlinked first, never followed or opened; then the file is created new.
// On failure the file is removed.
bool WriteNewFileSynced(const std::string& path, std::string_view bytes, mode_t mode,
                        std::string* why);

// `path` replaced whole: written to path + ".tmp" (WriteNewFileSynced), renamed onto `path`, the
// folder synced. After a crash `path` is the old file or the new one. Refused (nothing written)
// when `path` is a symbolic link.
bool WriteFileAtomically(const std::string& path, std::string_view bytes, mode_t mode,
                         std::string* why);

// fsync of a folder, so that a rename in it survives a crash (a file system that cannot sync a
// folder counts as synced).
bool SyncFolder(const std::string& dir, std::string* why);

// Whether `path` is a symbolic link (lstat; false when it does not exist).
bool IsSymlink(const std::string& path);

// `dir` as a private folder of the calling user: created 0700 when missing, then checked to be a
// folder (not a symbolic link), owned by the user and closed to group and others (no bit of 077).
bool EnsurePrivateDir(const std::string& dir, std::string* why);

}  // namespace irdist
