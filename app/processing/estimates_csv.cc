#include "app/processing/estimates_csv.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "base/utc_time.h"

namespace irdist {
namespace {

constexpr const char* kEstimatesHeader =
    "bracket,pose,repeat,method,dt_ms,true_d_mm,true_theta_deg,bias_ma,d_mm,theta_deg,"
    "outside_range,ok,health,x_mm,y_mm,z_mm,x_se_mm,y_se_mm,z_se_mm,true_x_mm,true_y_mm,"
    "true_z_mm,motion,spread_mm,outside,utc_time,host_monotonic_ns,camera_timestamp_ns,d_se_mm,"
    "theta_se_deg,flags";
constexpr int kEstimatesColumns = 31;
// Older files: without the standard errors and flags (28), without the motion, range and time
// columns too (22), without the 3D columns too (13: health last), or without health too (12).
constexpr int kEstimatesColumnsNoFlags = 28;
constexpr int kEstimatesColumnsNoMotion = 22;
constexpr int kEstimatesColumnsNo3d = 13;
constexpr int kEstimatesColumnsNoHealth = 12;

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) out.push_back(cell);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

double ParseNumber(const std::string& text, const std::string& where, const char* column) {
  try {
    size_t used = 0;
    const double value = std::stod(text, &used);
    if (used == text.size()) return value;
  } catch (const std::exception&) {
  }
  throw EstimatesFileError(where + ": column '" + column + "' is '" + text +
                           "', not a number; fix or delete that row.");
}

bool ParseBool(const std::string& text, const std::string& where, const char* column) {
  if (text == "1" || text == "true") return true;
  if (text == "0" || text == "false") return false;
  throw EstimatesFileError(where + ": column '" + column + "' is '" + text +
                           "', expected 0 or 1; fix or delete that row.");
}

}  // namespace

namespace {

// A ground-truth value as estimates.csv writes it: empty when unknown (irdist measure).
std::string Truth(double value) {
  if (!std::isfinite(value)) return "";
  std::ostringstream out;
  out << std::setprecision(10) << value;
  return out.str();
}

}  // namespace

