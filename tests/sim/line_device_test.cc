#include "sim/line_device.h"

#include <gtest/gtest.h>

#include <string>

#include "base/input_error.h"
#include "sim/device_emulator.h"

namespace irdist::sim {
namespace {

constexpr const char* kRig = R"(kind: virtual
station:
  devices:
    slide:
      driver: zaber_ascii
      port: auto
      axes: {slide: "1 1"}
      origin_mm: 1000
    source:
      driver: scpi_source
      port: auto
virtual:
  devices:
    source:
      drop_rate: 0.5
)";

// A device with no virtual.devices entry (while others have one) keeps the defaults: it was
// yaml-cpp's own "invalid node", naming no file.
TEST(DeviceKeys, ADeviceWithoutAVirtualEntryKeepsTheDefaults) {
  const DeviceKeys slide = ReadDeviceKeys({"slide", "zaber_ascii", "lab.yaml", kRig, 1}, {});
  EXPECT_EQ(slide.axes.at("slide"), "1 1");
  EXPECT_EQ(slide.station_numbers.at("origin_mm"), 1000.0);
  EXPECT_EQ(slide.faults.drop_rate, 0.0);
  EXPECT_EQ(slide.Number("travel_mm", 2500.0), 2500.0);
  const DeviceKeys source = ReadDeviceKeys({"source", "scpi_source", "lab.yaml", kRig, 1}, {});
  EXPECT_EQ(source.faults.drop_rate, 0.5);
}

// Keys that are lists or maps are InputErrors with file:line (were "bad conversion").
TEST(DeviceKeys, KeysThatAreNotNamesAreInputErrorsWithTheirLine) {
  std::string rig = kRig;
  rig.replace(rig.find("axes: {slide: \"1 1\"}"), 20, "axes: {[a]: \"1 1\"}");
  try {
    ReadDeviceKeys({"slide", "zaber_ascii", "lab.yaml", rig, 1}, {});
    ADD_FAILURE() << "a list key accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.File(), "lab.yaml");
    EXPECT_EQ(e.Line(), 7);
  }
}

}  // namespace
}  // namespace irdist::sim
