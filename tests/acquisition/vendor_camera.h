#pragma once
// Test helper: Aravis's fake camera serving a real vendor's GenICam file (the fixtures of
// tests/acquisition/genicam/vendors/, unpacked by CMake into the build's
// tests/acquisition/genicam_vendors/), powered up with the model's `.powerup` words before irdist
// opens it. Shared by tests/acquisition/aravis_vendor_files_test.cc and
// tests/integration/vendor_cameras_test.cc.
#include <arv.h>
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "tests/acquisition/fake_camera_process.h"

namespace irdist::testing {

// The fixture file `name` + `suffix` (".xml", ".powerup").
inline std::string VendorFixture(const std::string& name, const char* suffix) {
  return std::string(IRDIST_BINARY_DIR) + "/tests/acquisition/genicam_vendors/" + name + suffix;
}

// Another client on 127.0.0.1 (the camera's power-up, or a check of what irdist left).
class OtherClient {
 public:
  OtherClient() {
    GError* error = nullptr;
    camera_ = arv_camera_new("127.0.0.1", &error);
    Check(error, "connecting");
  }
  ~OtherClient() {
    if (camera_ != nullptr) g_object_unref(camera_);
  }
  OtherClient(const OtherClient&) = delete;
  OtherClient& operator=(const OtherClient&) = delete;

  // The fixture's `.powerup` words: what the model holds at power-up (its sensor, its limits,
  // the inquiry bits of what it implements, its name), which the fake camera's zeroed memory
  // lacks.
  void PowerUp(const std::string& path) {
    std::ifstream in(path);
    ASSERT_TRUE(in.good()) << path;
    std::string line;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream fields(line);
      guint32 address = 0, word = 0;
      fields >> std::hex >> address >> word;
      GError* error = nullptr;
      arv_device_write_register(arv_camera_get_device(camera_), address, word, &error);
      Check(error, line.c_str());
    }
  }
  // Each feature's value as a string ("" when unreadable).
  std::map<std::string, std::string> Read(const std::vector<std::string>& features) {
    std::map<std::string, std::string> values;
    for (const std::string& feature : features) {
      ArvGcNode* node = arv_device_get_feature(arv_camera_get_device(camera_), feature.c_str());
      if (node == nullptr || !ARV_IS_GC_FEATURE_NODE(node)) continue;
      GError* error = nullptr;
      const char* value =
          arv_gc_feature_node_get_value_as_string(ARV_GC_FEATURE_NODE(node), &error);
      if (error != nullptr) g_error_free(error);
      values[feature] = value == nullptr ? "" : value;
    }
    return values;
  }

 private:
  static void Check(GError* error, const char* what) {
    if (error == nullptr) return;
    ADD_FAILURE() << what << ": " << error->message;
    g_error_free(error);
  }
  ArvCamera* camera_ = nullptr;
};

// The fake camera serving the fixture `fixture` with serial `serial`, powered up as the model
// would be; stopped at the end.
class VendorFakeCamera {
 public:
  VendorFakeCamera(const std::string& fixture, const std::string& serial)
      : fake_(serial, {"-g", VendorFixture(fixture, ".xml")}) {
    OtherClient power_up;
    power_up.PowerUp(VendorFixture(fixture, ".powerup"));
  }

 private:
  FakeCameraProcess fake_;
};

}  // namespace irdist::testing