namespace {

// The 3D columns (13..21) of a row; empty = NaN.
void Read3d(const std::vector<std::string>& c, const std::string& where, EstimateRow* r) {
  double* const fields[] = {&r->x_mm,    &r->y_mm,      &r->z_mm,      &r->x_se_mm,  &r->y_se_mm,
                            &r->z_se_mm, &r->true_x_mm, &r->true_y_mm, &r->true_z_mm};
  const char* const names[] = {"x_mm",    "y_mm",      "z_mm",      "x_se_mm",  "y_se_mm",
                               "z_se_mm", "true_x_mm", "true_y_mm", "true_z_mm"};
  for (int i = 0; i < 9; ++i) {
    *fields[i] = c[13 + i].empty() ? NAN : ParseNumber(c[13 + i], where, names[i]);
  }
}

// The motion and range columns (22..24): motion, spread_mm (empty = NaN), outside (names
// separated by ';', empty = none).
void ReadMotionAndRanges(const std::vector<std::string>& c, const std::string& where,
                         EstimateRow* r) {
  r->motion = c[22];
  if (r->motion != "-" && r->motion != "static" && r->motion != "moving") {
    throw EstimatesFileError(where + ": motion '" + r->motion +
                             "' is not one of -, static, moving; fix that row.");
  }
  r->spread_mm = c[23].empty() ? NAN : ParseNumber(c[23], where, "spread_mm");
  std::istringstream names(c[24]);
  for (std::string name; std::getline(names, name, ';');) {
    if (!name.empty()) r->outside.push_back(name);
  }
}

// A count of ns (digits only, all 64 bits kept); empty = 0 (unknown).
std::uint64_t ParseCount(const std::string& text, const std::string& where, const char* column) {
  if (text.empty()) return 0;
  if (text.find_first_not_of("0123456789") == std::string::npos) {
    try {
      return std::stoull(text);
    } catch (const std::out_of_range&) {  // more than 64 bits: refused below
    }
  }
  throw EstimatesFileError(where + ": column '" + column + "' is '" + text +
                           "', not a count of ns; fix or delete that row.");
}

// The time columns (25..27) of a row; empty = 0 (unknown).
void ReadTimes(const std::vector<std::string>& c, const std::string& where, EstimateRow* r) {
  if (!c[25].empty()) {
    const std::optional<std::int64_t> utc_ns = ParseUtcIso8601(c[25]);
    if (!utc_ns) {
      throw EstimatesFileError(where + ": column 'utc_time' is '" + c[25] +
                               "', not YYYY-MM-DDTHH:MM:SS.ffffffZ; fix or delete that row.");
    }
    r->utc_ns = *utc_ns;
  }
  r->host_monotonic_ns =
      static_cast<std::int64_t>(ParseCount(c[26], where, "host_monotonic_ns"));
  r->camera_timestamp_ns = ParseCount(c[27], where, "camera_timestamp_ns");
}

// A standard error's cell: empty when the row has no estimate or the solver gave none.
std::string SeCell(bool ok, double se) {
  if (!ok || !(se >= 0.0) || !std::isfinite(se)) return "";
  std::ostringstream out;
  out << std::setprecision(6) << se;
  return out.str();
}

// An integer cell; empty when 0 (unknown).
template <typename Int>
std::string IntOrEmpty(Int value) {
  return value == 0 ? std::string() : std::to_string(value);
}

// The rows' lines (each ending in '\n'), as estimates.csv holds them.
std::string EstimateLines(const std::vector<EstimateRow>& rows) {
  std::ostringstream out;
  out << std::setprecision(10);
  for (const EstimateRow& r : rows) {
    out << r.bracket << ',' << r.pose << ',' << r.repeat << ',' << r.method << ',' << r.dt_ms << ','
        << Truth(r.true_d_mm) << ',' << Truth(r.true_theta_deg) << ',' << Truth(r.bias_ma) << ','
        << r.d_mm << ',' << r.theta_deg << ',' << (r.outside_range ? 1 : 0) << ',' << (r.ok ? 1 : 0)
        << ',' << r.health;
    for (double v : {r.x_mm, r.y_mm, r.z_mm, r.x_se_mm, r.y_se_mm, r.z_se_mm, r.true_x_mm,
                     r.true_y_mm, r.true_z_mm}) {
      out << ',' << Truth(v);
    }
    out << ',' << r.motion << ',' << Truth(r.spread_mm) << ',' << JoinNames(r.outside);
    out << ',' << (r.utc_ns != 0 ? FormatUtcIso8601(r.utc_ns) : "") << ','
        << IntOrEmpty(r.host_monotonic_ns) << ',' << IntOrEmpty(r.camera_timestamp_ns);
    out << ',' << SeCell(r.ok, r.d_std_mm) << ',' << SeCell(r.ok, r.theta_std_deg) << ','
        << FlagsCell(r.flags) << '\n';
  }
  return out.str();
}

// A cell that may be empty (a ground truth irdist measure does not know): NaN then.
double NumberOrNan(const std::string& text, const std::string& where, const char* column) {
  return text.empty() ? NAN : ParseNumber(text, where, column);
}

EstimateRow ParseEstimateRow(const std::vector<std::string>& c, int columns,
                             const std::string& where) {
  EstimateRow r;
  r.bracket = static_cast<int>(ParseNumber(c[0], where, "bracket"));
  r.pose = static_cast<int>(ParseNumber(c[1], where, "pose"));
  r.repeat = static_cast<int>(ParseNumber(c[2], where, "repeat"));
  r.method = c[3];
  r.dt_ms = ParseNumber(c[4], where, "dt_ms");
  r.true_d_mm = NumberOrNan(c[5], where, "true_d_mm");
  r.true_theta_deg = NumberOrNan(c[6], where, "true_theta_deg");
  r.bias_ma = NumberOrNan(c[7], where, "bias_ma");
  r.d_mm = ParseNumber(c[8], where, "d_mm");
  r.theta_deg = ParseNumber(c[9], where, "theta_deg");
  r.outside_range = ParseBool(c[10], where, "outside_range");
  r.ok = ParseBool(c[11], where, "ok");
  if (columns >= kEstimatesColumnsNo3d) r.health = c[12];
  if (columns >= kEstimatesColumnsNoMotion) Read3d(c, where, &r);
  if (columns >= kEstimatesColumnsNoFlags) {
    ReadMotionAndRanges(c, where, &r);
    ReadTimes(c, where, &r);
  }
  if (columns == kEstimatesColumns) {
    r.d_std_mm = c[28].empty() ? -1.0 : ParseNumber(c[28], where, "d_se_mm");
    r.theta_std_deg = c[29].empty() ? -1.0 : ParseNumber(c[29], where, "theta_se_deg");
    r.flags = ParseFlagsCell(c[30], where);
  }
  if (!(r.true_d_mm > 0.0) && !std::isnan(r.true_d_mm)) {
    throw EstimatesFileError(where + ": true_d_mm must be positive (or empty: unknown); fix that "
                             "row.");
  }
  return r;
}

// The number of columns a header line announces (0: not an estimates.csv header).
int ColumnsOfHeader(const std::string& line) {
  const std::string header(kEstimatesHeader);
  if (line == header) return kEstimatesColumns;
  if (line == header.substr(0, header.find(",d_se_mm"))) return kEstimatesColumnsNoFlags;
  if (line == header.substr(0, header.find(",motion"))) return kEstimatesColumnsNoMotion;
  if (line == header.substr(0, header.find(",x_mm"))) return kEstimatesColumnsNo3d;
  if (line == header.substr(0, header.find(",health"))) return kEstimatesColumnsNoHealth;
  return 0;
}

}  // namespace

