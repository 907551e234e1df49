#include "acquisition/recording_reader.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <utility>

#include <boost/crc.hpp>
#include <opencv2/core.hpp>

#include "acquisition/content_hash.h"
#include "acquisition/recording_files.h"
#include "acquisition/recording_integrity.h"
#include "base/bounds.h"
#include "base/regular_file.h"
#include "base/utc_time.h"
#include "base/yaml_fields.h"

namespace irdist {

namespace {

namespace fs = std::filesystem;

constexpr int kColumns = 23;    // format 2: ..., status, utc_time, host_monotonic_ns, sha256
constexpr int kColumnsV1 = 20;  // format 1: ends at status

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) fields.push_back(field);
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

bool ParseUint(const std::string& text, std::uint64_t* value) {
  if (text.empty() || text[0] == '-') return false;
  char* end = nullptr;
  errno = 0;
  const unsigned long long v = std::strtoull(text.c_str(), &end, 10);
  if (errno != 0 || end == nullptr || *end != '\0') return false;
  *value = v;
  return true;
}

// A count as an int; one beyond an int's range saturates (RowBoundsRefusal refuses it then).
int SaturatedInt(std::int64_t value) {
  return static_cast<int>(std::min<std::int64_t>(value, std::numeric_limits<int>::max()));
}

// Empty = NaN when `optional`.
bool ParseDouble(const std::string& text, double* value, bool optional = false) {
  if (text.empty()) {
    if (!optional) return false;
    *value = std::nan("");
    return true;
  }
  std::istringstream in(text);
  in.imbue(std::locale::classic());
  double v = 0.0;
  in >> v;
  if (in.fail() || !in.eof() || !std::isfinite(v)) return false;
  *value = v;
  return true;
}

// utc_time (host_time_ns as UTC ISO 8601, which it must match) and host_monotonic_ns (empty = 0).
bool ParseTimeColumns(const std::vector<std::string>& f, FrameRecord* r, std::string* why) {
  const std::optional<std::int64_t> utc_ns = ParseUtcIso8601(f[20]);
  if (!utc_ns || *utc_ns != r->host_time_ns / 1000 * 1000) {
    *why = "bad utc_time '" + f[20] + "' (host_time_ns " + std::to_string(r->host_time_ns) +
           " is " + FormatUtcIso8601(r->host_time_ns) + ")";
    return false;
  }
  if (!f[21].empty() && (!ParseCsvInt(f[21], &r->host_monotonic_ns) || r->host_monotonic_ns < 0)) {
    *why = "bad host_monotonic_ns '" + f[21] + "'";
    return false;
  }
  return true;
}

// frames.csv's text split into lines; `partial_last` when the last line lacks its '\n'.
struct CsvLines {
  std::vector<std::string> lines;  // lines[0] is line 1
  bool partial_last = false;
  std::uint64_t complete_bytes = 0;
};

CsvLines SplitLines(const std::string& text) {
  CsvLines csv;
  size_t start = 0;
  while (start < text.size()) {
    const size_t end = text.find('\n', start);
    if (end == std::string::npos) {
      csv.lines.push_back(text.substr(start));
      csv.partial_last = true;
      break;
    }
    csv.lines.push_back(text.substr(start, end - start));
    start = end + 1;
    csv.complete_bytes = start;
  }
  return csv;
}

// Duplicates, gaps and order of the indices: the rows are frames 0, 1, 2, ... in order.
class IndexTracker {
 public:
  // Returns "" when the row's index is the next one, else what is wrong.
  std::string Add(const FrameRecord& row) {
    std::string why;
    const auto earlier = index_line_.find(row.index);
    if (earlier != index_line_.end()) {
      why = "duplicate index " + std::to_string(row.index) + " (first at line " +
            std::to_string(earlier->second) + ")";
    } else if (row.index > expected_) {
      why = "gap: indices " + std::to_string(expected_) + ".." + std::to_string(row.index - 1) +
            " are missing";
    } else if (row.index < expected_) {
      why = "index " + std::to_string(row.index) + " out of order (expected " +
            std::to_string(expected_) + ")";
    }
    index_line_.emplace(row.index, row.line);
    expected_ = std::max(expected_, row.index + 1);
    return why;
  }

