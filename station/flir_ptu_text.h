#pragma once
// The FLIR PTU's reply text, read by station/flir_ptu.cc (station-internal): the unit's own
// limit-hit report, the commands about speed, the numbers in a reply, and what a resetting
// unit prints (its banner, "Initializing...", the echo of commands) before it answers again.

#include <string>

namespace irdist::ptu_text {

// "!P" or "!T" alone on a line (manual: the axis hit a limit and lost synchrony).
bool IsLimitHit(const std::string& line);

// Speed, acceleration and speed-bound commands (PS, TA, PU...): a refusal is about speed.
bool IsRateCommand(const std::string& command);

// The first number among the words of `text` ("* 22", "* Current Pan position is 22").
bool FirstNumber(const std::string& text, double* value);

// A line with "PAN-TILT" or "PTU" in it, any case (a version answer, the power-up banner).
bool NamesAPanTiltUnit(const std::string& line);

// What only a power-up (or reset) prints, with no '*' or '!' in it: the controller's banner
// (its name and version) or "Initializing...".
bool IsPowerUpText(const std::string& line);

// What a PTU prints while it powers up or resets, with no '*' or '!' in it: its banner,
// "Initializing...", or the echo of commands (PTU command words: letters and an optional
// signed integer, "V", "PP 1200 TP-40"). Such lines say the unit is there and busy, not that
// another device is on the port.
bool IsResetChatter(const std::string& line);

}  // namespace irdist::ptu_text