const std::vector<FlagSpec>& FlagSpecs() {
  static const std::vector<FlagSpec> specs = {
      // Notes: measured through; the estimate stands.
      {"defect_pixels", false, "defect pixels replaced within the blob's reach (count)"},
      {"other_blobs", false, "other light sources or reflections masked out of the window (count)"},
      {"t_meas_extrapolated", false,
       "a measurement exposure beyond the calibrated ones, within the graded tolerance (ms)"},
      {"signal_extrapolated", false,
       "the blob's peak beyond the calibration frames', within the graded tolerance (%)"},
      {"refocused", false,
       "the blur changed since calibration: measured with the bracket's own blur (%)"},
      // Suspect: the estimate is not trusted.
      {"no_blob", true, "a frame of the bracket has no blob"},
      {"saturated", true, "pixels at the format's maximum in the window (count)"},
      {"touches_border", true, "the window is cut by the image's border"},
      {"clipped", true, "the blob reaches the window's edge"},
      {"second_source", true, "another source's light reaches the IRED's (gap, px)"},
      {"occluded", true, "the disc's edge departs from an ellipse: something covers it (% of edge)"},
      {"moving", true, "the per-exposure distances disagree: the IRED moved (spread, mm)"},
      {"blur_larger", true, "the blob is more blurred than calibrated: focus changed (%)"},
      {"blur_smaller", true, "the blob is less blurred than calibrated: focus changed (%)"},
      {"outside", true, "outside the calibrated ranges (their names, joined by +)"},
      {"disagrees", true,
       "the radiometric estimate departs from the apparent size's (geometric) reading (%)"},
      {"no_estimate", true, "no estimate could be made"},
  };
  return specs;
}

const FlagSpec* FindFlagSpec(const std::string& name) {
  for (const FlagSpec& spec : FlagSpecs()) {
    if (name == spec.name) return &spec;
  }
  return nullptr;
}

bool HasFlag(const std::vector<EstimateFlag>& flags, const char* name) {
  for (const EstimateFlag& f : flags) {
    if (f.name == name) return true;
  }
  return false;
}

std::string FlagsCell(const std::vector<EstimateFlag>& flags) {
  std::string cell;
  for (const EstimateFlag& f : flags) {
    cell += (cell.empty() ? "" : " ") + f.name + (f.figure.empty() ? "" : "=" + f.figure);
  }
  return cell;
}

