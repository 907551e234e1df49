#include "acquisition/pixel_pipeline.h"

#include <cmath>
#include <cstdlib>

namespace irdist {

const std::vector<PixelFeatureSpec>& PixelPipelineTable() {
  static const std::vector<PixelFeatureSpec> table = {
      {"gamma switch",
       {"GammaEnable", "GammaEnabled"},
       "false",
       "a power-law curve on the gray levels"},
      {"gamma", {"Gamma"}, "1", "a power-law curve on the gray levels"},
      {"LUT",
       {"LUTEnable", "LUTEnabled"},
       "false",
       "any curve a user loaded into the lookup table"},
      {"sharpening switch",
       {"SharpeningEnable", "SharpnessEnable", "SharpeningEnabled"},
       "false",
       "an edge filter: moves gray levels across the blob's rim"},
      {"sharpening",
       {"SharpnessEnhancement", "BslSharpnessEnhancement"},
       "0",
       "an edge filter: moves gray levels across the blob's rim"},
      {"noise reduction",
       {"NoiseReduction", "BslNoiseReduction"},
       "0",
       "a spatial filter: smooths the blob's profile"},
      {"noise reduction mode",
       {"NoiseReductionMode"},
       "Off",
       "a spatial filter: smooths the blob's profile"},
      {"defect-pixel correction",
       {"DefectCorrectionEnable", "DefectPixelCorrectionEnable", "DefectCorrectStaticEnable"},
       "false",
       "interpolated pixels (irdist keeps its own defect map instead)"},
      {"digital shift", {"DigitalShift"}, "0", "a bit shift: multiplies gray levels, clips early"},
      {"black-level auto", {"BlackLevelAuto"}, "Off", "an offset that follows the scene"},
      {"black-level switch", {"BlackLevelEnable", "BlackLevelEnabled"}, "true",
       "off, the dark noise clips at 0: a bend at the bottom of the response"},
      {"contrast", {"BslContrast"}, "0", "an S-curve on the gray levels"},
      {"brightness", {"BslBrightness"}, "0", "an offset or curve on the gray levels"},
      {"contrast mode", {"BslContrastMode"}, "Linear", "the contrast curve's shape"},
      {"binning mode",
       {"BinningHorizontalMode", "BinningVerticalMode", "BinningMode"},
       "",
       "sum or average of binned pixels: both linear, the full scale differs (stated only)"},
  };
  return table;
}

namespace {

bool ParseNumber(const std::string& text, double* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return end != nullptr && *end == '\0' && std::isfinite(*value);
}

}  // namespace

bool IsNeutralValue(const std::string& value, const std::string& neutral) {
  if (neutral.empty() || value == neutral) return true;
  if (neutral == "false") return value == "0" || value == "False" || value == "FALSE";
  double a = 0.0, b = 0.0;
  if (ParseNumber(value, &a) && ParseNumber(neutral, &b)) return std::fabs(a - b) <= 1e-6;
  return false;
}

std::string NotNeutralSummary(const std::vector<PixelFeatureState>& states) {
  std::string out;
  for (const PixelFeatureState& s : states) {
    if (s.neutral) continue;
    out += (out.empty() ? "" : ", ") + s.feature + " " + s.now +
           (s.why.empty() ? "" : " (" + s.why + ")");
  }
  return out;
}

}  // namespace irdist
