#pragma once
// The one definition of pi for every module (C++17 has no std::numbers).

namespace irdist {

// pi to the precision of a double.
inline constexpr double kPi = 3.14159265358979323846;

}  // namespace irdist
