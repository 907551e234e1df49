#include "base/bounds.h"

#include <cmath>
#include <cstdio>

namespace irdist {

bool Bound::Contains(double value) const {
  if (!std::isfinite(value)) return false;
  const bool above_min = min_open ? value > min : value >= min;
  return above_min && value <= max;
}

std::string Bound::RangeText() const {
  std::string text = std::string(min_open ? "(" : "[") + BoundNumber(min) + ", " +
                     BoundNumber(max) + "]";
  if (unit[0] != '\0') text += std::string(" ") + unit;
  return text;
}

std::string Bound::Refusal(const std::string& what, double value, const std::string& fix) const {
  if (Contains(value)) return "";
  std::string text = what + " = " + BoundNumber(value) + " is outside " + RangeText() + " (" +
                     name + ": " + why + ")";
  if (!fix.empty()) text += "; " + fix;
  return text;
}

std::string BoundNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.10g", value);
  return text;
}

}  // namespace irdist