 private:
  std::map<std::int64_t, int> index_line_;
  std::int64_t expected_ = 0;
};

void AddSupersededWarning(const FrameRecord& row,
                          std::map<std::pair<std::int64_t, int>, int>* position_line,
                          std::vector<RecordingIssue>* warnings) {
  const auto position = std::make_pair(row.bracket_id, row.frame_in_bracket);
  const auto earlier = position_line->find(position);
  if (earlier != position_line->end()) {
    warnings->push_back({kFramesCsv, row.line,
                         "bracket " + std::to_string(row.bracket_id) + " frame " +
                             std::to_string(row.frame_in_bracket) + " supersedes line " +
                             std::to_string(earlier->second) + " (re-acquired)"});
  }
  (*position_line)[position] = row.line;
}

namespace yf = yaml_fields;

void ParseHeaderImage(const yf::MapReader& root, RecordingHeader* h) {
  const yf::MapReader image(root.Require("image"), root.File(), "image",
                            {"encoding", "bit_depth", "pixel_format"});
  if (image.String("encoding", "png16") != "png16") {
    yf::Fail(root.File(), image.Get("encoding").Mark(), "image.encoding must be png16");
  }
  const YAML::Node depth = image.Require("bit_depth");
  h->bit_depth = yf::AsInteger(depth, root.File(), "image.bit_depth");
  const std::string refusal = bounds::kBitDepth.Refusal(
      "image.bit_depth", h->bit_depth, "a 16-bit PNG carries 8 for Mono8, 12 for Mono12");
  if (!refusal.empty()) yf::Fail(root.File(), depth.Mark(), refusal);
  h->pixel_format = image.String("pixel_format", "");
}

void ParseHeaderCamera(const yf::MapReader& root, RecordingHeader* h) {
  if (!root.Has("camera")) return;
  const yf::MapReader camera(root.Get("camera"), root.File(), "camera",
                             {"vendor", "model", "serial", "firmware", "address", "features"});
  h->camera.vendor = camera.String("vendor", "");
  h->camera.model = camera.String("model", "");
  h->camera.serial = camera.String("serial", "");
  h->camera.firmware = camera.String("firmware", "");
  h->camera.address = camera.String("address", "");
  const YAML::Node features = camera.Get("features");
  if (!features) return;
  if (!features.IsMap()) yf::Fail(root.File(), features.Mark(), "camera.features must be a map");
  for (const auto& item : features) {
    h->camera_features[yf::AsString(item.first, root.File(), "camera.features key")] =
        yf::AsString(item.second, root.File(), "camera.features value");
  }
}

// recipe: / rig: {path, file, crc32} (the text in the file beside), or {path, text} (older).
void ParseHeaderText(const yf::MapReader& root, const char* key, std::string* path,
                     std::string* text, std::string* file, std::string* crc) {
  if (!root.Has(key)) return;
  const yf::MapReader block(root.Get(key), root.File(), key, {"path", "text", "file", "crc32"});
  *path = block.String("path", "");
  *text = block.String("text", "");
  *file = block.String("file", "");
  *crc = block.String("crc32", "");
  if (!file->empty() && *file != kRecipeCopy && *file != kRigCopy) {
    yf::Fail(root.File(), block.Get("file").Mark(),
             std::string(key) + ".file must be recipe.yaml or rig.yaml, beside recording.yaml");
  }
}

Completion ParseCompletionField(const yf::MapReader& root) {
  const YAML::Node node = root.Require("completion");
  const std::string text = yf::AsString(node, root.File(), "completion");
  if (text == "running") return Completion::kRunning;
  if (text == "complete") return Completion::kComplete;
  if (text == "cut") return Completion::kCut;
  yf::Fail(root.File(), node.Mark(),
           "completion '" + text + "' is not running, complete or cut; fix the key by hand");
}

// A count of rows in recording.yaml, refused at file:line:column outside bounds::kFrameNumber.
std::int64_t HeaderCount(const yf::MapReader& root, const YAML::Node& node, const char* key) {
  const double value = yf::AsNumber(node, root.File(), key);
  const std::string refusal = bounds::kFrameNumber.Refusal(
      key, value, "a count of frames.csv's rows; fix it by hand or restore the file");
  if (!refusal.empty()) yf::Fail(root.File(), node.Mark(), refusal);
  if (value != std::floor(value)) {
    yf::Fail(root.File(), node.Mark(), std::string(key) + " must be a whole number");
  }
  return static_cast<std::int64_t>(value);
}

// The command that made the recording and the rows a resume could not verify.
void ParseHeaderRun(const yf::MapReader& root, RecordingHeader* h) {
  h->run_command = root.String("command", "");
  if (!root.Has("unverified_rows")) return;
  const YAML::Node rows = root.Get("unverified_rows");
  h->unverified_rows = HeaderCount(root, rows, "unverified_rows");
}

// frame_count: -1 while running, else the rows at close (a count in bounds::kFrameNumber).
void ParseHeaderFrameCount(const yf::MapReader& root, RecordingHeader* h) {
  if (!root.Has("frame_count")) return;
  const YAML::Node node = root.Get("frame_count");
  if (yf::AsNumber(node, root.File(), "frame_count") == -1.0) return;
  h->frame_count = HeaderCount(root, node, "frame_count");
}

struct TextFiles {
  std::string recipe_file, recipe_crc, rig_file, rig_crc;
};

RecordingHeader ParseHeaderFields(const std::string& text, const std::string& path,
                                  TextFiles* files) {
  const yf::MapReader root(yf::Parse(text, path), path, "recording.yaml",
                           {"format", "format_version", "completion", "software_version",
                            "start_time", "end_time", "frame_count", "resumed", "image", "camera",
                            "station", "recipe", "rig", "frames_csv_sha256", "unverified_rows",
                            "command"});
  if (root.String("format", "") != "irdist-recording") {
    yf::Fail(path, root.Mark(), "'format' is not irdist-recording; this is not an irdist "
                                "recording header");
  }
  RecordingHeader h;
  h.format_version = root.Integer("format_version", 0);
  if (h.format_version < kOldestRecordingFormatVersion ||
      h.format_version > kRecordingFormatVersion) {
    yf::Fail(path, root.Mark(), "format_version " + std::to_string(h.format_version) +
                                    " is not supported (this irdist reads versions " +
                                    std::to_string(kOldestRecordingFormatVersion) + " to " +
                                    std::to_string(kRecordingFormatVersion) + ")");
  }
  h.frames_csv_sha256 = root.String("frames_csv_sha256", "");
  if (!h.frames_csv_sha256.empty() && !IsSha256Hex(h.frames_csv_sha256)) {
    yf::Fail(path, root.Get("frames_csv_sha256").Mark(),
             "frames_csv_sha256 must be 64 lowercase hex digits (the SHA-256 of frames.csv)");
  }
  h.completion = ParseCompletionField(root);
  ParseHeaderRun(root, &h);
  h.software_version = root.String("software_version", "");
  h.start_time = root.String("start_time", "");
  h.end_time = root.String("end_time", "");
  ParseHeaderFrameCount(root, &h);
  if (root.Has("resumed")) {
    const YAML::Node resumed = root.Get("resumed");
    if (!resumed.IsSequence()) yf::Fail(path, resumed.Mark(), "resumed must be a list of times");
    for (const auto& item : resumed) h.resumed.push_back(yf::AsString(item, path, "resumed"));
  }
  ParseHeaderImage(root, &h);
  ParseHeaderCamera(root, &h);
  if (root.Has("station")) {
    const yf::MapReader station(root.Get("station"), path, "station", {"identity"});
    h.station_identity = station.String("identity", "");
  }
  ParseHeaderText(root, "recipe", &h.recipe_path, &h.recipe_text, &files->recipe_file,
                  &files->recipe_crc);
  ParseHeaderText(root, "rig", &h.rig_path, &h.rig_text, &files->rig_file, &files->rig_crc);
  return h;
}

// The recipe or rig text from its file beside recording.yaml, checked against its CRC.
std::string ReadTextBeside(const std::string& dir, const std::string& file, const std::string& crc) {
  const std::string path = (fs::path(dir) / file).string();
  std::string text, why;
  if (!ReadRegularFile(path, kMaxRecordingTextBytes, &text, &why)) {
    throw RecordingError(path + " " + why + "; recording.yaml names it as the text used. "
                         "Restore it from a copy of the recording.");
  }
  if (TextCrc32Hex(text) != crc) {
    throw RecordingError(path + ": its CRC-32 is " + TextCrc32Hex(text) + ", recording.yaml says " +
                         crc + "; the file was edited. Restore it from a copy of the recording.");
  }
  return text;
}

RecordingHeader ReadHeader(const std::string& dir) {
  const std::string path = (fs::path(dir) / kRecordingYaml).string();
  std::string text, why;
  if (!ReadRegularFile(path, kMaxRecordingTextBytes, &text, &why)) {
    throw RecordingError(path + " " + why + ": not a recording directory (recording.yaml "
                         "missing). Give the directory that holds recording.yaml and frames.csv.");
  }
  TextFiles files;
  RecordingHeader h;
  try {
    h = ParseHeaderFields(text, path, &files);
  } catch (const InputError& error) {
    throw RecordingError(std::string(error.what()) + "; fix recording.yaml by hand.");
  }
  if (!files.recipe_file.empty()) h.recipe_text = ReadTextBeside(dir, files.recipe_file, files.recipe_crc);
  if (!files.rig_file.empty()) h.rig_text = ReadTextBeside(dir, files.rig_file, files.rig_crc);
  return h;
}


}  // namespace

