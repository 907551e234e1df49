#include "station/serial_transport.h"

#include <sys/ioctl.h>
#include <termios.h>

#include <boost/asio.hpp>

#include <cerrno>
#include <cstring>
#include <istream>

#include "station/port_lock.h"

namespace irdist {

namespace asio = boost::asio;

namespace {

using BufferIterator = asio::buffers_iterator<asio::streambuf::const_buffers_type>;

// Match conditions of async_read_until: a line ends at '\n', or at '\r' or '\n'.
std::pair<BufferIterator, bool> EndsAtLf(BufferIterator begin, BufferIterator end) {
  for (BufferIterator i = begin; i != end; ++i) {
    if (*i == '\n') return {++i, true};
  }
  return {end, false};
}

std::pair<BufferIterator, bool> EndsAtCrOrLf(BufferIterator begin, BufferIterator end) {
  for (BufferIterator i = begin; i != end; ++i) {
    if (*i == '\n' || *i == '\r') return {++i, true};
  }
  return {end, false};
}

// A received line without its line end and without any '\r'.
std::string CleanLine(const std::string& raw) {
  std::string clean;
  clean.reserve(raw.size());
  for (char c : raw) {
    if (c != '\r' && c != '\n') clean.push_back(c);
  }
  return clean;
}

// Raw mode, as Asio's own open() sets it: no echo, no line editing, no character translation,
// 8 data bits, receiver on, modem lines ignored. Closes the port and throws if it cannot be set.
void MakeRaw(int fd, const std::string& port) {
  termios tio{};
  if (::tcgetattr(fd, &tio) == 0) {
    ::cfmakeraw(&tio);
    tio.c_cflag |= CREAD | CLOCAL;
    if (::tcsetattr(fd, TCSANOW, &tio) == 0) return;
  }
  const int error = errno;
  CloseExclusivePort(fd);
  throw LinkError("cannot set the serial port to raw mode: " + std::string(std::strerror(error)),
                  port, "check that the port is a serial device");
}

}  // namespace

bool SerialOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (baud == 0 || baud > kMaxBaud) return fail("baud must lie in 1..4000000 bit/s");
  if (write_timeout.count() <= 0) return fail("write_timeout must be > 0");
  if (max_line_bytes < 16) return fail("max_line_bytes must be >= 16");
  return true;
}

struct SerialTransport::Impl {
  std::string port_name;
  SerialOptions options;
  LineLog* log = nullptr;
  asio::io_context io;
  asio::serial_port port{io};
  asio::streambuf buffer;

  // Runs the io_context until `done` or the deadline; on a timeout cancels the pending operation
  // and lets its handler run. Returns whether the operation completed.
  bool RunUntil(const bool& done, std::chrono::milliseconds deadline) {
    io.restart();
    io.run_for(deadline);
    if (done) return true;
    boost::system::error_code ignored;
    port.cancel(ignored);
    io.restart();
    io.run();  // the cancelled handler completes with operation_aborted
    return done;
  }
};

SerialTransport::SerialTransport(const std::string& port, SerialOptions options, LineLog* log)
    : impl_(std::make_unique<Impl>()) {
  std::string why;
  if (!options.IsValid(&why)) {
    throw LinkError("invalid serial settings: " + why, port,
                    "fix " + options.origin + " (common speeds: 9600, 115200)");
  }
  impl_->port_name = port;
  impl_->options = options;
  impl_->log = log;
  // Opened for this command alone (flock and TIOCEXCL until the destructor): a second irdist on
  // the same port is refused naming this process.
  const int fd = OpenExclusivePort(port, options.origin);
  MakeRaw(fd, port);
  boost::system::error_code ec;
  impl_->port.assign(fd, ec);
  if (ec) {
    CloseExclusivePort(fd);
    throw LinkError("cannot use serial port: " + ec.message(), port, "check " + options.origin);
  }
  // A pty rejects some of these; what matters (raw mode) is set above.
  impl_->port.set_option(asio::serial_port_base::baud_rate(options.baud), ec);
  impl_->port.set_option(asio::serial_port_base::character_size(8), ec);
  impl_->port.set_option(asio::serial_port_base::parity(asio::serial_port_base::parity::none), ec);
  impl_->port.set_option(
      asio::serial_port_base::stop_bits(asio::serial_port_base::stop_bits::one), ec);
  impl_->port.set_option(
      asio::serial_port_base::flow_control(asio::serial_port_base::flow_control::none), ec);
}

SerialTransport::~SerialTransport() {
  // Closing the descriptor drops the flock; the exclusive flag is cleared first (best effort: a
  // destructor cannot report it, and the emulators clear a flag left behind).
  const int fd = impl_->port.native_handle();
  if (fd >= 0 && ::ioctl(fd, TIOCNXCL) != 0) {
    // Left set: a real port drops it with this last close; a pty's emulator clears it.
  }
  boost::system::error_code ignored;
  impl_->port.close(ignored);
}

