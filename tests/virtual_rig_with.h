#pragma once
// Test helper: recipes/rigs/virtual.yaml with extra keys under `virtual.camera:` (e.g. the
// camera's pixel-shaping faults, `    fixed_gamma: 0.45\n`), written to the test's temporary
// folder as NAME.yaml; returns its path.

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>

namespace irdist::testing {

inline std::string VirtualRigWithCameraKeys(const std::string& name, const std::string& keys) {
  std::ifstream in(IRDIST_SOURCE_DIR "/recipes/rigs/virtual.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string anchor = "  camera:\n    readout_ms: 12.0\n";
  const std::size_t at = text.find(anchor);
  EXPECT_NE(at, std::string::npos) << "recipes/rigs/virtual.yaml has no virtual.camera section";
  if (at != std::string::npos) text.insert(at + anchor.size(), keys);
  const std::string path = ::testing::TempDir() + "/" + name + ".yaml";
  std::ofstream(path) << text;
  return path;
}

}  // namespace irdist::testing
