#pragma once
// The project's error base class and its CHECK macro (the COLMAP pattern, throwing instead of
// aborting: library code never exits). Every module may include base/; typed errors (CameraError,
// LinkError, InputError, ...) derive from irdist::Error.

#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace irdist {

// Base of every error irdist throws on purpose. what() reads as one self-contained message:
// what went wrong, where, and what to do about it.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A broken precondition: a bug in the caller, reported with file and line.
class CheckError : public Error {
 public:
  using Error::Error;
};

namespace internal {

template <typename... Args>
std::string Concat(Args&&... args) {
  std::ostringstream out;
  (out << ... << std::forward<Args>(args));
  return out.str();
}

[[noreturn]] inline void ThrowCheck(const char* file, int line, const char* condition,
                                    const std::string& message) {
  std::ostringstream out;
  out << file << ":" << line << ": check failed: " << condition;
  if (!message.empty()) out << ": " << message;
  throw CheckError(out.str());
}

}  // namespace internal
}  // namespace irdist

// IRDIST_CHECK(cond, "message", value, ...): throws irdist::CheckError naming file, line and cond.
#define IRDIST_CHECK(condition, ...)                                                  \
  do {                                                                                \
    if (!(condition)) {                                                               \
      ::irdist::internal::ThrowCheck(__FILE__, __LINE__, #condition,                  \
                                     ::irdist::internal::Concat("" __VA_OPT__(, ) __VA_ARGS__)); \
    }                                                                                 \
  } while (false)
