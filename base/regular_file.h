#pragma once
// Reading an input file without ever blocking or following a link out of its place: a FIFO, a
// device, a folder or a symbolic link is refused, and so is a file over a size limit. Every
// reader of a recipe, rig file, model file or recording goes through here. Writing one whole or
// not at all: WriteFileAtomically (base/safe_file.h).

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <string>

namespace irdist {

// Reads `path` whole into `bytes`. Returns false and says why in `why` when the file is not a
// regular file, is larger than `max_bytes` or cannot be read.
inline bool ReadRegularFile(const std::string& path, std::int64_t max_bytes, std::string* bytes,
                            std::string* why) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    *why = errno == ELOOP ? "is a symbolic link" : std::string("cannot be opened: ") +
                                                       std::strerror(errno);
    return false;
  }
  struct stat st {};
  bool ok = ::fstat(fd, &st) == 0;
  if (!ok) *why = std::string("cannot be examined: ") + std::strerror(errno);
  if (ok && !S_ISREG(st.st_mode)) {
    *why = "is not a regular file (a FIFO, device or folder)";
    ok = false;
  } else if (ok && st.st_size > max_bytes) {
    *why = "is " + std::to_string(st.st_size) + " bytes, over the limit of " +
           std::to_string(max_bytes);
    ok = false;
  }
  if (ok) bytes->resize(static_cast<size_t>(st.st_size));
  size_t got = 0;
  while (ok && got < bytes->size()) {
    const ssize_t n = ::read(fd, bytes->data() + got, bytes->size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      *why = std::string("cannot be read: ") + (n < 0 ? std::strerror(errno) : "shorter than its size");
      ok = false;
    } else {
      got += static_cast<size_t>(n);
    }
  }
  ::close(fd);
  return ok;
}

// Text files irdist reads (recipes, rig files, model files, recording.yaml, frames.csv).
constexpr std::int64_t kMaxInputTextBytes = std::int64_t{1} << 30;

}  // namespace irdist