const std::string& SerialTransport::port() const { return impl_->port_name; }

void SerialTransport::WriteLine(std::string_view line) {
  if (impl_->log) impl_->log->Sent(impl_->options.log_prefix + std::string(line));
  std::string bytes(line);
  bytes += impl_->options.line_end;
  bool done = false;
  boost::system::error_code result;
  asio::async_write(impl_->port, asio::buffer(bytes),
                    [&](const boost::system::error_code& ec, std::size_t) {
                      result = ec;
                      done = true;
                    });
  if (!impl_->RunUntil(done, impl_->options.write_timeout)) {
    throw LinkError("serial write timed out", impl_->port_name,
                    "check the cable and that the station is powered");
  }
  if (result && result != asio::error::operation_aborted) {
    throw LinkError("serial write failed: " + result.message(), impl_->port_name,
                    "check the cable and that the station is powered");
  }
}

std::string SerialTransport::ReadLine(std::chrono::milliseconds deadline) {
  const auto until = std::chrono::steady_clock::now() + deadline;
  while (true) {
    bool done = false;
    boost::system::error_code result;
    std::size_t length = 0;
    const auto on_read = [&](const boost::system::error_code& ec, std::size_t n) {
      result = ec;
      length = n;
      done = true;
    };
    if (impl_->options.cr_ends_line) {
      asio::async_read_until(impl_->port, impl_->buffer, &EndsAtCrOrLf, on_read);
    } else {
      asio::async_read_until(impl_->port, impl_->buffer, &EndsAtLf, on_read);
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        until - std::chrono::steady_clock::now());
    const bool completed = impl_->RunUntil(done, std::max(left, std::chrono::milliseconds(0)));
    if (completed && !result) {
      std::string line(length, '\0');
      std::istream in(&impl_->buffer);
      in.read(line.data(), static_cast<std::streamsize>(length));
      const std::string clean = CleanLine(line);
      if (clean.empty() && impl_->options.cr_ends_line) continue;  // the LF of a CR LF
      if (impl_->log) impl_->log->Received(impl_->options.log_prefix + clean);
      return clean;
    }
    if (result == asio::error::not_found || impl_->buffer.size() > impl_->options.max_line_bytes) {
      // No line end within the buffer's limit: hand back what came, the caller rejects it.
      std::string junk(impl_->buffer.size(), '\0');
      std::istream in(&impl_->buffer);
      in.read(junk.data(), static_cast<std::streamsize>(junk.size()));
      if (impl_->log) impl_->log->Received(impl_->options.log_prefix + junk);
      return junk;
    }
    if (completed && result && result != asio::error::operation_aborted) {
      throw LinkError("serial read failed: " + result.message(), impl_->port_name,
                      "check the cable and that the station is powered");
    }
    if (std::chrono::steady_clock::now() >= until) {
      if (impl_->log) {
        impl_->log->Note(impl_->options.log_prefix + "no line within " +
                         std::to_string(deadline.count()) + " ms");
      }
      throw LinkError("no reply line within " + std::to_string(deadline.count()) + " ms",
                      impl_->port_name,
                      "check that the station is powered and connected, and the baud rate");
    }
  }
}

std::vector<std::string> SerialTransport::ReadPending() {
  const int fd = impl_->port.native_handle();
  int available = 0;
  if (fd >= 0 && ::ioctl(fd, FIONREAD, &available) == 0 && available > 0) {
    boost::system::error_code ec;
    const std::size_t n =
        impl_->port.read_some(impl_->buffer.prepare(static_cast<std::size_t>(available)), ec);
    if (!ec) impl_->buffer.commit(n);
  }
  const std::string bytes(asio::buffers_begin(impl_->buffer.data()),
                          asio::buffers_end(impl_->buffer.data()));
  impl_->buffer.consume(impl_->buffer.size());  // a partial line is dropped, as by Flush()
  std::vector<std::string> lines;
  std::string line;
  for (char c : bytes) {
    const bool end = c == '\n' || (c == '\r' && impl_->options.cr_ends_line);
    if (!end) {
      line.push_back(c);
      continue;
    }
    const std::string clean = CleanLine(line);
    line.clear();
    if (clean.empty()) continue;
    if (impl_->log) impl_->log->Received(impl_->options.log_prefix + clean);
    lines.push_back(clean);
  }
  return lines;
}

void SerialTransport::Flush() {
  // Discard what is buffered here, then whatever the port already holds.
  impl_->buffer.consume(impl_->buffer.size());
  const int fd = impl_->port.native_handle();
  if (fd >= 0) ::tcflush(fd, TCIFLUSH);
}

}  // namespace irdist
