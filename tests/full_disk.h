#pragma once
// A full disk for a test: while a FullDisk lives, every file write beyond `bytes` fails (EFBIG,
// RLIMIT_FSIZE with SIGXFSZ ignored) as on a disk with no space left; the limit is restored after.

#include <signal.h>
#include <sys/resource.h>

#include <gtest/gtest.h>

namespace irdist::testing {

class FullDisk {
 public:
  explicit FullDisk(rlim_t bytes = 0) {
    ok_ = ::getrlimit(RLIMIT_FSIZE, &saved_) == 0;
    ::signal(SIGXFSZ, SIG_IGN);
    struct rlimit full = saved_;
    full.rlim_cur = bytes;
    ok_ = ok_ && ::setrlimit(RLIMIT_FSIZE, &full) == 0;
    EXPECT_TRUE(ok_) << "cannot limit the file size";
  }
  ~FullDisk() {
    if (ok_) {
      EXPECT_EQ(::setrlimit(RLIMIT_FSIZE, &saved_), 0);
    }
  }
  FullDisk(const FullDisk&) = delete;
  FullDisk& operator=(const FullDisk&) = delete;

 private:
  struct rlimit saved_ {};
  bool ok_ = false;
};

}  // namespace irdist::testing
