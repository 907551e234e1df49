// The report page: every figure drawn and captioned, hostile paths run no shell, a full disk
// is an error with the fix.
#include "app/reports/report.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <csignal>

#include <filesystem>
#include <string>
#include <vector>

#include "app/reports/validation_plots.h"
#include "tests/app/reports/report_helpers.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;
using testing::Rows;
using testing::Slurp;

TEST(Report, ValidationReportHasEveryFigureDrawnAndCaptioned) {
  const auto rows = Rows();
  const auto summary = Summarize(rows);
  const auto plots = ValidationPlots(rows, summary);
  std::vector<std::string> names;
  for (const Plot& p : plots) names.push_back(p.name);
  // Repeats >= 3 give Fig. 14; two methods give the comparison; two dts give Fig. 11.
  EXPECT_EQ(names, (std::vector<std::string>{"fig10_distance", "fig11_dt", "fig13_scatter",
                                             "fig13_histogram", "fig14_repetitions", "methods"}));
  const fs::path dir = fs::temp_directory_path() / ("irdist_report_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string index = WriteReport(dir.string(), "Validation", {{"recipe", "recipes/v.yaml"}},
                                        summary.BriefReport(), plots);
  const std::string html = Slurp(index);
  for (const Plot& p : plots) {
    EXPECT_TRUE(fs::exists(dir / (p.name + ".svg"))) << p.name;
    EXPECT_NE(html.find("id='" + p.name + "'"), std::string::npos) << p.name;
    EXPECT_TRUE(p.caption.find("Fig.") != std::string::npos ||
                p.caption.find("Not a figure of the paper") != std::string::npos)
        << p.name << ": the caption must say which figure it reproduces";
    EXPECT_TRUE(p.caption.find("(mm)") != std::string::npos ||
                p.caption.find("(%)") != std::string::npos)
        << p.name << ": the caption gives no unit";
    EXPECT_EQ(p.caption.find("NOTES.md"), std::string::npos) << p.name;
    EXPECT_EQ(p.caption.find("irdist show"), std::string::npos) << p.name;
    // The title is the page's heading only, not repeated inside the plot.
    EXPECT_EQ(Slurp(dir / (p.name + ".svg")).find(p.title), std::string::npos) << p.name;
    EXPECT_TRUE(p.script.find("key outside") != std::string::npos ||
                p.script.find("title '") == std::string::npos)
        << p.name << ": a legend on the data";
  }
  // The header says what produced the page.
  EXPECT_NE(html.find("<th>recipe</th><td>recipes/v.yaml</td>"), std::string::npos);
  EXPECT_NE(html.find("<th>report written</th>"), std::string::npos);
  EXPECT_EQ(html.find("class='missing'"), std::string::npos)
      << "a plot failed; see the .log files in " << dir;
  // Self-contained: the SVGs are inline, no external references.
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_EQ(html.find("src="), std::string::npos);
  fs::remove_all(dir);
}

TEST(Report, HostilePathsRunNoShellAndEveryPlotIsDrawn) {
  const auto rows = Rows();
  const auto summary = Summarize(rows);
  const auto plots = ValidationPlots(rows, summary);
  const fs::path root =
      fs::temp_directory_path() / ("irdist_hostile_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  const fs::path cwd = fs::current_path();
  fs::current_path(root);
  for (const std::string name :
       {"x'; touch INJECTED; echo '", "lab's run", "a \"b\" $HOME ; c", "$(touch INJECTED)"}) {
    const fs::path dir = root / name / "report";
    const std::string html = Slurp(WriteReport(dir.string(), "V", {}, "s", plots));
    EXPECT_EQ(html.find("class='missing'"), std::string::npos) << name;
    for (const Plot& p : plots) EXPECT_TRUE(fs::exists(dir / (p.name + ".svg"))) << name;
  }
  fs::current_path(cwd);
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    EXPECT_NE(entry.path().filename(), "INJECTED") << entry.path();
  }
  EXPECT_FALSE(fs::exists(cwd / "INJECTED"));
  fs::remove_all(root);
}

// A disk that fills up while the report is written, simulated with a file size limit (writes
// past it fail as on a full disk; gnuplot inherits the limit and cuts its SVG short).
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &saved_);
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit limit = saved_;
    limit.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, old_handler_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  rlimit saved_{};
  void (*old_handler_)(int) = nullptr;
};

// A full disk never leaves a cut report that looks whole: the error names the file and the fix,
// and no page (nor its temporary file) is left behind.
TEST(Report, AFullDiskIsAnErrorWithTheFixNotACutReport) {
  const fs::path dir = fs::temp_directory_path() / ("irdist_full_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const auto rows = Rows();
  const auto plots = ValidationPlots(rows, Summarize(rows));
  for (const bool with_plots : {true, false}) {
    SCOPED_TRACE(with_plots ? "a plot cut short" : "the page cut short");
    fs::remove_all(dir);
    try {
      FileSizeLimit limit(6000);  // each .dat and .gp fits; an SVG or the page does not
      WriteReport(dir.string(), "V", {}, std::string(with_plots ? 10 : 20000, 's'),
                  with_plots ? plots : std::vector<Plot>{});
      ADD_FAILURE() << "the report was written whole under a 6000-byte limit";
    } catch (const ReportError& e) {
      EXPECT_NE(std::string(e.what()).find("free disk space (df -h " + dir.string() + ")"),
                std::string::npos)
          << e.what();
    }
    EXPECT_FALSE(fs::exists(dir / "index.html"));
    EXPECT_FALSE(fs::exists(dir / "index.html.tmp"));
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace irdist