// The helpers the writer and the check share (acquisition/recording_files.h).

std::string FrameFileName(std::int64_t index) {
  char name[48];
  std::snprintf(name, sizeof(name), "frames/%06lld.png", static_cast<long long>(index));
  return name;
}

std::string TextCrc32Hex(const std::string& text) {
  boost::crc_32_type crc;
  crc.process_bytes(text.data(), text.size());
  char hex[16];
  std::snprintf(hex, sizeof(hex), "%08x", static_cast<unsigned>(crc.checksum()));
  return hex;
}

bool ParseCsvInt(const std::string& text, std::int64_t* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (errno != 0 || end == nullptr || *end != '\0') return false;
  *value = v;
  return true;
}

bool ParseFramesCsvRow(const std::string& line, FrameRecord* r, std::string* why, bool hashed) {
  const std::vector<std::string> f = Split(line);
  const int columns = hashed ? kColumns : kColumnsV1;
  if (static_cast<int>(f.size()) != columns) {
    *why = "expected " + std::to_string(columns) + " columns, found " + std::to_string(f.size());
    return false;
  }
  auto bad = [&](const char* column, const std::string& text) {
    *why = std::string("bad ") + column + " '" + text + "'";
    return false;
  };
  std::int64_t v = 0;
  if (!ParseCsvInt(f[0], &r->index) || r->index < 0) return bad("index", f[0]);
  r->file = f[1];
  if (r->file != FrameFileName(r->index)) {
    *why = "file '" + f[1] + "' is not " + FrameFileName(r->index) +
           " (a row names the PNG of its own index, inside the recording)";
    return false;
  }
  if (!ParseCsvInt(f[2], &r->bracket_id)) return bad("bracket_id", f[2]);
  if (!ParseCsvInt(f[3], &v) || v < 0) return bad("frame_in_bracket", f[3]);
  r->frame_in_bracket = SaturatedInt(v);
  if (!ParseCsvInt(f[4], &v) || v <= r->frame_in_bracket) return bad("bracket_size", f[4]);
  r->bracket_size = SaturatedInt(v);
  if (f[5] == "ref") {
    r->role = FrameRole::kReference;
  } else if (f[5] == "meas") {
    r->role = FrameRole::kMeasurement;
  } else {
    return bad("role", f[5]);
  }
  if (!ParseDouble(f[6], &r->requested_exposure_us)) return bad("requested_exposure_us", f[6]);
  if (!ParseDouble(f[7], &r->actual_exposure_us)) return bad("actual_exposure_us", f[7]);
  if (f[8] != "chunk" && f[8] != "readback") return bad("exposure_source", f[8]);
  r->exposure_from_chunk = f[8] == "chunk";
  // Only bias_ma_measured may be empty (not measured): the pose and the set current are the
  // frame's ground truth.
  if (!ParseDouble(f[9], &r->bias_ma_set)) return bad("bias_ma_set", f[9]);
  if (!ParseDouble(f[10], &r->bias_ma_measured, true)) return bad("bias_ma_measured", f[10]);
  if (!ParseDouble(f[11], &r->slide_mm)) return bad("slide_mm", f[11]);
  if (!ParseDouble(f[12], &r->pan_deg)) return bad("pan_deg", f[12]);
  if (!ParseDouble(f[13], &r->tilt_deg)) return bad("tilt_deg", f[13]);
  if (!ParseDouble(f[14], &r->theta_deg)) return bad("theta_deg", f[14]);
  if (!ParseCsvInt(f[15], &v) || v < 0) return bad("repeat", f[15]);
  r->repeat = SaturatedInt(v);
  if (!ParseUint(f[16], &r->camera_frame_id)) return bad("camera_frame_id", f[16]);
  if (!f[17].empty() && !ParseUint(f[17], &r->camera_timestamp_ns)) {
    return bad("camera_timestamp_ns", f[17]);
  }
  if (!ParseCsvInt(f[18], &r->host_time_ns)) return bad("host_time_ns", f[18]);
  r->status = f[19];
  if (r->status != "ok" && r->status != "retried") return bad("status", f[19]);
  r->sha256.clear();
  if (!hashed) return true;
  if (!ParseTimeColumns(f, r, why)) return false;
  if (!IsSha256Hex(f[22])) return bad("sha256 (64 hex digits)", f[22]);
  r->sha256 = f[22];
  return true;
}

