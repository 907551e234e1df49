#pragma once
// The station protocol's text as the station model and its emulator speak it
// (docs/station-protocol.md section 5): its integers, error codes and their messages, a command
// parsed into its header and parameters. Included by sim/station_model.h.

#include <string>
#include <vector>

namespace irdist::sim {

// The protocol's integer syntax: optional sign, 1-12 characters, decimal digits only.
bool ParseProtocolInt(const std::string& text, long long* value);

// One entry of the error queue (SYST:ERR?).
struct CommandError {
  int code;
  std::string message;
};

// One parsed command: its upper-case header, its comma-separated parameters and the time.
struct StationRequest {
  std::string header;
  std::vector<std::string> args;
  double now = 0.0;
  // Exactly n integer parameters into *out; 0, or the error code (-109, -108, -104).
  int Ints(std::size_t n, std::vector<long long>* out) const;
  int NoArgs() const { return args.empty() ? 0 : -108; }
  // An axis name (SLIDE, PAN, TILT: *axis 0, 1, 2) then exactly n integer parameters into *out;
  // 0, or the error code (-109, -108, -104).
  int AxisAndInts(std::size_t n, int* axis, std::vector<long long>* out) const;
};

// The code with its message ("Execution error" for a code the table does not know).
CommandError ErrorFor(int code);
// "a, b,c" -> {"a", "b", "c"} (spaces dropped); "" -> {}.
std::vector<std::string> SplitCommas(const std::string& text);
std::string Upper(std::string s);
// A value in the protocol's 0.01 units; a list of them "a,b,c".
long long Centi(double v);
std::string CentiList(const std::vector<double>& values);

}  // namespace irdist::sim
