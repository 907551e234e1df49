#include "app/reports/plot.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace irdist {
namespace {

// Series colours (colour-blind safe, Okabe-Ito) and point types, by series index.
const char* const kColours[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                "#E69F00", "#56B4E9", "#000000", "#999999"};
constexpr int kNumColours = 8;
const int kPointTypes[] = {7, 5, 9, 11, 13, 6, 4, 8};

}  // namespace

std::string SeriesColour(int i) { return kColours[i % kNumColours]; }
int SeriesPointType(int i) { return kPointTypes[i % kNumColours]; }

const char* const kPlotStyle =
    "set grid\nset key outside right top vertical Left reverse noenhanced\n"
    "set offsets graph 0.04, graph 0.04, graph 0.06, graph 0.06\n";

void ReplaceAll(std::string* text, const std::string& from, const std::string& to) {
  for (size_t at = 0; (at = text->find(from, at)) != std::string::npos; at += to.size()) {
    text->replace(at, from.size(), to);
  }
}

std::string FixedDigits(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

// A tick step of 1, 2 or 5 times a power of ten that puts at most `most_labels` labels on `span`
// (figures readable at 1280 px: gnuplot's own choice runs labels together on small panels).
double TickStep(double span, int most_labels) {
  if (!(span > 0.0) || !std::isfinite(span)) return 1.0;
  const double raw = span / most_labels;
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0}) {
    if (m * decade >= raw) return m * decade;
  }
  return 10.0 * decade;
}

// "set xtics STEP" (or ytics) for values spanning [lowest, highest], at most `most_labels` labels.
std::string TicsFor(const char* axis, const std::vector<double>& values, int most_labels) {
  if (values.empty()) return std::string("set ") + axis + "tics\n";
  const auto [lowest, highest] = std::minmax_element(values.begin(), values.end());
  std::ostringstream s;
  s << "set " << axis << "tics " << TickStep(*highest - *lowest, most_labels) << "\n";
  return s.str();
}

}  // namespace irdist
