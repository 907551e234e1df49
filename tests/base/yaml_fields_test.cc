#include "base/yaml_fields.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <string>

namespace irdist::yaml_fields {
namespace {

TEST(YamlFieldsTest, ClosestMatchSuggestsNearNamesOnly) {
  const std::vector<std::string> keys = {"slide_mm", "theta_deg", "pan_deg", "tilt_deg", "bias_ma"};
  EXPECT_EQ(ClosestMatch("slide", keys), "slide_mm");
  EXPECT_EQ(ClosestMatch("bias_mA", keys), "bias_ma");
  EXPECT_EQ(ClosestMatch("tilt", keys), "tilt_deg");
  EXPECT_EQ(ClosestMatch("temperature_c", keys), "");
}

TEST(YamlFieldsTest, SyntaxErrorsCarryTheirPosition) {
  try {
    Parse("a: [1, 2\nb: 3\n", "f.yaml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.File(), "f.yaml");
    EXPECT_GT(e.Line(), 0);
    EXPECT_GT(e.Column(), 0);
    EXPECT_NE(e.Message().find("YAML syntax error"), std::string::npos);
  }
}

TEST(YamlFieldsTest, MapReaderRefusesUnknownAndDuplicateKeys) {
  const YAML::Node ok = Parse("a: 1\nb: x\n", "f.yaml");
  const MapReader map(ok, "f.yaml", "section", {"a", "b", "c"});
  EXPECT_EQ(map.Number("a", 0.0), 1.0);
  EXPECT_EQ(map.String("b", ""), "x");
  EXPECT_EQ(map.Integer("c", 7), 7);  // absent: the fallback
  EXPECT_FALSE(map.Has("c"));
  try {
    map.Require("c");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.Line(), 1);
    EXPECT_NE(e.Message().find("section is missing the key 'c'"), std::string::npos);
  }
  EXPECT_THROW(MapReader(Parse("a: 1\nd: 2\n", "f.yaml"), "f.yaml", "section", {"a"}), InputError);
  try {
    MapReader(Parse("a: 1\na: 2\n", "f.yaml"), "f.yaml", "section", {"a"});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.Line(), 2);
    EXPECT_EQ(e.Column(), 1);
  }
  EXPECT_THROW(MapReader(Parse("[1, 2]", "f.yaml"), "f.yaml", "section", {"a"}), InputError);
}

TEST(YamlFieldsTest, ScalarConversionsAreStrict) {
  const YAML::Node node = Parse("i: 3\nf: 2.5\nt: yes\ns: word\nl: [1]\nn:\n", "f.yaml");
  EXPECT_EQ(AsInteger(node["i"], "f.yaml", "i"), 3);
  EXPECT_THROW(AsInteger(node["f"], "f.yaml", "f"), InputError);
  EXPECT_EQ(AsNumber(node["f"], "f.yaml", "f"), 2.5);
  EXPECT_THROW(AsNumber(node["s"], "f.yaml", "s"), InputError);
  EXPECT_THROW(AsNumber(node["l"], "f.yaml", "l"), InputError);
  EXPECT_THROW(AsNumber(node["n"], "f.yaml", "n"), InputError);
  EXPECT_TRUE(AsBoolean(node["t"], "f.yaml", "t"));
  EXPECT_THROW(AsBoolean(node["s"], "f.yaml", "s"), InputError);
  EXPECT_EQ(AsString(node["s"], "f.yaml", "s"), "word");
  EXPECT_THROW(AsString(node["l"], "f.yaml", "l"), InputError);
}

TEST(YamlFieldsTest, InputErrorFormatsItsPosition) {
  const InputError with_position("r.yaml", 3, 7, "bad");
  EXPECT_STREQ(with_position.what(), "r.yaml:3:7: bad");
  const InputError without("r.yaml", 0, 0, "cannot open");
  EXPECT_STREQ(without.what(), "r.yaml: cannot open");
}

// 2147483647 is a whole number: the error says it is out of range, and the range.
TEST(YamlFieldsTest, IntegersOutOfRangeSaySoAndGiveTheRange) {
  try {
    AsInteger(Parse("2147483647", "f.yaml"), "f.yaml", "count");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.Message().find("whole number,"), std::string::npos) << e.what();
    EXPECT_NE(e.Message().find("count '2147483647' is out of range"), std::string::npos)
        << e.what();
    EXPECT_NE(e.Message().find("[-2000000000, 2000000000]"), std::string::npos) << e.what();
  }
  EXPECT_EQ(AsInteger(Parse("-2000000000", "f.yaml"), "f.yaml", "count"), -2000000000);
  try {
    AsInteger(Parse("2.5", "f.yaml"), "f.yaml", "count");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(e.Message().find("must be a whole number, not '2.5'"), std::string::npos)
        << e.what();
  }
}

// A file that is not YAML (a password file) reads as one long scalar: the error names its kind
// and place, never its text; quoted values are cut at 40 characters.
TEST(YamlFieldsTest, ErrorsNeverEchoAFilesText) {
  const std::string passwd = "root:x:0:0:root:/root:/bin/bash\nuser:x:1000:1000::/home/u:/bin/sh\n";
  try {
    MapReader(Parse(passwd, "rig.yaml"), "rig.yaml", "the rig file", {"name"});
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).find("root"), std::string::npos) << e.what();
    EXPECT_NE(e.Message().find("not a single text value"), std::string::npos) << e.what();
  }
  try {
    AsNumber(Parse(std::string(100, 'x') + "\x01", "f.yaml"), "f.yaml", "n");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(e.Message().find("'" + std::string(40, 'x') + "...'"), std::string::npos)
        << e.what();
    EXPECT_EQ(e.Message().find(std::string(41, 'x')), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace irdist::yaml_fields

// A FIFO given as a recipe or rig file is refused at once, naming the file.
TEST(YamlFieldsTest, ReadFileRefusesAFifoWithoutBlocking) {
  const std::string path = ::testing::TempDir() + "recipe_fifo_" + std::to_string(::getpid());
  ::unlink(path.c_str());
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  try {
    irdist::yaml_fields::ReadFile(path);
    ADD_FAILURE() << "a FIFO was read as a recipe";
  } catch (const irdist::InputError& e) {
    EXPECT_EQ(e.File(), path);
    EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
  }
  ::unlink(path.c_str());
}
