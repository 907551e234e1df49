#pragma once
// A scripted Transport for the device drivers' tests: each written line goes to a responder (a
// small model of the device written from its manual's examples) whose reply lines are queued for
// ReadLine. An empty queue is a timeout (LinkError), as on a silent port.

#include <deque>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "station/driver.h"
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

// A rig file's `station.devices.<name>:` entry of `driver` on `port`, written at rig.yaml:line.
inline DeviceSpec FakeDeviceSpec(const std::string& name, const std::string& driver,
                                 const std::string& port, int line) {
  DeviceSpec spec;
  spec.name = name;
  spec.driver = driver;
  spec.port = port;
  spec.file = "rig.yaml";
  spec.line = line;
  return spec;
}

// The registered driver `driver_name`, built from `spec` over a FakeTransport whose far end is
// `device` (a scripted model of the device with Respond(line) -> reply lines).
template <typename Device>
struct FakeDeviceBench {
  std::shared_ptr<FakeWire> wire = std::make_shared<FakeWire>();
  Device device;
  std::unique_ptr<DeviceDriver> driver;
  FakeDeviceBench(const std::string& driver_name, const DeviceSpec& spec) {
    wire->respond = [this](const std::string& line) { return device.Respond(line); };
    const DriverInfo* info = FindDriver(driver_name);
    if (info == nullptr) throw std::logic_error("no driver registered as " + driver_name);
    driver = info->create(spec, std::make_unique<FakeTransport>(wire));
  }
};

}  // namespace irdist
