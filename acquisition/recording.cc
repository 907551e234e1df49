#include "acquisition/recording.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <sstream>
#include <utility>

#include <boost/crc.hpp>
#include <opencv2/imgcodecs.hpp>

#include "base/regular_file.h"
#include "base/utc_time.h"
#include "base/yaml_fields.h"

namespace irdist {
namespace {

namespace fs = std::filesystem;

constexpr char kYaml[] = "recording.yaml";
constexpr char kCsv[] = "frames.csv";
constexpr char kFramesDir[] = "frames";
constexpr int kColumns = 22;
// Recordings written before the time columns (utc_time, host_monotonic_ns) end at status.
constexpr int kColumnsBeforeTime = 20;


std::string Errno() { return std::strerror(errno); }

std::string FrameFileName(std::int64_t index) {
  char name[48];
  std::snprintf(name, sizeof(name), "frames/%06lld.png", static_cast<long long>(index));
  return name;
}

std::string FormatDouble(double value) {
  if (std::isnan(value)) return "";
  char text[64];
  std::snprintf(text, sizeof(text), "%.12g", value);
  return text;
}

// Writes all of `data` to `fd`, retrying short writes.
bool WriteAll(int fd, const void* data, size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    p += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

// fsync of a folder, so that a rename in it survives a crash.
void SyncFolder(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) throw RecordingError("cannot open folder " + dir + " to sync it: " + Errno() + ".");
  const bool ok = ::fsync(fd) == 0 || errno == EINVAL;  // EINVAL: the file system cannot sync
  const int saved = errno;
  ::close(fd);
  if (!ok) {
    errno = saved;
    throw RecordingError("cannot sync folder " + dir + ": " + Errno() + ". Is the disk failing?");
  }
}

// Writes `data` to `tmp` (created or truncated) and syncs it; on failure removes it and throws.
void WriteSynced(const std::string& tmp, const void* data, size_t size) {
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    throw RecordingError("cannot create " + tmp + ": " + Errno() +
                         ". Check the disk and permissions of the recording directory.");
  }
  const bool ok = WriteAll(fd, data, size) && ::fsync(fd) == 0;
  const int saved = errno;
  ::close(fd);
  if (!ok) {
    ::unlink(tmp.c_str());
    errno = saved;
    throw RecordingError("cannot write " + tmp + ": " + Errno() + ". Is the disk full?");
  }
}

void RenameOrThrow(const std::string& from, const std::string& to) {
  if (::rename(from.c_str(), to.c_str()) != 0) {
    throw RecordingError("cannot rename " + from + " to " + to + ": " + Errno() + ".");
  }
}

// Writes `data` to path + ".tmp", syncs it, renames it to `path` and syncs the folder: after a
// crash `path` is either the old or the new file, complete.
void WriteFileAtomically(const std::string& path, const void* data, size_t size) {
  const std::string tmp = path + ".tmp";
  WriteSynced(tmp, data, size);
  RenameOrThrow(tmp, path);
  SyncFolder(fs::path(path).parent_path().string());
}

constexpr std::int64_t kMaxPngBytes = std::int64_t{1} << 28;
constexpr std::int64_t kMaxTextBytes = std::int64_t{1} << 30;

// A CRC-32 of a text, as 8 hex digits: recording.yaml's check of recipe.yaml and rig.yaml.
std::string Crc32Hex(const std::string& text) {
  boost::crc_32_type crc;
  crc.process_bytes(text.data(), text.size());
  char hex[16];
  std::snprintf(hex, sizeof(hex), "%08x", static_cast<unsigned>(crc.checksum()));
  return hex;
}

// An empty field for 0: the camera gave no timestamp, the host's monotonic time was not recorded.
template <typename Int>
std::string NonZeroOrEmpty(Int value) { return value == 0 ? "" : std::to_string(value); }

// `time_columns` false: the layout of a recording written before them (a resumed old recording).
std::string FormatRow(const FrameRecord& r, bool time_columns = true) {
  std::ostringstream out;
  out << r.index << ',' << r.file << ',' << r.bracket_id << ',' << r.frame_in_bracket << ','
      << r.bracket_size << ',' << FrameRoleName(r.role) << ','
      << FormatDouble(r.requested_exposure_us) << ',' << FormatDouble(r.actual_exposure_us) << ','
      << (r.exposure_from_chunk ? "chunk" : "readback") << ',' << FormatDouble(r.bias_ma_set)
      << ',' << FormatDouble(r.bias_ma_measured) << ',' << FormatDouble(r.slide_mm) << ','
      << FormatDouble(r.pan_deg) << ',' << FormatDouble(r.tilt_deg) << ','
      << FormatDouble(r.theta_deg) << ',' << r.repeat << ',' << r.camera_frame_id << ','
      << NonZeroOrEmpty(r.camera_timestamp_ns) << ',' << r.host_time_ns << ',' << r.status;
  if (time_columns) {
    out << ',' << FormatUtcIso8601(r.host_time_ns) << ',' << NonZeroOrEmpty(r.host_monotonic_ns);
  }
  out << '\n';
  return out.str();
}

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) fields.push_back(field);
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

