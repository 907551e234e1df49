#include "app/runs/bracket_committer.h"

#include <chrono>
#include <utility>

#include "base/check.h"

namespace irdist {

BracketCommitter::BracketCommitter(PendingBrackets& recorder, int done_count,
                                   OnCommitted on_committed)
    : recorder_(recorder), done_count_(done_count), on_committed_(std::move(on_committed)) {}

void BracketCommitter::Begin() { recorder_.DropPending(); }

void BracketCommitter::Captured(std::string what) { last_what_ = std::move(what); }

void BracketCommitter::Confirmed() {
  recorder_.CommitPending([this, what = last_what_]() {
    const int done = ++done_count_;
    if (on_committed_) on_committed_(done, what);
  });
  const auto t0 = std::chrono::steady_clock::now();
  recorder_.WaitAppended();
  waited_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void BracketCommitter::Abandon(std::ostream& err, const std::string& stopped_by) {
  recorder_.DropPending();
  try {
    recorder_.WaitCommitted();
  } catch (const Error& e) {
    // The commit's own error is often the one that stopped the sweep: said once.
    if (stopped_by != e.what()) err << "\nirdist: also: " << e.what() << "\n";
  }
}

}  // namespace irdist
