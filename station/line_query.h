#pragma once
// Station-internal (included by the drivers' .cc files only, never by a public header): the one
// "send a query, retry after a lost or garbled reply, match the reply" loop of the serial device
// drivers (zaber_ascii, flir_ptu, scpi_source). Each driver keeps its own reply syntax: it hands
// the helper a judge that says of every received line whether it is the reply, a line to pass
// over, or a damaged reply; the helper does the writing, the deadlines and the retries.
//
// One attempt: before_send(attempt), write the line, then read lines until the reply timeout
// (counted from the write) runs out. A line judged kMatch ends the query; kSkip (another
// message, an echo, a late reply to an earlier attempt) is passed over and reading goes on;
// kRetry (a damaged reply) ends the attempt at once. An attempt that ends without a match calls
// after_miss(). After `attempts` attempts without a match: NoReplyError. An exception thrown by
// the judge (a device's refusal) ends the query at once, unretried.

#include <chrono>
#include <functional>
#include <optional>
#include <string>

#include "station/transport.h"

namespace irdist {

enum class ReplyVerdict {
  kMatch,  // this line is the reply
  kSkip,   // not this query's reply (another message, an echo, a late reply): read on
  kRetry,  // a damaged or invalid reply: this attempt failed, send again
};

// The query got no matching reply after every attempt. A LinkError naming the port, the device,
// the query, the attempts, the last line heard that was not the reply, and the fix.
class NoReplyError : public LinkError {
 public:
  NoReplyError(const std::string& device, const std::string& query, int attempts,
               const std::string& last_heard, const std::string& port, const std::string& fix);
  const std::string& device() const { return device_; }
  const std::string& query() const { return query_; }
  int attempts() const { return attempts_; }
  const std::string& last_heard() const { return last_heard_; }

 private:
  std::string device_, query_;
  int attempts_;
  std::string last_heard_;
};

struct LineQueryOptions {
  std::string device;  // who answers, for errors: "the PTU", "the SourceMeter"
  std::string port;    // the serial device, for errors
  std::string fix;     // what to do when no reply comes: cable, baud rate, power, address
  int attempts = 3;    // sends of one query, the first included (1 + the rig file's retries)
  std::chrono::milliseconds reply_timeout{1000};  // per attempt, counted from the write
  // Called before each write with the attempt's index (0 first): flush, resynchronise.
  std::function<void(int attempt)> before_send;
  // Called after each attempt that ended without a match (a reply may still be in flight).
  std::function<void()> after_miss;
  bool IsValid(std::string* why) const;
};

// One query as the driver sends it.
struct LineRequest {
  std::string query;  // the line sent, and the query's name in errors ("get pos", ":READ?")
  std::function<ReplyVerdict(const std::string& line)> judge;
  // The line written on an attempt, when it differs from `query` (a fresh message id each
  // attempt); empty: `query` as it is.
  std::function<std::string()> compose;
  std::string device;  // who is asked, for errors; empty: the options' device
};

struct DeviceSpec;  // station/driver.h

// A driver's query options from its rig-file entry: its port, its reply_timeout_ms
// (`default_timeout_ms` when not given) and 1 + its `retries` setting (`default_retries`);
// `device` and `fix` as in LineQueryOptions. The driver adds its hooks.
LineQueryOptions QueryOptionsOf(const DeviceSpec& spec, int default_retries,
                                int default_timeout_ms, std::string device, std::string fix);

class LineQuery {
 public:
  // `link` is the driver's transport and outlives this object.
  LineQuery(Transport* link, LineQueryOptions options);

  // The matching line, after up to options.attempts attempts. Throws NoReplyError.
  std::string Ask(const LineRequest& request);
  // One attempt only (a command that must not be repeated blindly), waiting `wait` for the
  // reply: the matching line, or nothing when none came.
  std::optional<std::string> AskOnce(const LineRequest& request, std::chrono::milliseconds wait);

  const LineQueryOptions& options() const { return options_; }

 private:
  std::optional<std::string> Attempt(const LineRequest& request, int attempt,
                                     std::chrono::milliseconds wait);
  std::optional<std::string> ReadReply(const LineRequest& request,
                                       std::chrono::milliseconds wait);

  Transport* link_;
  LineQueryOptions options_;
  std::string last_heard_;  // the last line of this query that was not its reply
};

}  // namespace irdist
