#include "station/line_query.h"

#include <utility>

#include "station/driver.h"

namespace irdist {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

std::string NoReplyText(const std::string& device, const std::string& query, int attempts,
                        const std::string& last_heard) {
  return "no valid reply to '" + query + "' from " + device + " after " +
         std::to_string(attempts) + (attempts == 1 ? " attempt" : " attempts") +
         (last_heard.empty() ? "" : " (last heard '" + last_heard + "')");
}

}  // namespace

NoReplyError::NoReplyError(const std::string& device, const std::string& query, int attempts,
                           const std::string& last_heard, const std::string& port,
                           const std::string& fix)
    : LinkError(NoReplyText(device, query, attempts, last_heard), port, fix),
      device_(device),
      query_(query),
      attempts_(attempts),
      last_heard_(last_heard) {}

bool LineQueryOptions::IsValid(std::string* why) const {
  std::string problem;
  if (attempts < 1) problem = "attempts must be >= 1";
  else if (reply_timeout.count() <= 0) problem = "reply_timeout must be > 0";
  else if (device.empty()) problem = "device must name who answers";
  else if (fix.empty()) problem = "fix must say what to do when no reply comes";
  if (why != nullptr) *why = problem;
  return problem.empty();
}

LineQueryOptions QueryOptionsOf(const DeviceSpec& spec, int default_retries,
                                int default_timeout_ms, std::string device, std::string fix) {
  LineQueryOptions options;
  options.device = std::move(device);
  options.fix = std::move(fix);
  options.port = spec.port;
  options.attempts = 1 + static_cast<int>(spec.Number("retries", default_retries));
  options.reply_timeout =
      milliseconds(spec.reply_timeout_ms > 0 ? spec.reply_timeout_ms : default_timeout_ms);
  return options;
}

LineQuery::LineQuery(Transport* link, LineQueryOptions options)
    : link_(link), options_(std::move(options)) {
  std::string why;
  IRDIST_CHECK(link_ != nullptr, "LineQuery needs the driver's transport");
  IRDIST_CHECK(options_.IsValid(&why), why);
}

std::string LineQuery::Ask(const LineRequest& request) {
  last_heard_.clear();
  for (int attempt = 0; attempt < options_.attempts; ++attempt) {
    std::optional<std::string> reply = Attempt(request, attempt, options_.reply_timeout);
    if (reply) return *reply;
  }
  throw NoReplyError(request.device.empty() ? options_.device : request.device, request.query,
                     options_.attempts, last_heard_, options_.port, options_.fix);
}

std::optional<std::string> LineQuery::AskOnce(const LineRequest& request, milliseconds wait) {
  last_heard_.clear();
  return Attempt(request, 0, wait);
}

std::optional<std::string> LineQuery::Attempt(const LineRequest& request, int attempt,
                                              milliseconds wait) {
  if (options_.before_send) options_.before_send(attempt);
  link_->WriteLine(request.compose ? request.compose() : request.query);
  std::optional<std::string> reply = ReadReply(request, wait);
  if (!reply && options_.after_miss) options_.after_miss();
  return reply;
}

// Reads until the judge takes a line (the reply) or rejects one (nothing), or `wait` runs out.
std::optional<std::string> LineQuery::ReadReply(const LineRequest& request, milliseconds wait) {
  const auto deadline = Clock::now() + wait;
  while (true) {
    const auto left = std::chrono::duration_cast<milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) return std::nullopt;
    std::string line;
    try {
      line = link_->ReadLine(left);
    } catch (const LinkError&) {
      return std::nullopt;  // no line before the deadline
    }
    const ReplyVerdict verdict = request.judge(line);
    if (verdict == ReplyVerdict::kMatch) return line;
    if (!line.empty()) last_heard_ = line;
    if (verdict == ReplyVerdict::kRetry) return std::nullopt;
  }
}

}  // namespace irdist