bool ParseInt(const std::string& text, std::int64_t* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (errno != 0 || end == nullptr || *end != '\0') return false;
  *value = v;
  return true;
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
  if (!f[21].empty() && (!ParseInt(f[21], &r->host_monotonic_ns) || r->host_monotonic_ns < 0)) {
    *why = "bad host_monotonic_ns '" + f[21] + "'";
    return false;
  }
  return true;
}

// Parses one frames.csv data line; on failure says which column is wrong.
bool ParseRow(const std::string& line, FrameRecord* r, std::string* why, bool time_columns = true) {
  const std::vector<std::string> f = Split(line);
  const int columns = time_columns ? kColumns : kColumnsBeforeTime;
  if (static_cast<int>(f.size()) != columns) {
    *why = "expected " + std::to_string(columns) + " columns, found " + std::to_string(f.size());
    return false;
  }
  auto bad = [&](const char* column, const std::string& text) {
    *why = std::string("bad ") + column + " '" + text + "'";
    return false;
  };
  std::int64_t v = 0;
  if (!ParseInt(f[0], &r->index) || r->index < 0) return bad("index", f[0]);
  r->file = f[1];
  if (r->file != FrameFileName(r->index)) {
    *why = "file '" + f[1] + "' is not " + FrameFileName(r->index) +
           " (a row names the PNG of its own index, inside the recording)";
    return false;
  }
  if (!ParseInt(f[2], &r->bracket_id)) return bad("bracket_id", f[2]);
  if (!ParseInt(f[3], &v) || v < 0) return bad("frame_in_bracket", f[3]);
  r->frame_in_bracket = static_cast<int>(v);
  if (!ParseInt(f[4], &v) || v <= r->frame_in_bracket) return bad("bracket_size", f[4]);
  r->bracket_size = static_cast<int>(v);
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
  if (!ParseInt(f[15], &v) || v < 0) return bad("repeat", f[15]);
  r->repeat = static_cast<int>(v);
  if (!ParseUint(f[16], &r->camera_frame_id)) return bad("camera_frame_id", f[16]);
  if (!f[17].empty() && !ParseUint(f[17], &r->camera_timestamp_ns)) {
    return bad("camera_timestamp_ns", f[17]);
  }
  if (!ParseInt(f[18], &r->host_time_ns)) return bad("host_time_ns", f[18]);
  r->status = f[19];
  if (r->status != "ok" && r->status != "retried") return bad("status", f[19]);
  return !time_columns || ParseTimeColumns(f, r, why);
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
    warnings->push_back({kCsv, row.line,
                         "bracket " + std::to_string(row.bracket_id) + " frame " +
                             std::to_string(row.frame_in_bracket) + " supersedes line " +
                             std::to_string(earlier->second) + " (re-acquired)"});
  }
  (*position_line)[position] = row.line;
}

namespace yf = yaml_fields;

constexpr char kRecipeFile[] = "recipe.yaml";
constexpr char kRigFile[] = "rig.yaml";

