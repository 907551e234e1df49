// The drivers' query-with-retry helper against a fake line that drops, garbles and delays
// replies. The device behind it answers "<id> OK" to "<id> ask" (a message id, as Zaber's
// protocol carries); a delayed reply comes one read later than it should, after the attempt that
// sent it has given up.

#include "station/line_query.h"

#include <gtest/gtest.h>

#include <deque>
#include <memory>
#include <string>
#include <vector>

namespace irdist {
namespace {

using std::chrono::milliseconds;

enum class Fault { kNone, kDrop, kGarble, kDelay };

struct Line {
  std::vector<std::string> written;
  std::deque<std::string> pending;
  std::deque<std::string> delayed;  // delivered after the next read timed out
  std::deque<Fault> faults;         // one per written line; kNone once empty
  std::vector<milliseconds> read_deadlines;
};

class FaultyTransport : public Transport {
 public:
  explicit FaultyTransport(std::shared_ptr<Line> line) : line_(std::move(line)) {}
  void WriteLine(std::string_view text) override {
    line_->written.emplace_back(text);
    const Fault fault = line_->faults.empty() ? Fault::kNone : line_->faults.front();
    if (!line_->faults.empty()) line_->faults.pop_front();
    const std::string id = std::string(text.substr(0, text.find(' ')));
    const std::string reply = id + " OK";
    if (fault == Fault::kNone) line_->pending.push_back(reply);
    if (fault == Fault::kGarble) line_->pending.push_back(id + " O\x7f");
    if (fault == Fault::kDelay) line_->delayed.push_back(reply);
  }
  std::string ReadLine(milliseconds deadline) override {
    line_->read_deadlines.push_back(deadline);
    if (line_->pending.empty()) {
      // The delayed reply arrives just after this read gave up.
      while (!line_->delayed.empty()) {
        line_->pending.push_back(line_->delayed.front());
        line_->delayed.pop_front();
      }
      throw LinkError("no reply", "fake", "test");
    }
    std::string text = line_->pending.front();
    line_->pending.pop_front();
    return text;
  }
  void Flush() override { line_->pending.clear(); }

 private:
  std::shared_ptr<Line> line_;
};

LineQueryOptions TestOptions() {
  LineQueryOptions options;
  options.device = "the test device";
  options.port = "/dev/ttyTEST";
  options.fix = "check the test cable";
  options.attempts = 3;
  options.reply_timeout = milliseconds(200);
  return options;
}

// "<id> ask" with a fresh id per attempt; the reply must carry the attempt's id and say OK. A
// reply with the right id and anything but OK is damaged; another id is a late reply.
struct Asker {
  std::shared_ptr<Line> line = std::make_shared<Line>();
  FaultyTransport transport{line};
  int next_id = 0;
  int id = 0;
  std::vector<int> before_send_attempts;
  int misses = 0;
  std::unique_ptr<LineQuery> query;

