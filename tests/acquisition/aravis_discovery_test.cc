// Listing and naming cameras (acquisition/aravis_discovery.cc): a name is resolved by Aravis id
// or serial number, a miss lists what was found; discovery itself finds Aravis's own fake camera
// (arv-fake-gv-camera-0.8) on 127.0.0.1 by its id "Aravis-Fake-<serial>", and a camera is opened
// by id or serial through it. Discovery broadcasts on every interface: its tests run only where
// loopback is the sole interface (CTest runs them in a network namespace of their own).
#include "acquisition/aravis_camera.h"

#include <net/if.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "tests/acquisition/fake_camera_process.h"

namespace irdist {
namespace {

using testing::FakeCameraProcess;
constexpr char kSerial[] = "IRDDISC1";

const std::vector<DeviceInfo> kDevices = {
    {"Basler-acA1300-21714", "Basler", "acA1300", "21714", "192.0.2.40", "GigEVision"},
    {"FLIR-BFS-19283746", "FLIR", "Blackfly S", "19283746", "192.0.2.41", "GigEVision"},
    {"Aravis-Fake-GV01", "Aravis", "Fake", "GV01", "127.0.0.1", "GigEVision"}};

TEST(ResolveCamera, ANameIsMatchedAsAnAravisIdOrASerialNumber) {
  EXPECT_EQ(ResolveCamera("FLIR-BFS-19283746", kDevices).address, "192.0.2.41");
  EXPECT_EQ(ResolveCamera("19283746", kDevices).address, "192.0.2.41");
  EXPECT_EQ(ResolveCamera("GV01", kDevices).id, "Aravis-Fake-GV01");
  // Neither a prefix nor another case is a match.
  EXPECT_THROW(ResolveCamera("FLIR-BFS", kDevices), CameraError);
  EXPECT_THROW(ResolveCamera("gv01", kDevices), CameraError);
}

// A miss names what was asked and every camera found with its address, and says what to do.
TEST(ResolveCamera, AMissListsEveryCameraFoundWithItsAddress) {
  try {
    ResolveCamera("192.0.2.99", kDevices);
    FAIL() << "expected CameraError";
  } catch (const CameraError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("'192.0.2.99'"), std::string::npos) << what;
    EXPECT_NE(what.find("Basler-acA1300-21714 (192.0.2.40), FLIR-BFS-19283746 (192.0.2.41), "
                        "Aravis-Fake-GV01 (127.0.0.1)"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("IP address"), std::string::npos) << what;
  }
  try {
    ResolveCamera("GV01", {});
    FAIL() << "expected CameraError";
  } catch (const CameraError& e) {
    EXPECT_NE(std::string(e.what()).find("cameras found: []"), std::string::npos) << e.what();
  }
}

// Only loopback in this network namespace: discovery (a broadcast) reaches nothing else.
bool OnlyLoopback() {
  struct if_nameindex* names = if_nameindex();
  if (names == nullptr) return false;
  bool only = true;
  for (auto* n = names; n->if_index != 0; ++n) only = only && std::string(n->if_name) == "lo";
  if_freenameindex(names);
  return only;
}

class AravisDiscoveryTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (OnlyLoopback()) fake_ = new FakeCameraProcess(kSerial);
  }
  static void TearDownTestSuite() {
    delete fake_;
    fake_ = nullptr;
  }
  void SetUp() override {
    if (fake_ == nullptr) GTEST_SKIP() << "discovery broadcasts: run in a network namespace";
  }
  static FakeCameraProcess* fake_;
};
FakeCameraProcess* AravisDiscoveryTest::fake_ = nullptr;

TEST_F(AravisDiscoveryTest, DiscoveryListsTheFakeCameraWithItsIdentityAndAddress) {
  const std::vector<DeviceInfo> devices = ListCameras();
  const DeviceInfo* fake = nullptr;
  for (const DeviceInfo& d : devices) {
    if (d.id == std::string("Aravis-Fake-") + kSerial) fake = &d;
  }
  ASSERT_NE(fake, nullptr) << devices.size() << " devices found, none Aravis-Fake-" << kSerial;
  EXPECT_EQ(fake->vendor, "Aravis");
  EXPECT_EQ(fake->model, "Fake");
  EXPECT_EQ(fake->serial, kSerial);
  EXPECT_EQ(fake->address, "127.0.0.1");
  EXPECT_EQ(fake->protocol, "GigEVision");
}

// A serial number is not an address: it is resolved through discovery (about 1 s), then opened.
TEST_F(AravisDiscoveryTest, ACameraIsOpenedByItsSerialThroughDiscovery) {
  const auto camera = AravisCamera::Open(kSerial);
  const CameraIdentity identity = camera->Identity();
  EXPECT_EQ(identity.serial, kSerial);
  EXPECT_EQ(identity.address, "127.0.0.1");
  EXPECT_EQ(identity.vendor, "Aravis");
}

}  // namespace
}  // namespace irdist
