// The model file's error (estimator/model_file_error.h): what() names the file, the line when
// known, the key when known, the problem and the fix; the parts are kept for the caller.
#include "estimator/model_file_error.h"

#include <gtest/gtest.h>

namespace irdist {
namespace {

TEST(ModelFileError, NamesFileLineKeyProblemAndFix) {
  const ModelFileError e("run/model.yaml", "blur.c0_px2", 12, "not a number");
  EXPECT_EQ(std::string(e.what()),
            "model file run/model.yaml:12: key 'blur.c0_px2': not a number. Re-run the "
            "calibration (irdist fit) to write a valid model file.");
  EXPECT_EQ(e.path(), "run/model.yaml");
  EXPECT_EQ(e.key(), "blur.c0_px2");
  EXPECT_EQ(e.line(), 12);
}

TEST(ModelFileError, LeavesOutAnUnknownLineAndKey) {
  const ModelFileError e("m.yaml", "", 0, "cannot be read");
  EXPECT_EQ(std::string(e.what()),
            "model file m.yaml: cannot be read. Re-run the calibration (irdist fit) to write a "
            "valid model file.");
  EXPECT_EQ(e.line(), 0);
  const Error& base = e;  // caught as the house's error
  EXPECT_NE(std::string(base.what()).find("m.yaml"), std::string::npos);
}

}  // namespace
}  // namespace irdist