void ParseHeaderImage(const yf::MapReader& root, RecordingHeader* h) {
  const yf::MapReader image(root.Require("image"), root.File(), "image",
                            {"encoding", "bit_depth", "pixel_format"});
  if (image.String("encoding", "png16") != "png16") {
    yf::Fail(root.File(), image.Get("encoding").Mark(), "image.encoding must be png16");
  }
  const YAML::Node depth = image.Require("bit_depth");
  h->bit_depth = yf::AsInteger(depth, root.File(), "image.bit_depth");
  if (h->bit_depth < 1 || h->bit_depth > 16) {
    yf::Fail(root.File(), depth.Mark(),
             "image.bit_depth " + std::to_string(h->bit_depth) +
                 " is impossible for a 16-bit PNG; it must be 1..16 (8 for Mono8, 12 for Mono12)");
  }
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
  if (!file->empty() && *file != kRecipeFile && *file != kRigFile) {
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

struct TextFiles {
  std::string recipe_file, recipe_crc, rig_file, rig_crc;
};

RecordingHeader ParseHeaderFields(const std::string& text, const std::string& path,
                                  TextFiles* files) {
  const yf::MapReader root(yf::Parse(text, path), path, "recording.yaml",
                           {"format", "format_version", "completion", "software_version",
                            "start_time", "end_time", "frame_count", "resumed", "image", "camera",
                            "station", "recipe", "rig"});
  if (root.String("format", "") != "irdist-recording") {
    yf::Fail(path, root.Mark(), "'format' is not irdist-recording; this is not an irdist "
                                "recording header");
  }
  RecordingHeader h;
  h.format_version = root.Integer("format_version", 0);
  if (h.format_version != kRecordingFormatVersion) {
    yf::Fail(path, root.Mark(), "format_version " + std::to_string(h.format_version) +
                                    " is not supported (this irdist reads version " +
                                    std::to_string(kRecordingFormatVersion) + ")");
  }
  h.completion = ParseCompletionField(root);
  h.software_version = root.String("software_version", "");
  h.start_time = root.String("start_time", "");
  h.end_time = root.String("end_time", "");
  h.frame_count = static_cast<std::int64_t>(root.Number("frame_count", -1));
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
  if (!ReadRegularFile(path, kMaxTextBytes, &text, &why)) {
    throw RecordingError(path + " " + why + "; recording.yaml names it as the text used. "
                         "Restore it from a copy of the recording.");
  }
  if (Crc32Hex(text) != crc) {
    throw RecordingError(path + ": its CRC-32 is " + Crc32Hex(text) + ", recording.yaml says " +
                         crc + "; the file was edited. Restore it from a copy of the recording.");
  }
  return text;
}

RecordingHeader ReadHeader(const std::string& dir) {
  const std::string path = (fs::path(dir) / kYaml).string();
  std::string text, why;
  if (!ReadRegularFile(path, kMaxTextBytes, &text, &why)) {
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

std::string HeaderYaml(const RecordingHeader& h) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << "irdist-recording";
  out << YAML::Key << "format_version" << YAML::Value << h.format_version;
  out << YAML::Key << "completion" << YAML::Value << CompletionName(h.completion);
  out << YAML::Key << "software_version" << YAML::Value << h.software_version;
  out << YAML::Key << "start_time" << YAML::Value << h.start_time;
  out << YAML::Key << "end_time" << YAML::Value << h.end_time;
  out << YAML::Key << "frame_count" << YAML::Value << h.frame_count;
  out << YAML::Key << "resumed" << YAML::Value << YAML::Flow << h.resumed;
  out << YAML::Key << "image" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "encoding" << YAML::Value << "png16";
  out << YAML::Key << "bit_depth" << YAML::Value << h.bit_depth;
  out << YAML::Key << "pixel_format" << YAML::Value << h.pixel_format;
  out << YAML::EndMap;
  out << YAML::Key << "camera" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "vendor" << YAML::Value << h.camera.vendor;
  out << YAML::Key << "model" << YAML::Value << h.camera.model;
  out << YAML::Key << "serial" << YAML::Value << h.camera.serial;
  out << YAML::Key << "firmware" << YAML::Value << h.camera.firmware;
  out << YAML::Key << "address" << YAML::Value << h.camera.address;
  out << YAML::Key << "features" << YAML::Value << YAML::BeginMap;
  for (const auto& [key, value] : h.camera_features) {
    out << YAML::Key << key << YAML::Value << YAML::DoubleQuoted << value;
  }
  out << YAML::EndMap << YAML::EndMap;
  out << YAML::Key << "station" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "identity" << YAML::Value << h.station_identity << YAML::EndMap;
  for (const auto& [key, path, file, text] :
       {std::tuple<const char*, const std::string&, const char*, const std::string&>{
            "recipe", h.recipe_path, kRecipeFile, h.recipe_text},
        std::tuple<const char*, const std::string&, const char*, const std::string&>{
            "rig", h.rig_path, kRigFile, h.rig_text}}) {
    out << YAML::Key << key << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "path" << YAML::Value << YAML::DoubleQuoted << path;
    out << YAML::Key << "file" << YAML::Value << file;
    out << YAML::Key << "crc32" << YAML::Value << YAML::DoubleQuoted << Crc32Hex(text);
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

int OpenCsvForAppend(const std::string& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (fd < 0) {
    throw RecordingError("cannot open " + path + " for appending: " + Errno() + ".");
  }
  return fd;
}


// The writer's lock: flock on <dir>/writer.lock, which holds the writer's pid. Returns the fd.
int AcquireWriterLock(const std::string& dir) {
  const std::string path = (fs::path(dir) / "writer.lock").string();
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) throw RecordingError("cannot create " + path + ": " + Errno() + ".");
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int saved = errno;
    char pid[32] = {0};
    const ssize_t n = ::pread(fd, pid, sizeof(pid) - 1, 0);
    ::close(fd);
    if (saved != EWOULDBLOCK) {
      errno = saved;
      throw RecordingError("cannot lock " + path + ": " + Errno() + ".");
    }
    std::string holder = n > 0 ? std::string(pid, static_cast<size_t>(n)) : "?";
    while (!holder.empty() && (holder.back() == '\n' || holder.back() == ' ')) holder.pop_back();
    throw RecordingError("the recording " + dir + " is being written by process " + holder +
                         " (it holds " + path + "); wait for that run to end or stop it, then "
                         "resume.");
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, pid.data(), pid.size(), 0) < 0) {
    // The lock holds without the pid; a refused writer then names "?".
  }
  return fd;
}

// Files in frames/ a resumed run does not keep: temp files and PNGs from `next_index` on.
std::vector<std::string> Leftovers(const std::string& dir, std::int64_t next_index) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(fs::path(dir) / kFramesDir, ec)) {
    const std::string name = entry.path().filename().string();
    std::int64_t index = -1;
    const bool tmp = name.size() > 4 && name.substr(name.size() - 4) == ".tmp";
    const bool png = name.size() > 4 && name.substr(name.size() - 4) == ".png" &&
                     ParseInt(name.substr(0, name.size() - 4), &index);
    if (tmp || (png && index >= next_index)) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

// Moves `names` from frames/ to <dir>/set-aside-<time>/ (never deleted). Returns that folder.
std::string MoveAside(const std::string& dir, const std::vector<std::string>& names) {
  if (names.empty()) return "";
  std::string stamp = UtcNowIso8601();
  std::replace(stamp.begin(), stamp.end(), ':', '-');
  const fs::path aside = fs::path(dir) / ("set-aside-" + stamp);
  std::error_code ec;
  fs::create_directories(aside, ec);
  if (ec) throw RecordingError("cannot create " + aside.string() + ": " + ec.message() + ".");
  for (const std::string& name : names) {
    fs::rename(fs::path(dir) / kFramesDir / name, aside / name, ec);
    if (ec) {
      throw RecordingError("cannot move " + name + " to " + aside.string() + ": " + ec.message() +
                           "; nothing was deleted.");
    }
  }
  SyncFolder((fs::path(dir) / kFramesDir).string());
  return aside.string();
}

// Brackets in order of first appearance; the last row of each (bracket, position) wins (a
// resumed run re-acquires incomplete brackets). The one completeness rule of every reader.
std::vector<RecordedBracket> BracketsOf(const std::vector<FrameRecord>& rows) {
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

// Reads and decodes a frame's PNG; an empty Mat and `why` when refused.
cv::Mat LoadFrame(const std::string& dir, const FrameRecord& row, std::string* why) {
  std::string bytes;
  if (!ReadRegularFile((fs::path(dir) / row.file).string(), kMaxPngBytes, &bytes, why)) {
    return cv::Mat();
  }
  return DecodeFramePng(std::vector<unsigned char>(bytes.begin(), bytes.end()), why);
}

std::uint32_t BigEndian32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

// The text of frames.csv (a regular file, read without blocking).
std::string ReadCsvText(const std::string& dir) {
  const std::string path = (fs::path(dir) / kCsv).string();
  std::string text, why;
  if (!ReadRegularFile(path, kMaxTextBytes, &text, &why)) {
    throw RecordingError(path + " " + why + ": not a recording directory (frames.csv missing or "
                         "unreadable). Give the directory that holds recording.yaml and "
                         "frames.csv.");
  }
  return text;
}

[[noreturn]] void ThrowIssue(const std::string& dir, const RecordingIssue& issue) {
  std::string where = (fs::path(dir) / issue.file).string();
  if (issue.line > 0) where += ":" + std::to_string(issue.line);
  throw RecordingError(where + ": " + issue.message +
                       "; run `irdist check` for a full report and repair or delete the row.");
}
}  // namespace

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

const std::string& FramesCsvHeader() {
  static const std::string header =
      "index,file,bracket_id,frame_in_bracket,bracket_size,role,requested_exposure_us,"
      "actual_exposure_us,exposure_source,bias_ma_set,bias_ma_measured,slide_mm,pan_deg,tilt_deg,"
      "theta_deg,repeat,camera_frame_id,camera_timestamp_ns,host_time_ns,status,utc_time,"
      "host_monotonic_ns";
  return header;
}

// The header of recordings written before the time columns: read, and resumed in their layout.
static std::string FramesCsvHeaderBeforeTime() {
  const std::string& header = FramesCsvHeader();
  return header.substr(0, header.rfind(",utc_time,"));
}

FrameRecord RecordFromFrame(const BracketFrame& frame, int bracket_size) {
  FrameRecord r;
  r.frame_in_bracket = frame.plan.frame_in_bracket;
  r.bracket_size = bracket_size;
  r.role = frame.plan.role;
  r.requested_exposure_us = frame.requested_exposure_us;
  r.actual_exposure_us = frame.actual_exposure_us;
  r.exposure_from_chunk = frame.exposure_from_chunk;
  r.bias_ma_measured = std::nan("");
  r.camera_frame_id = frame.frame_id;
  r.camera_timestamp_ns = frame.timestamp_ns;
  r.host_time_ns = frame.host_time_ns;
  r.host_monotonic_ns = frame.host_monotonic_ns;
  r.status = frame.retries > 0 ? "retried" : "ok";
  return r;
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
  csv.time_columns = !lines.lines.empty() && lines.lines[0] == FramesCsvHeader();
  if (lines.lines.empty() ||
      (!csv.time_columns && lines.lines[0] != FramesCsvHeaderBeforeTime())) {
    csv.errors.push_back({kCsv, 1, "header line is not the irdist frames.csv header (format " +
                                       std::to_string(kRecordingFormatVersion) + ")"});
    return csv;
  }
  const size_t complete_lines = lines.lines.size() - (lines.partial_last ? 1 : 0);
  if (lines.partial_last) {
    csv.warnings.push_back({kCsv, static_cast<int>(lines.lines.size()),
                            "last line has no end of line (cut mid-write); ignored"});
  }
  IndexTracker indices;
  std::map<std::pair<std::int64_t, int>, int> position_line;
  for (size_t i = 1; i < complete_lines; ++i) {
    FrameRecord row;
    std::string why;
    row.line = static_cast<int>(i + 1);
    if (!ParseRow(lines.lines[i], &row, &why, csv.time_columns)) {
      csv.errors.push_back({kCsv, row.line, "bad row: " + why});
      continue;
    }
    row.line = static_cast<int>(i + 1);
    why = indices.Add(row);
    if (!why.empty()) csv.errors.push_back({kCsv, row.line, why});
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

cv::Mat DecodeFramePng(const std::vector<unsigned char>& bytes, std::string* why) {
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (bytes.size() < 33 || std::memcmp(bytes.data(), kSignature, 8) != 0 ||
      std::memcmp(bytes.data() + 12, "IHDR", 4) != 0) {
    *why = "not a PNG file (no PNG signature and IHDR header)";
    return cv::Mat();
  }
  const std::int64_t width = BigEndian32(bytes.data() + 16);
  const std::int64_t height = BigEndian32(bytes.data() + 20);
  if (width < 1 || height < 1 || width > kMaxFrameSidePx || height > kMaxFrameSidePx ||
      width * height > kMaxFramePixels) {
    *why = "PNG header claims " + std::to_string(width) + " x " + std::to_string(height) +
           " px, beyond the limit of " + std::to_string(kMaxFrameSidePx) + " px a side and " +
           std::to_string(kMaxFramePixels) + " px; the file is damaged or not a frame";
    return cv::Mat();
  }
  if (bytes[24] != 16 || bytes[25] != 0) {
    *why = "not a single-channel 16-bit PNG (bit depth " + std::to_string(bytes[24]) +
           ", colour type " + std::to_string(bytes[25]) + ")";
    return cv::Mat();
  }
  cv::Mat image;
  try {
    image = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& error) {
    image = cv::Mat();
  }
  if (image.empty() || image.type() != CV_16UC1) {
    *why = "damaged PNG: its image data cannot be decoded as 16-bit gray";
    return cv::Mat();
  }
  return image;
}

// --- RecordingWriter --------------------------------------------------------------------------

RecordingWriter::RecordingWriter(std::string dir, RecordingHeader header, std::int64_t next_index)
    : dir_(std::move(dir)), header_(std::move(header)), next_index_(next_index) {}

RecordingWriter::~RecordingWriter() {
  // Staged files stay (as after a kill): not part of the recording; a resume moves them aside.
  if (csv_fd_ >= 0) ::close(csv_fd_);
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the lock
}

void RecordingWriter::WriteHeader() {
  const std::string text = HeaderYaml(header_);
  WriteFileAtomically((fs::path(dir_) / kYaml).string(), text.data(), text.size());
}

// recipe.yaml and rig.yaml beside recording.yaml: the texts as used, byte for byte.
static void WriteTextsBeside(const std::string& dir, const RecordingHeader& header) {
  WriteFileAtomically((fs::path(dir) / kRecipeFile).string(), header.recipe_text.data(),
                      header.recipe_text.size());
  WriteFileAtomically((fs::path(dir) / kRigFile).string(), header.rig_text.data(),
                      header.rig_text.size());
}

static void CreateCsv(const std::string& csv_path) {
  const std::string line = FramesCsvHeader() + "\n";
  const int fd = ::open(csv_path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) throw RecordingError("cannot create " + csv_path + ": " + Errno() + ".");
  const bool ok = WriteAll(fd, line.data(), line.size()) && ::fsync(fd) == 0;
  const int saved = errno;
  ::close(fd);
  errno = saved;
  if (!ok) throw RecordingError("cannot write " + csv_path + ": " + Errno() + ".");
}

std::unique_ptr<RecordingWriter> RecordingWriter::Open(const std::string& dir,
                                                       RecordingHeader header) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_empty(dir, ec)) {
    throw RecordingError("recording directory " + dir +
                         " exists and is not empty; choose a new directory (or resume it).");
  }
  fs::create_directories(fs::path(dir) / kFramesDir, ec);
  if (ec) {
    throw RecordingError("cannot create " + (fs::path(dir) / kFramesDir).string() + ": " +
                         ec.message() + ". Check the path and permissions.");
  }
  const int lock_fd = AcquireWriterLock(dir);
  if (header.start_time.empty()) header.start_time = UtcNowIso8601();
  header.completion = Completion::kRunning;
  header.end_time.clear();
  header.frame_count = -1;
  header.format_version = kRecordingFormatVersion;
  std::unique_ptr<RecordingWriter> writer(new RecordingWriter(dir, std::move(header), 0));
  writer->lock_fd_ = lock_fd;
  const std::string csv_path = (fs::path(dir) / kCsv).string();
  CreateCsv(csv_path);
  WriteTextsBeside(dir, writer->header_);
  writer->WriteHeader();
  writer->csv_fd_ = OpenCsvForAppend(csv_path);
  return writer;
}

std::unique_ptr<RecordingWriter> RecordingWriter::Resume(const std::string& dir) {
  const int lock_fd = AcquireWriterLock(dir);
  std::unique_ptr<RecordingWriter> writer(new RecordingWriter(dir, RecordingHeader{}, 0));
  writer->lock_fd_ = lock_fd;  // released by the writer's destructor on every path
  RecordingHeader header = ReadHeader(dir);
  if (header.completion == Completion::kComplete) {
    throw RecordingError((fs::path(dir) / kYaml).string() +
                         ": the recording is complete; there is nothing to resume. "
                         "Start a new recording instead.");
  }
  const std::string csv_path = (fs::path(dir) / kCsv).string();
  const FramesCsv csv = ParseFramesCsv(ReadCsvText(dir));
  if (!csv.errors.empty()) ThrowIssue(dir, csv.errors.front());
  std::int64_t next_index = 0;
  for (const FrameRecord& row : csv.rows) next_index = std::max(next_index, row.index + 1);
  // The partial last line (the row in flight) is dropped; leftover files are moved aside.
  if (csv.partial_last && ::truncate(csv_path.c_str(), static_cast<off_t>(csv.complete_bytes)) != 0) {
    throw RecordingError("cannot truncate the partial last line of " + csv_path + ": " + Errno());
  }
  const std::vector<std::string> leftovers = Leftovers(dir, next_index);
  writer->set_aside_dir_ = MoveAside(dir, leftovers);
  for (const std::string& name : leftovers) writer->set_aside_.push_back("frames/" + name);
  header.completion = Completion::kRunning;
  header.end_time.clear();
  header.frame_count = -1;
  header.resumed.push_back(UtcNowIso8601());
  writer->header_ = std::move(header);
  writer->next_index_ = next_index;
  writer->time_columns_ = csv.time_columns;  // an older recording continues in its own layout
  writer->WriteHeader();
  writer->csv_fd_ = OpenCsvForAppend(csv_path);
  return writer;
}

// Checks the row against the reader's rules: a row the reader would refuse is a bug of the
// caller, refused before anything reaches the disk.
static void CheckRowReadable(const std::string& row, std::int64_t index, bool time_columns) {
  FrameRecord parsed;
  std::string why;
  std::string line = row;
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
  IRDIST_CHECK(ParseRow(line, &parsed, &why, time_columns), "frame ", index,
               " would be unreadable in frames.csv: ", why);
}

// PNG settings of frames (zlib level and strategy): see EncodeFramePng.
constexpr int kPngLevel = 1;
constexpr int kPngStrategy = cv::IMWRITE_PNG_STRATEGY_DEFAULT;

// The frame as a lossless 16-bit PNG (8-bit frames widened, values unchanged). zlib level 1, default
// strategy: on a 256 x 256 Mono12 frame (bench/acquisition, BM_EncodePng) 3.2 ms of CPU and 44% of
// the raw size; Huffman-only and RLE cost the same or more, level 3 twice the time for 3% less,
// level 0 (stored) half the time for 2.3x the size. The encode overlaps the next exposure.
static std::vector<uchar> EncodeFramePng(const cv::Mat& image, std::int64_t index) {
  IRDIST_CHECK(!image.empty() && image.channels() == 1 &&
                   (image.depth() == CV_16U || image.depth() == CV_8U),
               "a frame must be a single-channel 8- or 16-bit image");
  cv::Mat image16;
  if (image.depth() == CV_16U) {
    image16 = image;
  } else {
    image.convertTo(image16, CV_16U);  // values unchanged
  }
  std::vector<uchar> png;
  if (!cv::imencode(".png", image16, png, {cv::IMWRITE_PNG_COMPRESSION, kPngLevel,
                                            cv::IMWRITE_PNG_STRATEGY, kPngStrategy})) {
    throw RecordingError("cannot encode frame " + std::to_string(index) + " as PNG.");
  }
  return png;
}

void RecordingWriter::ThrowIfFailed() const {
  IRDIST_CHECK(!closed_, "write after Close()");
  if (!first_error_.empty()) {
    throw RecordingError("the recording stopped at its first write error: " + first_error_);
  }
}

std::int64_t RecordingWriter::Stage(const cv::Mat& image) {
  ThrowIfFailed();
  const std::int64_t index = next_index_ + static_cast<std::int64_t>(staged_.size());
  const std::vector<uchar> png = EncodeFramePng(image, index);
  const std::string tmp = (fs::path(dir_) / FrameFileName(index)).string() + ".tmp";
  try {
    WriteSynced(tmp, png.data(), png.size());
  } catch (const RecordingError& error) {
    first_error_ = error.what();
    throw;
  }
  staged_.push_back(tmp);
  return index;
}

// Each record's index and file, from the staged frames; every row checked readable.
std::vector<std::string> RecordingWriter::StagedRows(std::vector<FrameRecord>* records) const {
  IRDIST_CHECK(records->size() == staged_.size(), "CommitStaged() needs one record per staged frame (",
               records->size(), " for ", staged_.size(), ")");
  std::vector<std::string> rows;
  for (std::size_t i = 0; i < records->size(); ++i) {
    FrameRecord& record = (*records)[i];
    record.index = next_index_ + static_cast<std::int64_t>(i);
    record.file = FrameFileName(record.index);
    rows.push_back(FormatRow(record, time_columns_));
    CheckRowReadable(rows.back(), record.index, time_columns_);
  }
  return rows;
}

std::vector<FrameRecord> RecordingWriter::CommitStaged(std::vector<FrameRecord> records) {
  ThrowIfFailed();
  std::string rows;
  for (const std::string& row : StagedRows(&records)) rows += row;
  try {
    for (std::size_t i = 0; i < staged_.size(); ++i) {
      RenameOrThrow(staged_[i], (fs::path(dir_) / records[i].file).string());
    }
    if (!staged_.empty()) SyncFolder((fs::path(dir_) / kFramesDir).string());
    // The rows only after their files are durable: a row never names a missing frame.
    if (!WriteAll(csv_fd_, rows.data(), rows.size()) || ::fsync(csv_fd_) != 0) {
      throw RecordingError("cannot append to " + (fs::path(dir_) / kCsv).string() + ": " +
                           Errno() + ". Is the disk full?");
    }
  } catch (const RecordingError& error) {
    first_error_ = error.what();
    throw;
  }
  next_index_ += static_cast<std::int64_t>(staged_.size());
  staged_.clear();
  return records;
}

void RecordingWriter::DropStaged() {
  for (const std::string& tmp : staged_) ::unlink(tmp.c_str());  // never visible; best effort
  staged_.clear();
}

FrameRecord RecordingWriter::Append(const cv::Mat& image, FrameRecord record) {
  IRDIST_CHECK(staged_.empty(), "Append() with staged frames: commit or drop them first");
  record.index = next_index_;
  record.file = FrameFileName(record.index);
  // Checked before anything reaches the disk.
  CheckRowReadable(FormatRow(record, time_columns_), record.index, time_columns_);
  Stage(image);
  return CommitStaged({std::move(record)}).front();
}

void RecordingWriter::Close(Completion completion) {
  IRDIST_CHECK(completion != Completion::kRunning, "Close() needs complete or cut");
  if (closed_) return;
  DropStaged();
  closed_ = true;
  if (csv_fd_ >= 0) {
    const bool synced = ::fsync(csv_fd_) == 0;
    ::close(csv_fd_);
    csv_fd_ = -1;
    if (!synced && first_error_.empty()) first_error_ = "cannot sync frames.csv: " + Errno();
  }
  header_.completion = first_error_.empty() ? completion : Completion::kCut;
  header_.end_time = UtcNowIso8601();
  header_.frame_count = next_index_;
  try {
    WriteHeader();
  } catch (const RecordingError&) {
    // After a failed write the first error is the one reported; recording.yaml stays "running",
    // which every reader treats as cut.
    if (first_error_.empty()) throw;
  }
  if (lock_fd_ >= 0) ::close(lock_fd_);  // the recording is closed: another writer may resume it
  lock_fd_ = -1;
}

// --- RecordingReader --------------------------------------------------------------------------

RecordingReader::RecordingReader(const std::string& dir)
    : dir_(dir), header_(ReadHeader(dir)) {
  FramesCsv csv = ParseFramesCsv(ReadCsvText(dir));
  if (!csv.errors.empty()) ThrowIssue(dir, csv.errors.front());
  rows_ = std::move(csv.rows);
}

std::vector<RecordedBracket> RecordingReader::Brackets() const { return BracketsOf(rows_); }

std::set<std::int64_t> RecordingReader::CompleteBracketIds() const {
  std::set<std::int64_t> ids;
  for (const auto& bracket : Brackets()) {
    if (bracket.complete) ids.insert(bracket.bracket_id);
  }
  return ids;
}

cv::Mat RecordingReader::LoadImage(const FrameRecord& row) const {
  std::string why;
  cv::Mat image = LoadFrame(dir_, row, &why);
  if (image.empty()) {
    throw RecordingError((fs::path(dir_) / row.file).string() + " (frames.csv:" +
                         std::to_string(row.line) + "): " + why +
                         "; run `irdist check` on the recording.");
  }
  return image;
}

// --- CheckRecording ---------------------------------------------------------------------------

std::string RecordingCheck::BriefReport() const {
  std::ostringstream out;
  out << "recording " << CompletionName(completion)
      << (completion == Completion::kRunning ? " (the writer did not finish: treat as cut)" : "")
      << ", " << rows << " frames, " << complete_brackets << "/" << brackets
      << " brackets complete, " << errors.size() << " errors, " << warnings.size()
      << " warnings\n";
  auto print = [&out](const char* kind, const Issue& issue) {
    out << kind << ": " << issue.file;
    if (issue.line > 0) out << ":" << issue.line;
    out << ": " << issue.message << "\n";
  };
  for (const auto& issue : errors) print("error", issue);
  for (const auto& issue : warnings) print("warning", issue);
  return out.str();
}

namespace {

// Every row's PNG: readable, 16-bit gray, all of one size.
void CheckFrames(const std::string& dir, const std::vector<FrameRecord>& rows,
                 RecordingCheck* check) {
  cv::Size size;
  for (const FrameRecord& row : rows) {
    std::string why;
    const cv::Mat image = LoadFrame(dir, row, &why);
    const std::string at = " (row at frames.csv:" + std::to_string(row.line) + ")";
    if (image.empty()) {
      check->errors.push_back({row.file, 0, why + at});
    } else if (size.area() == 0) {
      size = image.size();
    } else if (image.size() != size) {
      check->errors.push_back({row.file, 0, "size differs from the first frame" + at});
    }
  }
}

// Files in frames/ without a row, and temp files.
void CheckLeftovers(const std::string& dir, const std::vector<FrameRecord>& rows,
                    RecordingCheck* check) {
  std::set<std::string> files;
  for (const FrameRecord& row : rows) files.insert(row.file);
  std::error_code ec;
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(fs::path(dir) / kFramesDir, ec)) {
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  for (const std::string& name : names) {
    const std::string relative = std::string(kFramesDir) + "/" + name;
    if (name.size() > 4 && name.substr(name.size() - 4) == ".tmp") {
      check->warnings.push_back({relative, 0, "leftover temporary file of a frame in flight"});
    } else if (files.count(relative) == 0) {
      check->warnings.push_back({relative, 0, "orphan file: no row in frames.csv refers to it"});
    }
  }
}

void CheckBrackets(const std::vector<FrameRecord>& rows, RecordingCheck* check) {
  const std::vector<RecordedBracket> brackets = BracketsOf(rows);
  check->brackets = static_cast<std::int64_t>(brackets.size());
  for (const RecordedBracket& bracket : brackets) {
    if (bracket.complete) {
      ++check->complete_brackets;
    } else {
      check->warnings.push_back({kCsv, 0, "bracket " + std::to_string(bracket.bracket_id) +
                                              " is incomplete (" +
                                              std::to_string(bracket.frames.size()) + " of " +
                                              std::to_string(bracket.bracket_size) + " frames)"});
    }
  }
}

void CheckCompletion(const RecordingHeader& header, RecordingCheck* check) {
  switch (check->completion) {
    case Completion::kRunning:
      check->warnings.push_back(
          {kYaml, 0, "completion is 'running': the writer died; the run is cut"});
      break;
    case Completion::kCut:
      check->warnings.push_back({kYaml, 0, "completion is 'cut': the run was stopped early"});
      break;
    case Completion::kComplete:
      if (header.frame_count != check->rows) {
        check->errors.push_back({kYaml, 0, "frame_count " + std::to_string(header.frame_count) +
                                               " but frames.csv has " +
                                               std::to_string(check->rows) + " rows"});
      }
      break;
  }
}

}  // namespace

RecordingCheck CheckRecording(const std::string& dir) {
  RecordingCheck check;
  if (!fs::exists(fs::path(dir) / kYaml) && !fs::exists(fs::path(dir) / kCsv)) {
    throw RecordingError(dir + " is not a recording (no recording.yaml, no frames.csv).");
  }
  RecordingHeader header;
  check.completion = Completion::kRunning;
  bool header_ok = true;
  try {
    header = ReadHeader(dir);
    check.completion = header.completion;
  } catch (const RecordingError& error) {
    check.errors.push_back({kYaml, 0, error.what()});
    header_ok = false;
  }
  FramesCsv csv;
  try {
    csv = ParseFramesCsv(ReadCsvText(dir));
  } catch (const RecordingError& error) {
    check.errors.push_back({kCsv, 0, error.what()});
    return check;
  }
  check.errors.insert(check.errors.end(), csv.errors.begin(), csv.errors.end());
  check.warnings.insert(check.warnings.end(), csv.warnings.begin(), csv.warnings.end());
  check.rows = static_cast<std::int64_t>(csv.rows.size());
  CheckFrames(dir, csv.rows, &check);
  CheckLeftovers(dir, csv.rows, &check);
  CheckBrackets(csv.rows, &check);
  if (header_ok) CheckCompletion(header, &check);
  return check;
}

}  // namespace irdist
