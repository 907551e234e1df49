// The house style every figure of a report shares: series colours and point types, tick steps of
// 1, 2 or 5 times a power of ten, the number and text helpers, and the style's gnuplot text as
// gnuplot reads it. The figures themselves are tested in calibration_plots_test.cc and
// validation_plots_test.cc, the page in report_test.cc.
#include "app/reports/plot.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "base/process.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

// Eight series are told apart by colour and by point type, and the ninth starts the cycle again.
TEST(SeriesStyle, EightDistinctColoursAndPointTypesThenTheCycleRepeats) {
  std::set<std::string> colours;
  std::set<int> points;
  const std::regex rgb("#[0-9A-Fa-f]{6}");  // gnuplot's `lc rgb '#RRGGBB'`
  for (int i = 0; i < 8; ++i) {
    EXPECT_TRUE(std::regex_match(SeriesColour(i), rgb)) << SeriesColour(i);
    colours.insert(SeriesColour(i));
    points.insert(SeriesPointType(i));
    EXPECT_EQ(SeriesColour(i + 8), SeriesColour(i));
    EXPECT_EQ(SeriesPointType(i + 8), SeriesPointType(i));
  }
  EXPECT_EQ(colours.size(), 8u);
  EXPECT_EQ(points.size(), 8u);
}

// The first series are Okabe and Ito's colour-blind safe blue, vermillion and bluish green.
TEST(SeriesStyle, TheFirstColoursAreOkabeItos) {
  EXPECT_EQ(SeriesColour(0), "#0072B2");
  EXPECT_EQ(SeriesColour(1), "#D55E00");
  EXPECT_EQ(SeriesColour(2), "#009E73");
}

// Steps from the 1-2-5 series: the smallest one that keeps the labels at most `most_labels`.
TEST(TickStep, TheSmallestOneTwoFiveStepWithinTheLabelCount) {
  EXPECT_DOUBLE_EQ(TickStep(1500.0, 10), 200.0);  // 150 mm per label: 200, not 100
  EXPECT_DOUBLE_EQ(TickStep(1000.0, 10), 100.0);  // exactly 10 labels fit
  EXPECT_DOUBLE_EQ(TickStep(37.0, 5), 10.0);      // 7.4 per label
  EXPECT_DOUBLE_EQ(TickStep(0.03, 6), 0.005);     // 0.005 per label
  EXPECT_NEAR(TickStep(0.9, 3), 0.5, 1e-15);      // 0.3 per label
  for (double span : {0.7, 3.0, 42.0, 999.0, 12345.0}) {
    const double step = TickStep(span, 8);
    EXPECT_LE(span / step, 8.0 * (1.0 + 1e-12)) << span;
    const double mantissa = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
    EXPECT_TRUE(std::abs(mantissa - 1.0) < 1e-9 || std::abs(mantissa - 2.0) < 1e-9 ||
                std::abs(mantissa - 5.0) < 1e-9) << span << ": " << step;
  }
}

// No span (one value, or none finite) still gives a usable step, never zero or NaN.
TEST(TickStep, AnEmptyOrUnknownSpanGivesAUnitStep) {
  EXPECT_DOUBLE_EQ(TickStep(0.0, 10), 1.0);
  EXPECT_DOUBLE_EQ(TickStep(NAN, 10), 1.0);
  EXPECT_DOUBLE_EQ(TickStep(INFINITY, 10), 1.0);
}

TEST(TicsFor, SetsTheStepForTheValuesSpanInAnyOrder) {
  EXPECT_EQ(TicsFor("x", {3000.0, 1500.0, 2250.0}, 10), "set xtics 200\n");
  EXPECT_EQ(TicsFor("y", {-0.01, 0.02}, 6), "set ytics 0.005\n");
  EXPECT_EQ(TicsFor("y", {}, 6), "set ytics\n");  // no data: gnuplot's own ticks
}

TEST(TextHelpers, FixedDigitsRoundsAndReplaceAllReplacesEveryOccurrence) {
  EXPECT_EQ(FixedDigits(2001.256, 1), "2001.3");
  EXPECT_EQ(FixedDigits(-0.004, 2), "-0.00");
  EXPECT_EQ(FixedDigits(2.0 / 3.0, 3), "0.667");
  EXPECT_EQ(FixedDigits(1e6, 0), "1000000");  // never in exponent form
  std::string script = "plot '__DATA__' index 0, '__DATA__' index 1";
  ReplaceAll(&script, "__DATA__", "fig10.dat");
  EXPECT_EQ(script, "plot 'fig10.dat' index 0, 'fig10.dat' index 1");
  std::string grows = "a-a";
  ReplaceAll(&grows, "a", "aa");  // a replacement holding the pattern is not replaced again
  EXPECT_EQ(grows, "aa-aa");
}

// What a report's reader depends on: gnuplot takes the house style, the tick lines and the
// series' colours and point types, and draws every series in its colour.
TEST(PlotStyle, GnuplotDrawsAFigureInTheHouseStyle) {
  if (FindProgram("gnuplot").empty()) GTEST_SKIP() << "gnuplot is not installed";
  const fs::path dir =
      fs::temp_directory_path() / ("irdist-plot-style-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "style.dat") << "1500 1.0\n3000 2.0\n\n\n1500 2.0\n3000 1.0\n";
  std::ostringstream gp;
  gp << "set terminal svg size 900,500\nset output 'style.svg'\n"
     << kPlotStyle << TicsFor("x", {1500.0, 3000.0}, 10) << TicsFor("y", {1.0, 2.0}, 6)
     << "plot 'style.dat' index 0 using 1:2 with linespoints pt " << SeriesPointType(0)
     << " lc rgb '" << SeriesColour(0) << "' title 'first', 'style.dat' index 1 using 1:2 "
     << "with linespoints pt " << SeriesPointType(1) << " lc rgb '" << SeriesColour(1)
     << "' title 'second'\n";
  std::ofstream(dir / "style.gp") << gp.str();
  ProcessSpec spec;
  spec.argv = {"gnuplot", "style.gp"};
  spec.working_dir = dir.string();
  spec.stderr_path = (dir / "style.log").string();
  const ProcessResult result = RunProgram(spec);
  std::ifstream log_in(dir / "style.log");
  const std::string log((std::istreambuf_iterator<char>(log_in)), {});
  EXPECT_TRUE(result.Succeeded()) << log;
  EXPECT_EQ(log, "");  // not even a warning
  std::ifstream svg_in(dir / "style.svg");
  std::string svg((std::istreambuf_iterator<char>(svg_in)), {});
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  for (int i = 0; i < 2; ++i) {
    // gnuplot's SVG names a colour as rgb(R, G, B), each a width-3 decimal.
    const long rgb = std::stol(SeriesColour(i).substr(1), nullptr, 16);
    char stroke[40];
    std::snprintf(stroke, sizeof(stroke), "rgb(%3ld, %3ld, %3ld)", rgb >> 16, (rgb >> 8) & 255,
                  rgb & 255);
    EXPECT_NE(svg.find(stroke), std::string::npos) << "series " << i << " not drawn in " << stroke;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace irdist
