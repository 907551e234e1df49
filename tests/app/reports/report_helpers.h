#pragma once
// Shared by the tests of app/reports/: a validation's estimate rows (3 distances, 2 currents,
// 3 repetitions, the default method's joint and per-exposure rows and a geometric row per
// bracket), a file's text, a plot by name, and the tick steps a gnuplot script sets.

#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/reports/plot.h"
#include "app/reports/summary.h"

namespace irdist::testing {

inline std::vector<EstimateRow> Rows() {
  std::vector<EstimateRow> rows;
  int bracket = 0;
  for (double d : {1500.0, 2000.0, 2500.0}) {
    for (double ma : {475.0, 525.0}) {
      for (int rep = 0; rep < 3; ++rep) {
        for (double dt : {0.0, 22.0, 24.0}) {
          EstimateRow r;
          r.bracket = bracket;
          r.repeat = rep;
          r.method = "i0_free";
          r.dt_ms = dt;
          r.true_d_mm = d;
          r.true_theta_deg = 20.0;
          r.bias_ma = ma;
          r.d_mm = d * (1.0 + 0.001 * (rep - 1) + 0.0001 * dt);
          r.theta_deg = 20.5;
          rows.push_back(r);
        }
        EstimateRow g = rows.back();
        g.method = "geometric";
        g.dt_ms = 0.0;
        g.d_mm = d * 1.004;
        rows.push_back(g);
        ++bracket;
      }
    }
  }
  return rows;
}

inline std::string Slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline const Plot& Named(const std::vector<Plot>& plots, const std::string& name) {
  for (const Plot& p : plots) {
    if (p.name == name) return p;
  }
  throw std::runtime_error("no plot " + name);
}

// The steps of "set xtics STEP" / "set ytics STEP" (or "set xtics START, STEP") in a script.
inline std::vector<double> TickSteps(const std::string& script, const std::string& axis) {
  std::vector<double> steps;
  const std::string key = "set " + axis + "tics ";
  for (size_t at = script.find(key); at != std::string::npos; at = script.find(key, at + 1)) {
    const size_t from = at + key.size();
    const std::string line = script.substr(from, script.find('\n', at) - from);
    if (line.empty() || !(std::isdigit(line[0]) || line[0] == '.')) continue;
    const size_t comma = line.find(',');
    steps.push_back(std::stod(comma == std::string::npos ? line : line.substr(comma + 1)));
  }
  return steps;
}

}  // namespace irdist::testing