std::vector<EstimateFlag> ParseFlagsCell(const std::string& cell, const std::string& where) {
  std::vector<EstimateFlag> flags;
  std::istringstream in(cell);
  for (std::string word; in >> word;) {
    const std::size_t eq = word.find('=');
    EstimateFlag f{word.substr(0, eq), eq == std::string::npos ? "" : word.substr(eq + 1)};
    if (FindFlagSpec(f.name) == nullptr) {
      throw EstimatesFileError(where + ": flag '" + f.name +
                               "' is not one of irdist's flags (docs/reports.md); fix that row.");
    }
    flags.push_back(f);
  }
  return flags;
}

bool EstimateRow::Trusted() const {
  if (!ok) return false;
  for (const EstimateFlag& f : flags) {
    const FlagSpec* spec = FindFlagSpec(f.name);
    if (spec == nullptr || spec->suspect) return false;
  }
  return true;
}

std::string JoinNames(const std::vector<std::string>& names, const char* separator) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : separator) + name;
  return out;
}

EstimatesCsvWriter::EstimatesCsvWriter(const std::string& path) : path_(path) {
  // Never through a link planted at its name (ELOOP).
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd_ < 0) {
    throw EstimatesFileError(path + ": cannot be written (" + std::strerror(errno) +
                             "); check the folder exists and is writable, and that the name is "
                             "not a symbolic link.");
  }
  try {
    WriteAll(std::string(kEstimatesHeader) + "\n");
  } catch (const EstimatesFileError&) {
    ::close(fd_);  // no empty estimates.csv left behind (a full disk): the name stays free
    ::unlink(path.c_str());
    throw;
  }
}

EstimatesCsvWriter::~EstimatesCsvWriter() {
  if (fd_ >= 0) ::close(fd_);  // every Append was synced: nothing to report here
}

void EstimatesCsvWriter::Append(const std::vector<EstimateRow>& rows) {
  if (!rows.empty()) WriteAll(EstimateLines(rows));
}

void EstimatesCsvWriter::WriteAll(const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      throw EstimatesFileError(path_ + ": write failed (" + std::strerror(errno) +
                               "; disk full?); free space.");
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fdatasync(fd_) != 0) {
    throw EstimatesFileError(path_ + ": sync failed (" + std::strerror(errno) +
                             "); check the disk.");
  }
}

void WriteEstimatesCsv(const std::string& path, const std::vector<EstimateRow>& rows) {
  EstimatesCsvWriter writer(path);
  writer.Append(rows);
}

std::vector<EstimateRow> ReadEstimatesCsv(const std::string& path, std::string* note) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw EstimatesFileError(path + ": cannot be opened; check the path.");
  std::ostringstream whole;
  whole << in.rdbuf();
  const std::string text = whole.str();
  if (note != nullptr) note->clear();
  std::istringstream lines(text);
  std::string line;
  std::getline(lines, line);
  const int columns = ColumnsOfHeader(line);
  if (columns == 0) {
    throw EstimatesFileError(path + ":1: the header is not '" + std::string(kEstimatesHeader) +
                             "'; is this an irdist estimates.csv?");
  }
  std::vector<EstimateRow> rows;
  int line_no = 1;
  std::size_t end = line.size() + 1;  // bytes read up to the end of this line
  while (std::getline(lines, line)) {
    ++line_no;
    end += line.size() + 1;
    const std::string where = path + ":" + std::to_string(line_no);
    if (end > text.size() && text.back() != '\n') {  // no end of line: torn by a crash
      if (note != nullptr) {
        *note = where + ": a torn last line (no end of line: the writer stopped while writing "
                        "it) was dropped";
      }
      break;
    }
    if (line.empty()) continue;
    const std::vector<std::string> c = SplitCsv(line);
    if (static_cast<int>(c.size()) != columns) {
      throw EstimatesFileError(where + ": " + std::to_string(c.size()) + " columns, expected " +
                               std::to_string(columns) + "; fix or delete that row.");
    }
    rows.push_back(ParseEstimateRow(c, columns, where));
  }
  return rows;
}

}  // namespace irdist
