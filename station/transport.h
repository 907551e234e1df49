#pragma once
// The seam between the station client and the wire: a line-oriented transport. The real one is a
// serial port (station/serial_transport.h); tests put the station emulator behind a pty.

#include <chrono>
#include <string>
#include <string_view>
#include <vector>

#include "base/check.h"

namespace irdist {

// A link failure: the port cannot be opened or written, or no (valid) reply came in time.
// what() reads "<what> (<where>); <fix>".
class LinkError : public Error {
 public:
  LinkError(std::string what, std::string where, std::string fix)
      : Error(what + " (" + where + "); " + fix),
        what_(std::move(what)),
        where_(std::move(where)),
        fix_(std::move(fix)) {}
  const std::string& failure() const { return what_; }
  const std::string& where() const { return where_; }
  const std::string& fix() const { return fix_; }

 private:
  std::string what_;
  std::string where_;
  std::string fix_;
};

class Transport {
 public:
  virtual ~Transport() = default;
  // Sends `line` followed by the transport's line end (\r\n unless configured). Throws LinkError.
  virtual void WriteLine(std::string_view line) = 0;
  // The next received line without its line end ('\r' dropped). Throws LinkError if no complete
  // line arrives within `deadline` (the partial line is kept for the next call).
  virtual std::string ReadLine(std::chrono::milliseconds deadline) = 0;
  // Drops any bytes already received and not yet returned (resynchronisation).
  virtual void Flush() {}
  // The complete lines already received and not yet returned, without waiting (an unsolicited
  // report such as the PTU's limit hit, or late replies); whatever is left (a partial line) is
  // dropped as by Flush(). The default only flushes.
  virtual std::vector<std::string> ReadPending() {
    Flush();
    return {};
  }
};

}  // namespace irdist