std::vector<RecordedBracket> BracketsOfRows(const std::vector<FrameRecord>& rows) {
  std::vector<RecordedBracket> brackets;
  std::map<std::int64_t, size_t> where;
  std::map<std::int64_t, std::map<int, const FrameRecord*>> positions;
  for (const FrameRecord& row : rows) {
    if (where.find(row.bracket_id) == where.end()) {
      where[row.bracket_id] = brackets.size();
      brackets.emplace_back();
      brackets.back().bracket_id = row.bracket_id;
    }
    brackets[where[row.bracket_id]].bracket_size = row.bracket_size;
    positions[row.bracket_id][row.frame_in_bracket] = &row;
  }
  for (RecordedBracket& bracket : brackets) {
    for (const auto& [position, row] : positions[bracket.bracket_id]) {
      if (position < bracket.bracket_size) bracket.frames.push_back(*row);
    }
    bracket.complete = static_cast<int>(bracket.frames.size()) == bracket.bracket_size;
  }
  return brackets;
}


std::string ReadFramesCsvText(const std::string& dir) {
  const std::string path = (fs::path(dir) / kFramesCsv).string();
  std::string text, why;
  if (!ReadRegularFile(path, kMaxRecordingTextBytes, &text, &why)) {
    throw RecordingError(path + " " + why + ": not a recording directory (frames.csv missing or "
                         "unreadable). Give the directory that holds recording.yaml and "
                         "frames.csv.");
  }
  return text;
}

