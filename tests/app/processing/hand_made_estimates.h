#pragma once
// A hand-made estimates.csv and the test fixture that writes it into a fresh folder: the rows the
// validation's statistics (tests/app/processing/validation_summary_test.cc) and summary.yaml
// (tests/app/reports/summary_test.cc) are checked on by hand.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace irdist {

// A hand-made estimates.csv. Pose 0: 2000 mm, 20 deg, two currents, two repeats each; pose 1:
// 1500 mm, 0 deg, one current, with per-dt rows (22 and 24 ms) beside its joint row.
constexpr const char* kCsv =
    "bracket,pose,repeat,method,dt_ms,true_d_mm,true_theta_deg,bias_ma,d_mm,theta_deg,"
    "outside_range,ok\n"
    "0,0,0,i0_free,0,2000,20,475,2010,21,0,1\n"
    "1,0,1,i0_free,0,2000,20,475,1990,19.5,0,1\n"
    "2,1,0,i0_free,0,2000,20,525,2020,20,0,1\n"
    "3,1,1,i0_free,0,2000,20,525,2000,22,0,1\n"
    "4,2,0,i0_free,0,1500,0,500,1530,5,1,1\n"
    "4,2,0,i0_free,22,1500,0,500,1515,4,0,1\n"
    "4,2,0,i0_free,24,1500,0,500,1503,3,0,1\n"
    "4,2,0,geometric,0,1500,0,500,1485,0,0,1\n"
    "5,2,1,geometric,0,1500,0,500,0,0,0,0\n";

class HandMadeEstimatesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("irdist_summary_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    std::ofstream(dir_ / "estimates.csv") << kCsv;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

}  // namespace irdist
