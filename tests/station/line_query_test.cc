// The drivers' query-with-retry helper against a fake line (tests/station/fake_transport.h)
// that drops, garbles and delays replies. The device behind it answers "<id> OK" to "<id> ask" (a message id, as Zaber's
// protocol carries); a delayed reply comes one read later than it should, after the attempt that
// sent it has given up.

#include "station/line_query.h"

#include <gtest/gtest.h>

#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "tests/station/fake_transport.h"

namespace irdist {
namespace {

using std::chrono::milliseconds;

enum class Fault { kNone, kDrop, kGarble, kDelay };

// The device: answers "<id> OK" to "<id> ask" unless the next fault (one per written line) drops
// the reply, damages it, or holds it back until the next read has timed out.
struct Device {
  std::deque<Fault> faults;
  std::deque<std::string> delayed;
  std::vector<std::string> Respond(const std::string& line) {
    const Fault fault = faults.empty() ? Fault::kNone : faults.front();
    if (!faults.empty()) faults.pop_front();
    const std::string id = line.substr(0, line.find(' '));
    if (fault == Fault::kDrop) return {};
    if (fault == Fault::kGarble) return {id + " O\x7f"};
    if (fault == Fault::kDelay) {
      delayed.push_back(id + " OK");
      return {};
    }
    return {id + " OK"};
  }
};

// The fake wire of the drivers' tests, with the deadline of every read kept and the delayed
// replies delivered just after a read gave up.
class DelayingTransport : public FakeTransport {
 public:
  DelayingTransport(std::shared_ptr<FakeWire> wire, Device* device)
      : FakeTransport(wire), wire_(std::move(wire)), device_(device) {}
  std::string ReadLine(milliseconds deadline) override {
    read_deadlines.push_back(deadline);
    if (wire_->pending.empty()) {
      wire_->pending.insert(wire_->pending.end(), device_->delayed.begin(), device_->delayed.end());
      device_->delayed.clear();
      throw LinkError("no reply", "fake", "test");
    }
    return FakeTransport::ReadLine(deadline);
  }
  std::vector<milliseconds> read_deadlines;

 private:
  std::shared_ptr<FakeWire> wire_;
  Device* device_;
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
  std::shared_ptr<FakeWire> wire = std::make_shared<FakeWire>();
  Device device;
  DelayingTransport transport{wire, &device};
  int next_id = 0;
  int id = 0;
  std::vector<int> before_send_attempts;
  int misses = 0;
  std::unique_ptr<LineQuery> query;