void RefuseLinkedRecordingParts(const std::string& dir) {
  const std::string linked = LinkedRecordingPart(dir);
  if (!linked.empty()) throw RecordingError(LinkedPartMessage(dir, linked) + ".");
}

[[noreturn]] void ThrowRecordingIssue(const std::string& dir, const RecordingIssue& issue) {
  std::string where = (fs::path(dir) / issue.file).string();
  if (issue.line > 0) where += ":" + std::to_string(issue.line);
  throw RecordingError(where + ": " + issue.message +
                       "; run `irdist check` for a full report and repair or delete the row.");
}


const char* CompletionName(Completion completion) {
  switch (completion) {
    case Completion::kRunning:
      return "running";
    case Completion::kComplete:
      return "complete";
    case Completion::kCut:
      return "cut";
  }
  return "running";
}

// The format 1 header (no sha256 column).
static const std::string& FramesCsvHeaderV1() {
  static const std::string header =
      "index,file,bracket_id,frame_in_bracket,bracket_size,role,requested_exposure_us,"
      "actual_exposure_us,exposure_source,bias_ma_set,bias_ma_measured,slide_mm,pan_deg,tilt_deg,"
      "theta_deg,repeat,camera_frame_id,camera_timestamp_ns,host_time_ns,status";
  return header;
}

