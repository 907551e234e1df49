#pragma once
// The conformance suite of docs/station-protocol.md: a board (or an emulator) is exercised over
// its serial link and each rule of the document is checked (framing, checksum, errors and their
// queue, states, e-stop, homing, moves and soft limits, the trigger and the retransmission
// cache). `irdist station-test PORT` prints the table. The suite moves the axes and switches the
// IRED: run it with the IRED's path clear; it ends with the IRED off.

#include <chrono>
#include <string>
#include <vector>

#include "station/transport.h"

namespace irdist {

struct ConformanceOptions {
  std::chrono::milliseconds reply_timeout{500};
  std::chrono::milliseconds move_timeout{120000};
  std::chrono::milliseconds poll_period{10};
  // The first problem, naming the field, in *why (empty when valid); those of ClientOptions.
  bool IsValid(std::string* why) const;
};

struct ConformanceCheck {
  std::string name;     // "checksum", "estop-current-off", ...
  std::string section;  // of docs/station-protocol.md
  bool passed = false;
  std::string detail;   // what was seen when it failed
};

struct ConformanceReport {
  std::vector<ConformanceCheck> checks;
  bool Passed() const { return Failures() == 0; }
  int Failures() const;
  std::string Table() const;  // one line per check: PASS/FAIL, name, section, detail
};

// Runs every check in order (each failure is recorded, the suite continues). Throws LinkError
// only when the board does not answer at all.
ConformanceReport RunConformance(Transport& transport, const ConformanceOptions& options);

}  // namespace irdist
