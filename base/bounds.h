#pragma once
// The one table of bounds: every number a file or a flag carries (rig file, recipe, model file
// and its provenance, command-line options, Python arguments) is checked against a named quantity
// here, with a finite range set by physics (never by the virtual rig's values) and the reason.
// Readers refuse a value outside it at file:line:column or by the option's name; the model writer
// refuses to write one (docs/recipes.md "Bounds" lists the table).

#include <string>

namespace irdist {

// A named physical quantity and its range: [min, max], or (min, max] when min_open.
struct Bound {
  const char* name;  // "blur variance"
  const char* unit;  // "px^2"; "" for a pure number
  double min;
  double max;
  bool min_open;
  const char* why;  // the physics behind the range, said in a refusal

  // Finite and inside the range (NaN and infinities never are).
  bool Contains(double value) const;
  // "(0, 16] px^2"
  std::string RangeText() const;
  // "" when `value` is inside; else "<what> = <value> is outside <range>: <why>; <fix>".
  std::string Refusal(const std::string& what, double value, const std::string& fix = "") const;
};

// A number in at most 10 significant digits ("1e+308", never 309 digits).
std::string BoundNumber(double value);

namespace bounds {

// Times.
inline constexpr Bound kExposureMs{"exposure", "ms", 0.0, 100000.0, true,
                                   "a camera's exposure (100 s is far beyond any GigE camera's)"};
inline constexpr Bound kDurationS{"duration or wait", "s", 0.0, 86400.0, true,
                                  "a run's duration or a device's wait lies within a day"};
inline constexpr Bound kDelayMs{"delay", "ms", 0.0, 86400000.0, false,
                                "a device's readout, settling or overhead lies within a day"};
inline constexpr Bound kExposureUs{"exposure", "us", 0.0, 1.0e8, true,
                                   "a camera's exposure (100 s is far beyond any GigE camera's)"};
static_assert(kExposureUs.max == kExposureMs.max * 1000.0, "one exposure bound in ms and us");
inline constexpr Bound kUtcTimeNs{"wall-clock time", "ns since 1970", 0.0, 7.2581184e18, false,
                                  "a frame's arrival lies between 1970-01-01 (the clock's start) "
                                  "and 2200-01-01 UTC"};
inline constexpr Bound kMonotonicNs{"monotonic time", "ns", 0.0, 3.16e18, false,
                                    "a host's monotonic clock counts from its boot: less than a "
                                    "century"};
// A track's white-acceleration power spectral density (estimator/track_filter.h, measure --track).
inline constexpr Bound kAccelPsd{"acceleration noise density", "mm^2/s^3", 0.0, 1.0e12, true,
                                 "q = a^2 T: 1e12 is 1000 g sustained for a second, beyond any "
                                 "carriage, robot or hand"};
// The virtual rig's clock (rig `virtual.time_scale`, --time-scale, a sim's override).
inline constexpr Bound kTimeScale{"time scale", "simulated s per host s", 0.01, 1000.0, false,
                                  "from 100x slower than real time (each frame watched) to 1000x "
                                  "faster (a sweep in seconds)"};
// Sizes and counts.
inline constexpr Bound kDiskGb{"disk budget", "GB", 0.0, 1.0e6, true,
                               "no disk holds more than a petabyte"};
inline constexpr Bound kCount{"count", "", 1.0, 1.0e9, false,
                              "at least one, and a billion brackets is decades of measuring"};
inline constexpr Bound kFrameNumber{"frame or bracket number", "", 0.0, 1.0e9, false,
                                    "counted from 0; a billion frames is decades of measuring"};
inline constexpr Bound kToleranceSteps{"position tolerance", "steps", 0.0, 1.0e6, false,
                                       "a motor's tolerance is a few steps; a million is more "
                                       "than an axis's travel"};
inline constexpr Bound kSensorPx{"sensor coordinate", "px", 0.0, 1048576.0, false,
                                 "no sensor is wider than 2^20 pixels"};
inline constexpr Bound kBitDepth{"bit depth", "bit", 1.0, 16.0, false,
                                 "a camera's pixels carry 1 to 16 bits (Mono8: 8, Mono12: 12)"};
inline constexpr Bound kFrameBitDepth{"bit depth of a frame", "bit", 8.0, 16.0, false,
                                      "the features read Mono8 to Mono16 frames"};
// The station's pose and the emitter's current, as recorded with each frame.
inline constexpr Bound kSlideMm{"slide position", "mm", -1.0e5, 1.0e5, false,
                                "a linear stage's position lies within 100 m of its home"};
inline constexpr Bound kAngleDeg{"angle", "deg", -360.0, 360.0, false,
                                 "a pan, tilt or off-axis angle lies within one turn either way"};
// A station axis's cruise speed (a track recipe's profile).
inline constexpr Bound kSlideSpeedMmS{"slide speed", "mm/s", 0.0, 5000.0, true,
                                      "a linear stage carrying a pan-tilt head cruises at most a "
                                      "few m/s"};
inline constexpr Bound kAngularSpeedDegS{"angular speed", "deg/s", 0.0, 1000.0, true,
                                         "a pan-tilt unit turns at most a few turns per second"};
inline constexpr Bound kPositionSdMm{"position uncertainty", "mm", 0.0, 1000.0, true,
                                     "a stage's commanded position is known within a metre"};
inline constexpr Bound kCurrentMa{"IRED current", "mA", -10.0, 10000.0, false,
                                  "an IRED's forward current is at most a few amperes; a source "
                                  "reading back an emitter that is off may show a few mA below 0"};
// Camera intrinsics (OpenCV's pinhole with distortion [k1, k2, p1, p2, k3]).
inline constexpr Bound kFocalPx{"focal length", "px", 10.0, 1.0e6, false,
                                "focal length / pixel pitch: 1 mm / 20 um = 50 px to "
                                "1000 mm / 1 um = 1e6 px"};
inline constexpr Bound kRadialDistortion{"radial distortion coefficient", "", -5.0, 5.0, false,
                                         "lenses for measurement bend rays by a few percent; a "
                                         "larger k is a fisheye or a typo"};
inline constexpr Bound kTangentialDistortion{"tangential distortion coefficient", "", -0.1, 0.1,
                                             false,
                                             "decentring of a lens's elements is a fraction of "
                                             "a percent"};
// The largest share of the image radius that distortion may move a point at the sensor's corner.
inline constexpr double kMaxCornerDistortion = 0.5;
// Blur (the blob's variance per axis, px^2).
inline constexpr Bound kBlurVarPx2{"blur variance", "px^2", 0.0, 16.0, true,
                                   "a variance is > 0; 16 px^2 is a defocus disc of 8 px radius "
                                   "(variance R^2/4), beyond any focused measurement optic"};
inline constexpr Bound kBlurOffsetPx2{"blur correction", "px^2", -16.0, 16.0, false,
                                      "a correction to a blur variance is smaller than the "
                                      "largest blur (the corrected blur is checked as well)"};
inline constexpr Bound kBlurNoisePx2{"blur noise", "px^2", 0.0, 16.0, true,
                                     "the scatter of a blur variance is > 0 and below the "
                                     "largest blur"};
inline constexpr Bound kNoiseExponent{"noise exponent", "", -10.0, 10.0, false,
                                      "noise grows with a power of the distance: shot noise "
                                      "d^1, a dark floor d^2 or d^4"};
inline constexpr Bound kShare{"share", "", 0.0, 1.0, false, "a share of a whole"};
// The optics' line spread's excess kurtosis (the blob fit's Gram-Charlier edge).
inline constexpr Bound kOpticsExcess{"excess kurtosis",
                                     "",
                                     -3.0,
                                     4.0,
                                     false,
                                     "a defocus disc's edge reads -2, an Airy pattern's 4; "
                                     "beyond, the edge's line spread goes negative"};
// The blob fit's edge correction (estimator/edge_correction.h): a share of the disc's brightness.
inline constexpr Bound kEdgeCorrection{"edge correction",
                                       "",
                                       -0.5,
                                       0.5,
                                       false,
                                       "the share of the disc's brightness the fit's edge misses "
                                       "at a pixel: a lens's reads a few 0.01"};
// The fit's fitness (estimator/fitness.h): chi-squares and ratios of variances in noise units.
inline constexpr Bound kChiSquare{"chi-square", "", 0.0, 1.0e15, false,
                                  "a sum of squared residuals in noise units is >= 0; 1e15 is "
                                  "residuals 3e7 times their noise (the fit clips a worse one)"};
inline constexpr Bound kTailProbability{"tail probability", "", 0.0, 1.0, true,
                                        "a probability of a good fit failing, above 0, below 1"};
inline constexpr Bound kResidualPercent{"relative residual", "%", -100.0, 1.0e6, false,
                                        "a positive quantity's model misses it by at least "
                                        "-100%; 1e6% is 10000 times it (the fit clips a worse one)"};

}  // namespace bounds
}  // namespace irdist
