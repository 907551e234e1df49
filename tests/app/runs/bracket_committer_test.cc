#include "app/runs/bracket_committer.h"

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "base/check.h"

// The live run's data-safety step driven without a camera: a fake recorder holds one pending
// bracket as LiveRecorder does (a capture replaces it, a drop forgets it, a commit appends it).

namespace irdist {
namespace {

class FakeRecorder : public PendingBrackets {
 public:
  // What LiveRecorder::CaptureBracket leaves: the bracket pending (replacing any pending one).
  void Capture(const std::string& bracket) {
    pending_ = bracket;
    calls.push_back("capture " + bracket);
  }
  void DropPending() override {
    if (!pending_.empty()) calls.push_back("drop " + pending_);
    pending_.clear();
  }
  bool CommitPending(std::function<void()> on_committed) override {
    if (pending_.empty()) return false;
    calls.push_back("commit " + pending_);
    committed.push_back(pending_);
    pending_.clear();
    appended_ = false;
    if (on_committed) on_committed();
    return true;
  }
  void WaitAppended() override {
    calls.push_back("wait appended");
    appended_ = true;
  }
  void WaitCommitted() override {
    calls.push_back("wait committed");
    if (!commit_error.empty()) throw Error(commit_error);
  }
  bool appended() const { return appended_; }

  std::vector<std::string> calls;
  std::vector<std::string> committed;  // what reached the recording, in order
  std::string commit_error;

 private:
  std::string pending_;
  bool appended_ = true;
};

struct Update {
  int done;
  std::string what;
};

class BracketCommitterTest : public ::testing::Test {
 protected:
  BracketCommitterTest()
      : committer_(recorder_, 3, [this](int done, const std::string& what) {
          updates_.push_back({done, what});
        }) {}

  // One pose as app/runs/run.cc's sweep callback does it, then the sweep's confirmation.
  void TakePose(const std::string& bracket, bool confirmed) {
    committer_.Begin();
    recorder_.Capture(bracket);
    committer_.Captured("pose " + bracket);
    if (confirmed) committer_.Confirmed();
  }

  FakeRecorder recorder_;
  std::vector<Update> updates_;
  BracketCommitter committer_;
};

TEST_F(BracketCommitterTest, CommitsEachConfirmedBracketAndWaitsForItBeforeTheNextMove) {
  TakePose("b0", true);
  EXPECT_TRUE(recorder_.appended());  // in the recording before Confirmed() returns
  TakePose("b1", true);
  EXPECT_EQ(recorder_.committed, (std::vector<std::string>{"b0", "b1"}));
  EXPECT_EQ(recorder_.calls, (std::vector<std::string>{"capture b0", "commit b0", "wait appended",
                                                       "capture b1", "commit b1",
                                                       "wait appended"}));
  ASSERT_EQ(updates_.size(), 2u);
  EXPECT_EQ(updates_[0].done, 4);  // counting on from the 3 poses of earlier sessions
  EXPECT_EQ(updates_[0].what, "pose b0");
  EXPECT_EQ(updates_[1].done, 5);
  EXPECT_EQ(committer_.done_count(), 5);
}

TEST_F(BracketCommitterTest, DropsTheBracketOfARetakenPoseAndCommitsOnlyTheRetake) {
  TakePose("b0-first", false);  // a device restarted: the sweep retakes the pose, no confirmation
  TakePose("b0-retake", true);
  EXPECT_EQ(recorder_.committed, (std::vector<std::string>{"b0-retake"}));
  EXPECT_EQ(recorder_.calls[1], "drop b0-first");
  ASSERT_EQ(updates_.size(), 1u);
  EXPECT_EQ(updates_[0].what, "pose b0-retake");
  EXPECT_EQ(committer_.done_count(), 4);
}

TEST_F(BracketCommitterTest, AbandonDropsTheUnconfirmedBracketAndReportsTheCommitsError) {
  TakePose("b0", true);
  TakePose("b1", false);  // the sweep failed before confirming b1
  recorder_.commit_error = "disk full";
  std::ostringstream err;
  committer_.Abandon(err);
  EXPECT_EQ(recorder_.committed, (std::vector<std::string>{"b0"}));
  EXPECT_EQ(recorder_.calls.back(), "wait committed");
  EXPECT_NE(err.str().find("also: disk full"), std::string::npos) << err.str();
  EXPECT_EQ(committer_.done_count(), 4);
}

TEST_F(BracketCommitterTest, AbandonDoesNotRepeatTheErrorThatStoppedTheSweep) {
  TakePose("b0", false);
  recorder_.commit_error = "disk full";
  std::ostringstream err;
  committer_.Abandon(err, "disk full");
  EXPECT_EQ(err.str(), "");
  committer_.Abandon(err, "station silent");
  EXPECT_NE(err.str().find("also: disk full"), std::string::npos) << err.str();
}

TEST_F(BracketCommitterTest, AConfirmationWithNothingPendingCommitsNothing) {
  committer_.Confirmed();
  EXPECT_TRUE(recorder_.committed.empty());
  EXPECT_TRUE(updates_.empty());
  EXPECT_EQ(committer_.done_count(), 3);
}

}  // namespace
}  // namespace irdist
