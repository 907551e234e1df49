#include "base/safe_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace irdist {
namespace {

std::string Errno() { return std::strerror(errno); }

std::string FolderOf(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

// Writes all of `bytes` to `fd`, retrying short and interrupted writes.
bool WriteAll(int fd, std::string_view bytes) {
  const char* p = bytes.data();
  std::size_t left = bytes.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace

int CreateNewFile(const std::string& path, mode_t mode, std::string* why) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, mode);
  if (fd < 0) {
    *why = errno == EEXIST ? "exists already (or is a symbolic link)"
                           : "cannot be created: " + Errno();
  }
  return fd;
}

bool WriteNewFileSynced(const std::string& path, std::string_view bytes, mode_t mode,
                        std::string* why) {
  if (::unlink(path.c_str()) != 0 && errno != ENOENT) {
    *why = "a stale file there cannot be removed: " + Errno();
    return false;
  }
  const int fd = CreateNewFile(path, mode, why);
  if (fd < 0) return false;
  const bool ok = WriteAll(fd, bytes) && ::fsync(fd) == 0;
  const int saved = errno;
  ::close(fd);
  if (!ok) {
    ::unlink(path.c_str());
    *why = std::string("cannot be written: ") + std::strerror(saved) + " (is the disk full?)";
  }
  return ok;
}

bool SyncFolder(const std::string& dir, std::string* why) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) {
    *why = "folder " + dir + " cannot be opened to sync it: " + Errno();
    return false;
  }
  const bool ok = ::fsync(fd) == 0 || errno == EINVAL;  // EINVAL: the file system cannot sync
  const int saved = errno;
  ::close(fd);
  if (!ok) *why = "folder " + dir + " cannot be synced: " + std::strerror(saved);
  return ok;
}

bool WriteFileAtomically(const std::string& path, std::string_view bytes, mode_t mode,
                         std::string* why) {
  if (IsSymlink(path)) {
    *why = "is a symbolic link; irdist does not write through links (remove it)";
    return false;
  }
  const std::string tmp = path + ".tmp";
  if (!WriteNewFileSynced(tmp, bytes, mode, why)) {
    *why = tmp + " " + *why;
    return false;
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    *why = "cannot be replaced by " + tmp + ": " + Errno();
    ::unlink(tmp.c_str());
    return false;
  }
  return SyncFolder(FolderOf(path), why);
}

bool IsSymlink(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0 && S_ISLNK(st.st_mode);
}

bool EnsurePrivateDir(const std::string& dir, std::string* why) {
  if (::mkdir(dir.c_str(), 0700) != 0 && errno != EEXIST) {
    *why = "cannot be created: " + Errno();
    return false;
  }
  struct stat st {};
  if (::lstat(dir.c_str(), &st) != 0) {
    *why = "cannot be examined: " + Errno();
    return false;
  }
  if (S_ISLNK(st.st_mode) || !S_ISDIR(st.st_mode)) {
    *why = S_ISLNK(st.st_mode) ? "is a symbolic link, not a private folder"
                               : "is not a folder";
  } else if (st.st_uid != ::geteuid()) {
    *why = "belongs to user id " + std::to_string(st.st_uid) + ", not to you (" +
           std::to_string(::geteuid()) + ")";
  } else if ((st.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof(mode), "%03o", static_cast<unsigned>(st.st_mode & 0777));
    *why = std::string("has mode ") + mode + "; a private folder is 700 (chmod 700 it)";
  } else {
    return true;
  }
  return false;
}

}  // namespace irdist
