#pragma once
// The features of a camera that change pixel values after the sensor: one table, with the
// spellings vendors use and the value that leaves the gray levels as the sensor made them. irdist
// reads distance from gray levels, so each is set to its neutral value where the camera has it,
// saved and put back with the rest of the camera's state, and written to recording.yaml and
// camera-test's table. A feature the table does not know is caught by the linearity series
// (acquisition/linearity.h).

#include <string>
#include <vector>

namespace irdist {

struct PixelFeatureSpec {
  const char* what;                    // the feature's job, e.g. "LUT"
  std::vector<const char*> spellings;  // GenICam names, SFNC first, then vendors'
  // The value written (as GenICam's string form: "false", "Off", "1", "0"); empty = only stated
  // (recorded and shown, never written: binning mode, linear either way).
  const char* neutral;
  const char* effect;  // what it does to the gray levels when not neutral
};

// Every pixel-shaping feature irdist knows, in the order they are set.
const std::vector<PixelFeatureSpec>& PixelPipelineTable();

// One pixel-shaping feature as a camera had it and as irdist left it.
struct PixelFeatureState {
  std::string what;     // the table's job name
  std::string feature;  // the spelling this camera uses
  std::string found;    // its value before Configure
  std::string now;      // its value after
  bool neutral = true;  // `now` is the table's neutral value (or the row is only stated)
  std::string why;      // when not neutral: why it could not be set (read-only, locked, refused)
};

// Whether `value` (as the camera reads it) is the neutral `neutral` (numbers compared as numbers,
// so "1.000000" is "1"; booleans as false/0).
bool IsNeutralValue(const std::string& value, const std::string& neutral);

// "LUTEnable true (read-only)" for each row that is not neutral; empty when all are.
std::string NotNeutralSummary(const std::vector<PixelFeatureState>& states);

}  // namespace irdist
