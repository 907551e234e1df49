#pragma once
// The data-safety step of a live run (app/runs/run.cc): each bracket reaches the recording after
// the sweep confirmed its pose (every device seen alive after the capture) and before anything
// moves again; a bracket whose pose is retaken (a device restarted) or that a failure interrupts is
// dropped. The committer holds no camera or station: it drives the recorder's one pending bracket
// through PendingBrackets, which LiveRecorder (app/runs/capture.h) implements and a test can fake.

#include <atomic>
#include <functional>
#include <ostream>
#include <string>

namespace irdist {

// A recorder that holds back the last captured bracket until told to commit or drop it.
class PendingBrackets {
 public:
  virtual ~PendingBrackets() = default;
  // Forgets the pending bracket (none: no effect).
  virtual void DropPending() = 0;
  // Appends the pending bracket on a worker; `on_committed` runs there after the append. Returns
  // whether there was a pending bracket.
  virtual bool CommitPending(std::function<void()> on_committed) = 0;
  // Waits until the committed bracket's frames are in the recording; rethrows the append's error.
  virtual void WaitAppended() = 0;
  // Waits for the commit in flight (features included); rethrows its error.
  virtual void WaitCommitted() = 0;
};

class BracketCommitter {
 public:
  // Called on the recorder's worker after each commit, with the number of poses done so far
  // (done_count given here included) and the Captured() text of the committed pose.
  using OnCommitted = std::function<void(int done_count, const std::string& what)>;

  BracketCommitter(PendingBrackets& recorder, int done_count, OnCommitted on_committed);
  // A new capture for this pose begins: whatever is pending was never confirmed.
  void Begin();
  // The pose's bracket was captured (pending); `what` names the pose for the progress line.
  void Captured(std::string what);
  // The sweep confirmed the pose: append its frames and wait until they are in the recording.
  void Confirmed();
  // The sweep failed or stopped: the unconfirmed bracket is dropped, the commit in flight ends
  // (its error, if any, is written to `err` after the one that stopped the sweep, the text
  // `stopped_by`, unless it is that one).
  void Abandon(std::ostream& err, const std::string& stopped_by = "");

  int done_count() const { return done_count_; }
  // Host time the sweep waited for brackets to reach the recording, s.
  double waited_s() const { return waited_s_; }

 private:
  PendingBrackets& recorder_;
  std::atomic<int> done_count_;
  OnCommitted on_committed_;
  std::string last_what_;
  double waited_s_ = 0.0;
};

}  // namespace irdist
