#pragma once
// A scripted Transport for the device drivers' tests: each written line goes to a responder (a
// small model of the device written from its manual's examples) whose reply lines are queued for
// ReadLine. An empty queue is a timeout (LinkError), as on a silent port.

#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "station/transport.h"

namespace irdist {

struct FakeWire {
  std::function<std::vector<std::string>(const std::string&)> respond;
  std::vector<std::string> written;  // every line the driver sent
  std::deque<std::string> pending;   // lines waiting to be read
  int reads_timed_out = 0;
};

class FakeTransport : public Transport {
 public:
  explicit FakeTransport(std::shared_ptr<FakeWire> wire) : wire_(std::move(wire)) {}
  void WriteLine(std::string_view line) override {
    wire_->written.emplace_back(line);
    if (!wire_->respond) return;
    for (std::string& reply : wire_->respond(std::string(line))) {
      wire_->pending.push_back(std::move(reply));
    }
  }
  std::string ReadLine(std::chrono::milliseconds) override {
    if (wire_->pending.empty()) {
      ++wire_->reads_timed_out;
      throw LinkError("no reply", "fake", "test");
    }
    std::string line = wire_->pending.front();
    wire_->pending.pop_front();
    return line;
  }
  void Flush() override { wire_->pending.clear(); }

 private:
  std::shared_ptr<FakeWire> wire_;
};

}  // namespace irdist