  explicit Asker(LineQueryOptions options = TestOptions()) {
    options.before_send = [this](int attempt) { before_send_attempts.push_back(attempt); };
    options.after_miss = [this] { ++misses; };
    wire->respond = [this](const std::string& line) { return device.Respond(line); };
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

TEST(LineQueryOptions, FromTheRigFileEntryWithTheDriversDefaults) {
  DeviceSpec spec = FakeDeviceSpec("head", "flir_ptu", "/dev/ttyUSB1", 10);
  LineQueryOptions options = QueryOptionsOf(spec, 4, 1000, "the PTU", "check the cable");
  EXPECT_EQ(options.attempts, 5);
  EXPECT_EQ(options.reply_timeout, milliseconds(1000));
  EXPECT_EQ(options.port, "/dev/ttyUSB1");
  EXPECT_EQ(options.device, "the PTU");
  EXPECT_EQ(options.fix, "check the cable");
  spec.settings["retries"] = {"0", 12};
  spec.reply_timeout_ms = 250;
  options = QueryOptionsOf(spec, 4, 1000, "the PTU", "check the cable");
  EXPECT_EQ(options.attempts, 1);
  EXPECT_EQ(options.reply_timeout, milliseconds(250));
}

TEST(LineQuery, AnsweredQueryIsSentOnce) {
  Asker a;
  EXPECT_EQ(a.query->Ask(a.Request()), "1 OK");
  EXPECT_EQ(a.wire->written, std::vector<std::string>({"1 ask"}));
  EXPECT_EQ(a.before_send_attempts, std::vector<int>({0}));
  EXPECT_EQ(a.misses, 0);
}

TEST(LineQuery, DroppedReplyIsAskedAgainAfterTheTimeout) {
  Asker a;
  a.device.faults = {Fault::kDrop, Fault::kDrop};
  EXPECT_EQ(a.query->Ask(a.Request()), "3 OK");
  EXPECT_EQ(a.wire->written, std::vector<std::string>({"1 ask", "2 ask", "3 ask"}));
  EXPECT_EQ(a.before_send_attempts, std::vector<int>({0, 1, 2}));
  EXPECT_EQ(a.misses, 2);
}

TEST(LineQuery, GarbledReplyEndsTheAttemptAtOnce) {
  Asker a;
  a.device.faults = {Fault::kGarble};
  EXPECT_EQ(a.query->Ask(a.Request()), "2 OK");
  EXPECT_EQ(a.wire->written.size(), 2u);
  // One read for the garbled line, one for the good reply: no waiting after the damage.
  EXPECT_EQ(a.transport.read_deadlines.size(), 2u);
}

TEST(LineQuery, LateReplyToAnEarlierAttemptIsPassedOver) {
  Asker a;
  a.device.faults = {Fault::kDelay};
  EXPECT_EQ(a.query->Ask(a.Request()), "2 OK");
  // Attempt 2 first reads the late "1 OK" (skipped), then its own reply.
  EXPECT_EQ(a.wire->written, std::vector<std::string>({"1 ask", "2 ask"}));
  EXPECT_EQ(a.transport.read_deadlines.size(), 3u);
}

TEST(LineQuery, EveryReadWaitsAtMostTheReplyTimeout) {
  Asker a;
  a.device.faults = {Fault::kDelay, Fault::kGarble};
  a.query->Ask(a.Request());
  for (const milliseconds deadline : a.transport.read_deadlines) {
    EXPECT_GT(deadline.count(), 0);
    EXPECT_LE(deadline.count(), 200);
  }
}

TEST(LineQuery, AfterTheLastAttemptATypedErrorNamesTheDeviceAndTheFix) {
  Asker a;
  a.device.faults = {Fault::kDrop, Fault::kGarble, Fault::kDrop, Fault::kNone};
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
  EXPECT_EQ(a.wire->written.size(), 3u);  // exactly `attempts` sends, never a fourth
  EXPECT_EQ(a.misses, 3);
}

TEST(LineQuery, RequestMayNameWhoIsAsked) {
  Asker a;
  a.device.faults = {Fault::kDrop, Fault::kDrop, Fault::kDrop};
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
  a.device.faults = {Fault::kDrop};
  EXPECT_THROW(a.query->Ask(a.Request()), NoReplyError);
  EXPECT_EQ(a.wire->written.size(), 1u);
}

TEST(LineQuery, AskOnceNeverSendsTwice) {
  Asker a;
  a.device.faults = {Fault::kDrop};
  EXPECT_FALSE(a.query->AskOnce(a.Request(), milliseconds(50)).has_value());
  EXPECT_EQ(a.wire->written.size(), 1u);
  EXPECT_EQ(a.misses, 1);
  EXPECT_EQ(a.query->AskOnce(a.Request(), milliseconds(50)).value_or(""), "2 OK");
  EXPECT_LE(a.transport.read_deadlines.back().count(), 50);
}

TEST(LineQuery, AnErrorFromTheJudgeIsNotRetried) {
  Asker a;
  LineRequest request = a.Request();
  request.judge = [](const std::string&) -> ReplyVerdict { throw Error("refused"); };
  EXPECT_THROW(a.query->Ask(request), Error);
  EXPECT_EQ(a.wire->written.size(), 1u);
}

TEST(LineQuery, WithoutComposeTheQueryIsSentAsItIs) {
  Asker a;
  LineRequest request;
  request.query = "7 ask";
  request.judge = [](const std::string& reply) {
    return reply == "7 OK" ? ReplyVerdict::kMatch : ReplyVerdict::kSkip;
  };
  a.device.faults = {Fault::kDrop};
  EXPECT_EQ(a.query->Ask(request), "7 OK");
  EXPECT_EQ(a.wire->written, std::vector<std::string>({"7 ask", "7 ask"}));
}

}  // namespace
}  // namespace irdist
