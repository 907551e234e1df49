#include "estimator/model_file_geometric.h"

#include <gtest/gtest.h>

#include <string>

#include "estimator/model_file_error.h"

namespace irdist::model_file {
namespace {

GeometricModel Read(const std::string& yaml, int version = 5) {
  GeometricModel g;
  ReadGeometricTerms(Reader("model.yaml"), YAML::Load(yaml), version, &g);
  return g;
}

// The header's example, by hand; and what the writer emits reads back the same.
TEST(ModelFileGeometric, TheHeadersExampleReadsAndTheWritersOutputRoundTrips) {
  const GeometricModel g = Read(
      "blur_u1_px2: 0.12\nblur_u2_px2: -0.03\nblur_u3_px2: 0.004\n"
      "tilt_theta_deg: [0, 5, 10]\ntilt_var_px2: [0.003, 0, -0.01]\n");
  EXPECT_EQ(g.blur_u3_px2, 0.004);
  EXPECT_EQ(g.tilt_theta_deg, (std::vector<double>{0.0, 5.0, 10.0}));
  EXPECT_EQ(g.tilt_var_px2, (std::vector<double>{0.003, 0.0, -0.01}));
  YAML::Emitter out;
  out << YAML::BeginMap;
  EmitGeometricTerms(out, g);
  out << YAML::EndMap;
  const GeometricModel back = Read(out.c_str());
  EXPECT_EQ(back.blur_u1_px2, g.blur_u1_px2);
  EXPECT_EQ(back.tilt_theta_deg, g.tilt_theta_deg);
  EXPECT_EQ(back.tilt_var_px2, g.tilt_var_px2);
  EXPECT_TRUE(Read("{}").tilt_theta_deg.empty());
}

// A bad tilt term or blur term is refused at its line, with the key and the fix.
TEST(ModelFileGeometric, BadTermsAreRefusedAtTheirLine) {
  const auto why = [](const std::string& yaml, int version = 5) {
    try {
      Read(yaml, version);
    } catch (const ModelFileError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(why("tilt_theta_deg: [0, 5]\n").find("tilt_var_px2"), std::string::npos);
  EXPECT_NE(why("tilt_theta_deg: [0, 5]\ntilt_var_px2: [0]\n").find("model.yaml:2"),
            std::string::npos);
  EXPECT_NE(why("tilt_theta_deg: [0, 5, 5]\ntilt_var_px2: [0, 0, 0]\n").find("tilt_theta_deg[2]"),
            std::string::npos);
  EXPECT_NE(why("tilt_theta_deg: [-1]\ntilt_var_px2: [0]\n").find("[0, 90)"), std::string::npos);
  EXPECT_NE(why("blur_u1_px2: 0.1\nblur_u2_px2: 0.2\n", 3).find("format_version 4"),
            std::string::npos);
  EXPECT_NE(why("blur_u3_px2: 0.1\n").find("blur_u1_px2"), std::string::npos);
}

}  // namespace
}  // namespace irdist::model_file
