#include "station/line_log.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "station/transport.h"

namespace irdist {
namespace {

TEST(LineLog, WritesDirectionTimestampAndEscapes) {
  const std::string path = std::string(IRDIST_BINARY_DIR) + "/line_log_test.log";
  {
    LineLog log(path);
    log.Sent("#1 *IDN?*AB");
    log.Received(std::string("#1 OK\x07z", 7));
    log.Note("timeout");
  }
  std::ifstream in(path);
  std::string l1, l2, l3;
  std::getline(in, l1);
  std::getline(in, l2);
  std::getline(in, l3);
  double t1 = -1, t2 = -1;
  char d1 = 0, d2 = 0;
  std::istringstream(l1) >> t1 >> d1;
  std::istringstream(l2) >> t2 >> d2;
  EXPECT_GE(t1, 0.0);
  EXPECT_GE(t2, t1);  // monotonic
  EXPECT_EQ(d1, '>');
  EXPECT_EQ(d2, '<');
  EXPECT_NE(l1.find("#1 *IDN?*AB"), std::string::npos);
  EXPECT_NE(l2.find("#1 OK\\x07z"), std::string::npos);
  EXPECT_NE(l3.find(" # timeout"), std::string::npos);
}

TEST(LineLog, UnwritablePathThrowsLinkError) {
  EXPECT_THROW(LineLog("/nonexistent-dir/x/station.log"), LinkError);
}

}  // namespace
}  // namespace irdist