const std::string& FramesCsvHeader() {
  static const std::string header = FramesCsvHeaderV1() + ",utc_time,host_monotonic_ns,sha256";
  return header;
}

// --- RecordedBracket --------------------------------------------------------------------------

const FrameRecord* RecordedBracket::Reference() const {
  for (const auto& frame : frames) {
    if (frame.role == FrameRole::kReference) return &frame;
  }
  return nullptr;
}

std::vector<const FrameRecord*> RecordedBracket::Measurements() const {
  std::vector<const FrameRecord*> out;
  for (const auto& frame : frames) {
    if (frame.role == FrameRole::kMeasurement) out.push_back(&frame);
  }
  return out;
}

// --- Parsing, shared by every reader ----------------------------------------------------------


FramesCsv ParseFramesCsv(const std::string& text) {
  FramesCsv csv;
  const CsvLines lines = SplitLines(text);
  csv.partial_last = lines.partial_last;
  csv.complete_bytes = lines.complete_bytes;
  csv.hashed = !lines.lines.empty() && lines.lines[0] == FramesCsvHeader();
  if (lines.lines.empty() || (!csv.hashed && lines.lines[0] != FramesCsvHeaderV1())) {
    csv.errors.push_back({kFramesCsv, 1,
                          "header line is not the irdist frames.csv header (format " +
                              std::to_string(kRecordingFormatVersion) + ")"});
    return csv;
  }
  const size_t complete_lines = lines.lines.size() - (lines.partial_last ? 1 : 0);
  if (lines.partial_last) {
    csv.warnings.push_back({kFramesCsv, static_cast<int>(lines.lines.size()),
                            "last line has no end of line (cut mid-write); ignored"});
  }
  IndexTracker indices;
  std::map<std::pair<std::int64_t, int>, int> position_line;
  for (size_t i = 1; i < complete_lines; ++i) {
    FrameRecord row;
    std::string why;
    row.line = static_cast<int>(i + 1);
    if (!ParseFramesCsvRow(lines.lines[i], &row, &why, csv.hashed)) {
      csv.errors.push_back({kFramesCsv, row.line, "bad row: " + why});
      continue;
    }
    why = RowBoundsRefusal(row);
    if (!why.empty()) {
      csv.errors.push_back({kFramesCsv, row.line, "bad row: " + why});
      continue;
    }
    row.line = static_cast<int>(i + 1);
    why = indices.Add(row);
    if (!why.empty()) csv.errors.push_back({kFramesCsv, row.line, why});
    AddSupersededWarning(row, &position_line, &csv.warnings);
    csv.rows.push_back(std::move(row));
  }
  return csv;
}

RecordingHeader ParseRecordingHeader(const std::string& text, const std::string& file) {
  TextFiles files;
  try {
    return ParseHeaderFields(text, file, &files);
  } catch (const InputError& error) {
    throw RecordingError(std::string(error.what()) + "; fix recording.yaml by hand.");
  }
}

RecordingHeader ReadRecordingHeader(const std::string& dir) { return ReadHeader(dir); }


// --- RecordingReader --------------------------------------------------------------------------


RecordingReader::RecordingReader(const std::string& dir)
    : dir_(dir), header_((RefuseLinkedRecordingParts(dir), ReadHeader(dir))) {
  FramesCsv csv = ParseFramesCsv(ReadFramesCsvText(dir));
  if (!csv.errors.empty()) ThrowRecordingIssue(dir, csv.errors.front());
  rows_ = std::move(csv.rows);
}

std::vector<RecordedBracket> RecordingReader::Brackets() const { return BracketsOfRows(rows_); }

std::set<std::int64_t> RecordingReader::CompleteBracketIds() const {
  std::set<std::int64_t> ids;
  for (const auto& bracket : Brackets()) {
    if (bracket.complete) ids.insert(bracket.bracket_id);
  }
  return ids;
}

cv::Mat RecordingReader::LoadImage(const FrameRecord& row) const {
  std::string why;
  cv::Mat image = LoadFramePng(dir_, row, &why);
  if (image.empty()) {
    throw RecordingError((fs::path(dir_) / row.file).string() + " (frames.csv:" +
                         std::to_string(row.line) + "): " + why +
                         "; run `irdist check` on the recording.");
  }
  return image;
}

}  // namespace irdist
