#pragma once
// The Zaber ASCII protocol's text (Zaber's ASCII Protocol Manual): addresses, the LRC checksum,
// replies split into their fields, warning flags and rejection reasons, as the driver
// (station/zaber_ascii.cc) reads and writes them. Station-internal.

#include <string>

namespace irdist::zaber_ascii_text {

struct Address {
  int device = 1;
  int axis = 1;
};

// "1" = device 1 (its axis 1); "1 2" = device 1, axis 2. False on a bad address.
bool ParseAddress(const std::string& text, Address* out);

// Manual, "Checksumming": the bytes between the message type character and ':' summed modulo
// 256, then two's complement, as two upper-case hex digits.
std::string Lrc(const std::string& body);

struct Reply {
  char type = '@';  // '@' reply, '#' info, '!' alert
  int device = 0, axis = 0, id = -1;
  std::string flag, status, warning, data;
};

// Splits a received line; false when it is not a well-formed message (garbled, bad or missing
// checksum when `need_checksum`). *checked tells whether it carried a valid checksum.
bool ParseReply(std::string line, bool need_checksum, Reply* out, bool* checked);

// Manual, "Warning Flags". Faults (F*) stop the axis; WR/WH mean no reference position.
std::string FlagMeaning(const std::string& flag);

// WR, WH: the axis has no reference position (a power cycle, or never homed).
bool Unreferenced(const std::string& flag);

// The data of a numeric reply: one integer, or one per axis ("1651 1651" from a device-scope
// get). Anything else is a reply damaged on the wire ("1651" with a flipped bit: "16=1").
bool IsIntegers(const std::string& data);

// F*: a fault that stopped the axis.
bool Fault(const std::string& flag);

// Manual, "Reply Flags": why a command was rejected, and what to do.
std::string RejectionFix(const std::string& reason);

}  // namespace irdist::zaber_ascii_text
