#pragma once
// The serial transport: a Transport over a serial port (a USB-serial adapter on real hardware, the
// emulator's pseudo-terminal on the virtual rig). Every read and write has a deadline; bytes are
// logged line by line to an optional LineLog. No Asio types in this header.

#include <chrono>
#include <memory>
#include <string>
#include <string_view>

#include "station/line_log.h"
#include "station/transport.h"

namespace irdist {

// The fastest serial line a Linux tty driver sets (B4000000), bit/s.
constexpr unsigned int kMaxBaud = 4000000;

struct SerialOptions {
  unsigned int baud = 115200;                        // bits/s, 1..kMaxBaud; 8N1, no flow control
  std::chrono::milliseconds write_timeout{1000};     // a write not done by then throws LinkError
  std::size_t max_line_bytes = 512;                  // a longer "line" is cut and returned as is
  // Appended to every written line: "\r\n" (irdist station), "\n" (Zaber ASCII, SCPI), " " or
  // "\n" (FLIR PTU). Received lines end at '\n', a '\r' before it dropped.
  std::string line_end = "\r\n";
  // A '\r' alone also ends a received line (devices that end replies with CR only, as the FLIR
  // PTU manuals show); the empty line between a CR and its LF is then skipped.
  bool cr_ends_line = false;
  // Written before every line this transport logs ("slide: "), so that several devices can share
  // one LineLog; empty for a station of one device.
  std::string log_prefix;
  // Where the port and the baud were given, for the fix of an error ("the rig file's
  // station.port", "the PORT and --baud of irdist station-test").
  std::string origin = "the rig file's station.port and baud";
  bool IsValid(std::string* why) const;
};

class SerialTransport : public Transport {
 public:
  // Opens `port` (e.g. /dev/ttyUSB0 or /dev/pts/7) and configures it. Settings a pty rejects
  // (baud, flow control) are tolerated. `log` (may be null) must outlive the transport.
  // Throws LinkError if the options are not valid or the port cannot be opened.
  SerialTransport(const std::string& port, SerialOptions options = {}, LineLog* log = nullptr);
  ~SerialTransport() override;
  SerialTransport(const SerialTransport&) = delete;
  SerialTransport& operator=(const SerialTransport&) = delete;

  void WriteLine(std::string_view line) override;
  std::string ReadLine(std::chrono::milliseconds deadline) override;
  void Flush() override;
  std::vector<std::string> ReadPending() override;
  const std::string& port() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace irdist