  explicit Asker(LineQueryOptions options = TestOptions()) {
    options.before_send = [this](int attempt) { before_send_attempts.push_back(attempt); };
    options.after_miss = [this] { ++misses; };
    query = std::make_unique<LineQuery>(&transport, std::move(options));
  }
  LineRequest Request() {
    LineRequest request;
    request.query = "ask";
    request.compose = [this] {
      id = ++next_id;
      return std::to_string(id) + " ask";
    };
    request.judge = [this](const std::string& reply) {
      if (reply.rfind(std::to_string(id) + " ", 0) != 0) return ReplyVerdict::kSkip;
      return reply == std::to_string(id) + " OK" ? ReplyVerdict::kMatch : ReplyVerdict::kRetry;
    };
    return request;
  }
};

TEST(LineQueryOptions, DefaultsNeedOnlyTheDeviceAndTheFix) {
  LineQueryOptions options;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  options.device = "the PTU";
  options.fix = "check the cable";
  EXPECT_TRUE(options.IsValid(&why)) << why;
  options.attempts = 0;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("attempts"), std::string::npos);
}

TEST(LineQuery, AnsweredQueryIsSentOnce) {
  Asker a;
  EXPECT_EQ(a.query->Ask(a.Request()), "1 OK");
  EXPECT_EQ(a.line->written, std::vector<std::string>({"1 ask"}));
  EXPECT_EQ(a.before_send_attempts, std::vector<int>({0}));
  EXPECT_EQ(a.misses, 0);
}

TEST(LineQuery, DroppedReplyIsAskedAgainAfterTheTimeout) {
  Asker a;
  a.line->faults = {Fault::kDrop, Fault::kDrop};
  EXPECT_EQ(a.query->Ask(a.Request()), "3 OK");
  EXPECT_EQ(a.line->written, std::vector<std::string>({"1 ask", "2 ask", "3 ask"}));
  EXPECT_EQ(a.before_send_attempts, std::vector<int>({0, 1, 2}));
  EXPECT_EQ(a.misses, 2);
}

TEST(LineQuery, GarbledReplyEndsTheAttemptAtOnce) {
  Asker a;
  a.line->faults = {Fault::kGarble};
  EXPECT_EQ(a.query->Ask(a.Request()), "2 OK");
  EXPECT_EQ(a.line->written.size(), 2u);
  // One read for the garbled line, one for the good reply: no waiting after the damage.
  EXPECT_EQ(a.line->read_deadlines.size(), 2u);
}

TEST(LineQuery, LateReplyToAnEarlierAttemptIsPassedOver) {
  Asker a;
  a.line->faults = {Fault::kDelay};
  EXPECT_EQ(a.query->Ask(a.Request()), "2 OK");
  // Attempt 2 first reads the late "1 OK" (skipped), then its own reply.
  EXPECT_EQ(a.line->written, std::vector<std::string>({"1 ask", "2 ask"}));
  EXPECT_EQ(a.line->read_deadlines.size(), 3u);
}

TEST(LineQuery, EveryReadWaitsAtMostTheReplyTimeout) {
  Asker a;
  a.line->faults = {Fault::kDelay, Fault::kGarble};
  a.query->Ask(a.Request());
  for (const milliseconds deadline : a.line->read_deadlines) {
    EXPECT_GT(deadline.count(), 0);
    EXPECT_LE(deadline.count(), 200);
  }
}

TEST(LineQuery, AfterTheLastAttemptATypedErrorNamesTheDeviceAndTheFix) {
  Asker a;
  a.line->faults = {Fault::kDrop, Fault::kGarble, Fault::kDrop, Fault::kNone};
  try {
    a.query->Ask(a.Request());
    FAIL() << "expected NoReplyError";
  } catch (const NoReplyError& e) {
    EXPECT_EQ(e.attempts(), 3);
    EXPECT_EQ(e.device(), "the test device");
    EXPECT_EQ(e.query(), "ask");
    EXPECT_EQ(e.where(), "/dev/ttyTEST");
    EXPECT_EQ(e.fix(), "check the test cable");
    EXPECT_EQ(e.last_heard(), "2 O\x7f");
    const std::string what = e.what();
    EXPECT_NE(what.find("'ask' from the test device after 3 attempts"), std::string::npos) << what;
    EXPECT_NE(what.find("/dev/ttyTEST"), std::string::npos) << what;
    EXPECT_NE(what.find("check the test cable"), std::string::npos) << what;
  }
  EXPECT_EQ(a.line->written.size(), 3u);  // exactly `attempts` sends, never a fourth
  EXPECT_EQ(a.misses, 3);
}

TEST(LineQuery, RequestMayNameWhoIsAsked) {
  Asker a;
  a.line->faults = {Fault::kDrop, Fault::kDrop, Fault::kDrop};
  LineRequest request = a.Request();
  request.device = "Zaber device 2";
  try {
    a.query->Ask(request);
    FAIL() << "expected NoReplyError";
  } catch (const LinkError& e) {  // a NoReplyError is a LinkError for the drivers' callers
    EXPECT_NE(std::string(e.what()).find("from Zaber device 2"), std::string::npos) << e.what();
  }
}

TEST(LineQuery, RetriesFollowTheOptions) {
  LineQueryOptions options = TestOptions();
  options.attempts = 1;
  Asker a(options);
  a.line->faults = {Fault::kDrop};
  EXPECT_THROW(a.query->Ask(a.Request()), NoReplyError);
  EXPECT_EQ(a.line->written.size(), 1u);
}

TEST(LineQuery, AskOnceNeverSendsTwice) {
  Asker a;
  a.line->faults = {Fault::kDrop};
  EXPECT_FALSE(a.query->AskOnce(a.Request(), milliseconds(50)).has_value());
  EXPECT_EQ(a.line->written.size(), 1u);
  EXPECT_EQ(a.misses, 1);
  EXPECT_EQ(a.query->AskOnce(a.Request(), milliseconds(50)).value_or(""), "2 OK");
  EXPECT_LE(a.line->read_deadlines.back().count(), 50);
}

TEST(LineQuery, AnErrorFromTheJudgeIsNotRetried) {
  Asker a;
  LineRequest request = a.Request();
  request.judge = [](const std::string&) -> ReplyVerdict { throw Error("refused"); };
  EXPECT_THROW(a.query->Ask(request), Error);
  EXPECT_EQ(a.line->written.size(), 1u);
}

TEST(LineQuery, WithoutComposeTheQueryIsSentAsItIs) {
  Asker a;
  LineRequest request;
  request.query = "7 ask";
  request.judge = [](const std::string& reply) {
    return reply == "7 OK" ? ReplyVerdict::kMatch : ReplyVerdict::kSkip;
  };
  a.line->faults = {Fault::kDrop};
  EXPECT_EQ(a.query->Ask(request), "7 OK");
  EXPECT_EQ(a.line->written, std::vector<std::string>({"7 ask", "7 ask"}));
}

}  // namespace
}  // namespace irdist
