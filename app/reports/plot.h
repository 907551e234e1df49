#pragma once
// One figure of a report: a gnuplot script and its data, drawn into the page by WriteReport
// (app/reports/report.h); and the house style every figure shares (series colours and point
// types, colour-blind safe; grid, padding and the legend outside the data; tick steps that keep
// the labels apart).

#include <string>
#include <vector>

namespace irdist {

// One plot: a gnuplot script body (after terminal and output are set) and its data file.
struct Plot {
  std::string name;     // file stem: <name>.dat, <name>.gp, <name>.svg
  std::string title;    // heading in the report (the only place the title appears)
  std::string caption;  // what it shows, units, and which figure of the paper it reproduces
  std::string data;     // contents of <name>.dat (gnuplot blocks separated by two blank lines)
  std::string script;   // gnuplot commands; the data file is referred to as '__DATA__'
  int width_px = 900;   // SVG size
  int height_px = 500;
};

// Series colours (Okabe-Ito) and gnuplot point types, by series index (they repeat after 8).
std::string SeriesColour(int i);
int SeriesPointType(int i);

// Axis padding so that no point sits on the frame, and the legend outside the data.
extern const char* const kPlotStyle;

// A tick step of 1, 2 or 5 times a power of ten that puts at most `most_labels` labels on `span`
// (figures readable at 1280 px: gnuplot's own choice runs labels together on small panels).
double TickStep(double span, int most_labels);
// "set xtics STEP" (or ytics) for values spanning [lowest, highest], at most `most_labels` labels.
std::string TicsFor(const char* axis, const std::vector<double>& values, int most_labels);

// `v` with `digits` digits after the point.
std::string FixedDigits(double v, int digits);
// Replaces every `from` in `*text` by `to`.
void ReplaceAll(std::string* text, const std::string& from, const std::string& to);

}  // namespace irdist
