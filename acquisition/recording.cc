#include "acquisition/recording.h"

#include <fcntl.h>
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
#include <sstream>
#include <utility>

#include <opencv2/imgcodecs.hpp>

namespace irdist {
namespace {

namespace fs = std::filesystem;

constexpr char kYaml[] = "recording.yaml";
constexpr char kCsv[] = "frames.csv";
constexpr char kFramesDir[] = "frames";
constexpr int kColumns = 20;

std::string NowIso8601() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const auto micros =
      std::chrono::duration_cast<std::chrono::microseconds>(now.time_since_epoch()).count() %
      1000000;
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[64];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%S", &utc);
  char out[96];
  std::snprintf(out, sizeof(out), "%s.%06lldZ", text, static_cast<long long>(micros));
  return out;
}

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

// Writes `data` to path + ".tmp", then renames it to `path` (atomic).
void WriteFileAtomically(const std::string& path, const void* data, size_t size) {
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    throw RecordingError("cannot create " + tmp + ": " + Errno() +
                         ". Check the disk and permissions of the recording directory.");
  }
  const bool ok = WriteAll(fd, data, size);
  const int saved = errno;
  ::close(fd);
  if (!ok) {
    errno = saved;
    throw RecordingError("cannot write " + tmp + ": " + Errno() + ". Is the disk full?");
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    throw RecordingError("cannot rename " + tmp + " to " + path + ": " + Errno() + ".");
  }
}

std::string FormatRow(const FrameRecord& r) {
  std::ostringstream out;
  out << r.index << ',' << r.file << ',' << r.bracket_id << ',' << r.frame_in_bracket << ','
      << r.bracket_size << ',' << FrameRoleName(r.role) << ','
      << FormatDouble(r.requested_exposure_us) << ',' << FormatDouble(r.actual_exposure_us) << ','
      << (r.exposure_from_chunk ? "chunk" : "readback") << ',' << FormatDouble(r.bias_ma_set)
      << ',' << FormatDouble(r.bias_ma_measured) << ',' << FormatDouble(r.slide_mm) << ','
      << FormatDouble(r.pan_deg) << ',' << FormatDouble(r.tilt_deg) << ','
      << FormatDouble(r.theta_deg) << ',' << r.repeat << ',' << r.camera_frame_id << ','
      << r.camera_timestamp_ns << ',' << r.host_time_ns << ',' << r.status << '\n';
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
  if (in.fail() || !in.eof()) return false;
  *value = v;
  return true;
}

// Parses one frames.csv data line; on failure says which column is wrong.
bool ParseRow(const std::string& line, FrameRecord* r, std::string* why) {
  const std::vector<std::string> f = Split(line);
  if (static_cast<int>(f.size()) != kColumns) {
    *why = "expected " + std::to_string(kColumns) + " columns, found " + std::to_string(f.size());
    return false;
  }
  auto bad = [&](const char* column, const std::string& text) {
    *why = std::string("bad ") + column + " '" + text + "'";
    return false;
  };
  std::int64_t v = 0;
  if (!ParseInt(f[0], &r->index) || r->index < 0) return bad("index", f[0]);
  r->file = f[1];
  if (r->file.rfind("frames/", 0) != 0) return bad("file", f[1]);
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
  if (!ParseDouble(f[9], &r->bias_ma_set, true)) return bad("bias_ma_set", f[9]);
  if (!ParseDouble(f[10], &r->bias_ma_measured, true)) return bad("bias_ma_measured", f[10]);
  if (!ParseDouble(f[11], &r->slide_mm, true)) return bad("slide_mm", f[11]);
  if (!ParseDouble(f[12], &r->pan_deg, true)) return bad("pan_deg", f[12]);
  if (!ParseDouble(f[13], &r->tilt_deg, true)) return bad("tilt_deg", f[13]);
  if (!ParseDouble(f[14], &r->theta_deg, true)) return bad("theta_deg", f[14]);
  if (!ParseInt(f[15], &v) || v < 0) return bad("repeat", f[15]);
  r->repeat = static_cast<int>(v);
  if (!ParseUint(f[16], &r->camera_frame_id)) return bad("camera_frame_id", f[16]);
  if (!ParseUint(f[17], &r->camera_timestamp_ns)) return bad("camera_timestamp_ns", f[17]);
  if (!ParseInt(f[18], &r->host_time_ns)) return bad("host_time_ns", f[18]);
  r->status = f[19];
  if (r->status != "ok" && r->status != "retried") return bad("status", f[19]);
  return true;
}

// frames.csv split into lines; `partial` is set when the last line lacks its '\n'.
struct CsvText {
  std::vector<std::string> lines;  // lines[0] is line 1
  bool partial_last = false;
  std::uint64_t complete_bytes = 0;  // bytes up to and including the last '\n'
};

CsvText ReadCsv(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw RecordingError("cannot open " + path +
                         ": not a recording directory (frames.csv missing). Give the directory "
                         "that holds recording.yaml and frames.csv.");
  }
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  CsvText csv;
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

Completion ParseCompletion(const std::string& text, const std::string& path) {
  if (text == "running") return Completion::kRunning;
  if (text == "complete") return Completion::kComplete;
  if (text == "cut") return Completion::kCut;
  throw RecordingError(path + ": completion '" + text +
                       "' is not running, complete or cut; fix the key by hand.");
}

RecordingHeader ReadHeader(const std::string& dir) {
  const std::string path = (fs::path(dir) / kYaml).string();
  RecordingHeader h;
  try {
    const YAML::Node root = YAML::LoadFile(path);
    if (root["format"].as<std::string>("") != "irdist-recording") {
      throw RecordingError(path + ": 'format' is not irdist-recording; this is not an irdist "
                           "recording header.");
    }
    h.format_version = root["format_version"].as<int>(0);
    if (h.format_version != kRecordingFormatVersion) {
      throw RecordingError(path + ": format_version " + std::to_string(h.format_version) +
                           " is not supported (this irdist reads version " +
                           std::to_string(kRecordingFormatVersion) + "); use a matching irdist.");
    }
    h.completion = ParseCompletion(root["completion"].as<std::string>(""), path);
    h.software_version = root["software_version"].as<std::string>("");
    h.start_time = root["start_time"].as<std::string>("");
    h.end_time = root["end_time"].as<std::string>("");
    h.frame_count = root["frame_count"].as<std::int64_t>(-1);
    if (root["resumed"] && root["resumed"].IsSequence()) {
      for (const auto& item : root["resumed"]) h.resumed.push_back(item.as<std::string>());
    }
    const YAML::Node image = root["image"];
    h.bit_depth = image["bit_depth"].as<int>(16);
    h.pixel_format = image["pixel_format"].as<std::string>("");
    const YAML::Node camera = root["camera"];
    h.camera.vendor = camera["vendor"].as<std::string>("");
    h.camera.model = camera["model"].as<std::string>("");
    h.camera.serial = camera["serial"].as<std::string>("");
    h.camera.firmware = camera["firmware"].as<std::string>("");
    h.camera.address = camera["address"].as<std::string>("");
    if (camera["features"] && camera["features"].IsMap()) {
      for (const auto& item : camera["features"]) {
        h.camera_features[item.first.as<std::string>()] = item.second.as<std::string>("");
      }
    }
    h.station_identity = root["station"]["identity"].as<std::string>("");
    h.recipe_path = root["recipe"]["path"].as<std::string>("");
    h.recipe_text = root["recipe"]["text"].as<std::string>("");
    h.rig_path = root["rig"]["path"].as<std::string>("");
    h.rig_text = root["rig"]["text"].as<std::string>("");
  } catch (const YAML::BadFile&) {
    throw RecordingError("cannot open " + path + ": not a recording directory (recording.yaml "
                         "missing). Give the directory that holds recording.yaml and frames.csv.");
  } catch (const YAML::Exception& error) {
    throw RecordingError(path + ":" + std::to_string(error.mark.line + 1) +
                         ": unreadable YAML (" + error.msg +
                         "); restore the file from frames.csv's run or fix it by hand.");
  }
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
  for (const auto& [key, path, text] :
       {std::tuple<const char*, const std::string&, const std::string&>{"recipe", h.recipe_path,
                                                                         h.recipe_text},
        std::tuple<const char*, const std::string&, const std::string&>{"rig", h.rig_path,
                                                                         h.rig_text}}) {
    out << YAML::Key << key << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "path" << YAML::Value << path;
    out << YAML::Key << "text" << YAML::Value << YAML::Literal << text;
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
      "theta_deg,repeat,camera_frame_id,camera_timestamp_ns,host_time_ns,status";
  return header;
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

// --- RecordingWriter --------------------------------------------------------------------------

RecordingWriter::RecordingWriter(std::string dir, RecordingHeader header, std::int64_t next_index)
    : dir_(std::move(dir)), header_(std::move(header)), next_index_(next_index) {}

RecordingWriter::~RecordingWriter() {
  if (csv_fd_ >= 0) ::close(csv_fd_);
}

void RecordingWriter::WriteHeader() {
  const std::string text = HeaderYaml(header_);
  WriteFileAtomically((fs::path(dir_) / kYaml).string(), text.data(), text.size());
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
  if (header.start_time.empty()) header.start_time = NowIso8601();
  header.completion = Completion::kRunning;
  header.end_time.clear();
  header.frame_count = -1;
  header.format_version = kRecordingFormatVersion;
  std::unique_ptr<RecordingWriter> writer(new RecordingWriter(dir, std::move(header), 0));
  const std::string csv_path = (fs::path(dir) / kCsv).string();
  const std::string line = FramesCsvHeader() + "\n";
  const int fd = ::open(csv_path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) throw RecordingError("cannot create " + csv_path + ": " + Errno() + ".");
  const bool ok = WriteAll(fd, line.data(), line.size());
  ::close(fd);
  if (!ok) throw RecordingError("cannot write " + csv_path + ": " + Errno() + ".");
  writer->WriteHeader();
  writer->csv_fd_ = OpenCsvForAppend(csv_path);
  return writer;
}

// The complete rows of frames.csv (a partial last line, the frame in flight of a killed writer,
// is left out), each with its line number. Throws RecordingError naming file:line.
static std::vector<FrameRecord> ParseCompleteRows(const CsvText& csv, const std::string& csv_path) {
  if (csv.lines.empty() || csv.lines[0] != FramesCsvHeader()) {
    throw RecordingError(csv_path + ":1: header line is not the irdist frames.csv header (format " +
                         std::to_string(kRecordingFormatVersion) + "); run `irdist check`.");
  }
  std::vector<FrameRecord> rows;
  const size_t complete_lines = csv.lines.size() - (csv.partial_last ? 1 : 0);
  for (size_t i = 1; i < complete_lines; ++i) {
    FrameRecord row;
    std::string why;
    if (!ParseRow(csv.lines[i], &row, &why)) {
      throw RecordingError(csv_path + ":" + std::to_string(i + 1) + ": " + why +
                           "; run `irdist check` for a full report and repair or delete the row.");
    }
    row.line = static_cast<int>(i + 1);
    rows.push_back(std::move(row));
  }
  return rows;
}

std::unique_ptr<RecordingWriter> RecordingWriter::Resume(const std::string& dir) {
  RecordingHeader header = ReadHeader(dir);
  const std::string yaml_path = (fs::path(dir) / kYaml).string();
  if (header.completion == Completion::kComplete) {
    throw RecordingError(yaml_path + ": the recording is complete; there is nothing to resume. "
                         "Start a new recording instead.");
  }
  const std::string csv_path = (fs::path(dir) / kCsv).string();
  const CsvText csv = ReadCsv(csv_path);
  std::int64_t next_index = 0;
  for (const FrameRecord& row : ParseCompleteRows(csv, csv_path)) {
    next_index = std::max(next_index, row.index + 1);
  }
  // Drop the partial last line and the leftovers of the frame in flight.
  if (csv.partial_last && ::truncate(csv_path.c_str(), static_cast<off_t>(csv.complete_bytes)) != 0) {
    throw RecordingError("cannot truncate the partial last line of " + csv_path + ": " + Errno());
  }
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(fs::path(dir) / kFramesDir, ec)) {
    const std::string name = entry.path().filename().string();
    std::int64_t index = -1;
    const bool tmp = name.size() > 4 && name.substr(name.size() - 4) == ".tmp";
    const bool png = name.size() > 4 && name.substr(name.size() - 4) == ".png" &&
                     ParseInt(name.substr(0, name.size() - 4), &index);
    if (tmp || (png && index >= next_index)) fs::remove(entry.path(), ec);
  }
  header.completion = Completion::kRunning;
  header.end_time.clear();
  header.frame_count = -1;
  header.resumed.push_back(NowIso8601());
  std::unique_ptr<RecordingWriter> writer(new RecordingWriter(dir, std::move(header), next_index));
  writer->WriteHeader();
  writer->csv_fd_ = OpenCsvForAppend(csv_path);
  return writer;
}

FrameRecord RecordingWriter::Append(const cv::Mat& image, FrameRecord record) {
  IRDIST_CHECK(!closed_, "Append() after Close()");
  IRDIST_CHECK(!image.empty() && image.channels() == 1 &&
                   (image.depth() == CV_16U || image.depth() == CV_8U),
               "Append() needs a single-channel 8- or 16-bit image");
  cv::Mat image16;
  if (image.depth() == CV_16U) {
    image16 = image;
  } else {
    image.convertTo(image16, CV_16U);  // values unchanged
  }
  record.index = next_index_;
  record.file = FrameFileName(record.index);
  const std::string row = FormatRow(record);
  {
    // The writer holds its rows to the reader's rules: a row the reader would refuse is a bug of
    // the caller, refused before anything reaches the disk.
    FrameRecord parsed;
    std::string why;
    std::string line = row;
    while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
    IRDIST_CHECK(ParseRow(line, &parsed, &why), "frame ", record.index,
                 " would be unreadable in frames.csv: ", why);
  }
  std::vector<uchar> png;
  if (!cv::imencode(".png", image16, png, {cv::IMWRITE_PNG_COMPRESSION, 1})) {
    throw RecordingError("cannot encode frame " + std::to_string(record.index) + " as PNG.");
  }
  const std::string path = (fs::path(dir_) / record.file).string();
  WriteFileAtomically(path, png.data(), png.size());
  if (!WriteAll(csv_fd_, row.data(), row.size())) {
    throw RecordingError("cannot append to " + (fs::path(dir_) / kCsv).string() + ": " + Errno() +
                         ". Is the disk full?");
  }
  ++next_index_;
  return record;
}

void RecordingWriter::Close(Completion completion) {
  IRDIST_CHECK(completion != Completion::kRunning, "Close() needs complete or cut");
  if (closed_) return;
  if (csv_fd_ >= 0) {
    ::fsync(csv_fd_);
    ::close(csv_fd_);
    csv_fd_ = -1;
  }
  header_.completion = completion;
  header_.end_time = NowIso8601();
  header_.frame_count = next_index_;
  WriteHeader();
  closed_ = true;
}

// --- RecordingReader --------------------------------------------------------------------------

RecordingReader::RecordingReader(const std::string& dir)
    : dir_(dir), header_(ReadHeader(dir)) {
  const std::string csv_path = (fs::path(dir) / kCsv).string();
  rows_ = ParseCompleteRows(ReadCsv(csv_path), csv_path);
}

std::vector<RecordedBracket> RecordingReader::Brackets() const {
  std::vector<RecordedBracket> brackets;
  std::map<std::int64_t, size_t> where;
  // Last row of each (bracket, position) wins: a resumed run re-acquires incomplete brackets.
  std::map<std::int64_t, std::map<int, const FrameRecord*>> positions;
  for (const FrameRecord& row : rows_) {
    if (where.find(row.bracket_id) == where.end()) {
      where[row.bracket_id] = brackets.size();
      brackets.emplace_back();
      brackets.back().bracket_id = row.bracket_id;
    }
    brackets[where[row.bracket_id]].bracket_size = row.bracket_size;
    positions[row.bracket_id][row.frame_in_bracket] = &row;
  }
  for (RecordedBracket& bracket : brackets) {
    const auto& present = positions[bracket.bracket_id];
    for (const auto& [position, row] : present) {
      if (position < bracket.bracket_size) bracket.frames.push_back(*row);
    }
    bracket.complete = static_cast<int>(bracket.frames.size()) == bracket.bracket_size;
  }
  return brackets;
}

std::set<std::int64_t> RecordingReader::CompleteBracketIds() const {
  std::set<std::int64_t> ids;
  for (const auto& bracket : Brackets()) {
    if (bracket.complete) ids.insert(bracket.bracket_id);
  }
  return ids;
}

cv::Mat RecordingReader::LoadImage(const FrameRecord& row) const {
  const std::string path = (fs::path(dir_) / row.file).string();
  cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty()) {
    throw RecordingError(path + " (frames.csv:" + std::to_string(row.line) +
                         "): missing or not a readable PNG; run `irdist check` on the recording.");
  }
  if (image.type() != CV_16UC1) {
    throw RecordingError(path + ": expected a single-channel 16-bit PNG; the file was replaced.");
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

RecordingCheck CheckRecording(const std::string& dir) {
  RecordingCheck check;
  if (!fs::exists(fs::path(dir) / kYaml) && !fs::exists(fs::path(dir) / kCsv)) {
    throw RecordingError(dir + " is not a recording (no recording.yaml, no frames.csv).");
  }
  RecordingHeader header;
  try {
    header = ReadHeader(dir);
    check.completion = header.completion;
  } catch (const RecordingError& error) {
    check.errors.push_back({kYaml, 0, error.what()});
    check.completion = Completion::kRunning;
  }
  CsvText csv;
  try {
    csv = ReadCsv((fs::path(dir) / kCsv).string());
  } catch (const RecordingError& error) {
    check.errors.push_back({kCsv, 0, error.what()});
    return check;
  }
  if (csv.lines.empty() || csv.lines[0] != FramesCsvHeader()) {
    check.errors.push_back({kCsv, 1, "header line is not the frames.csv header of format 1"});
    return check;
  }
  const size_t complete_lines = csv.lines.size() - (csv.partial_last ? 1 : 0);
  if (csv.partial_last) {
    check.warnings.push_back({kCsv, static_cast<int>(csv.lines.size()),
                              "last line has no end of line (cut mid-write); ignored"});
  }
  std::vector<FrameRecord> rows;
  std::map<std::int64_t, int> index_line;
  std::map<std::string, int> file_line;
  std::map<std::pair<std::int64_t, int>, int> position_line;
  std::int64_t expected = 0;
  cv::Size size;
  for (size_t i = 1; i < complete_lines; ++i) {
    const int line = static_cast<int>(i + 1);
    FrameRecord row;
    std::string why;
    if (!ParseRow(csv.lines[i], &row, &why)) {
      check.errors.push_back({kCsv, line, "bad row: " + why});
      continue;
    }
    row.line = line;
    if (index_line.count(row.index) != 0) {
      check.errors.push_back({kCsv, line, "duplicate index " + std::to_string(row.index) +
                                              " (first at line " +
                                              std::to_string(index_line[row.index]) + ")"});
    } else if (row.index > expected) {
      check.errors.push_back({kCsv, line, "gap: indices " + std::to_string(expected) + ".." +
                                              std::to_string(row.index - 1) + " are missing"});
    } else if (row.index < expected) {
      check.errors.push_back({kCsv, line, "index " + std::to_string(row.index) +
                                              " out of order (expected " +
                                              std::to_string(expected) + ")"});
    }
    index_line.emplace(row.index, line);
    expected = std::max(expected, row.index + 1);
    if (file_line.count(row.file) != 0) {
      check.errors.push_back({kCsv, line, "duplicate file " + row.file + " (first at line " +
                                              std::to_string(file_line[row.file]) + ")"});
    }
    file_line.emplace(row.file, line);
    const auto position = std::make_pair(row.bracket_id, row.frame_in_bracket);
    if (position_line.count(position) != 0) {
      check.warnings.push_back(
          {kCsv, line, "bracket " + std::to_string(row.bracket_id) + " frame " +
                           std::to_string(row.frame_in_bracket) + " supersedes line " +
                           std::to_string(position_line[position]) + " (re-acquired)"});
    }
    position_line[position] = line;
    const cv::Mat image = cv::imread((fs::path(dir) / row.file).string(), cv::IMREAD_UNCHANGED);
    if (image.empty()) {
      check.errors.push_back({row.file, 0, "missing or unreadable PNG (row at frames.csv:" +
                                               std::to_string(line) + ")"});
    } else if (image.type() != CV_16UC1) {
      check.errors.push_back({row.file, 0, "not a single-channel 16-bit PNG (frames.csv:" +
                                               std::to_string(line) + ")"});
    } else if (size.area() == 0) {
      size = image.size();
    } else if (image.size() != size) {
      check.errors.push_back({row.file, 0, "size differs from the first frame (frames.csv:" +
                                               std::to_string(line) + ")"});
    }
    rows.push_back(std::move(row));
  }
  check.rows = static_cast<std::int64_t>(rows.size());

  // Files in frames/ without a row.
  std::error_code ec;
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(fs::path(dir) / kFramesDir, ec)) {
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  for (const std::string& name : names) {
    const std::string relative = std::string(kFramesDir) + "/" + name;
    if (name.size() > 4 && name.substr(name.size() - 4) == ".tmp") {
      check.warnings.push_back({relative, 0, "leftover temporary file of a frame in flight"});
    } else if (file_line.count(relative) == 0) {
      check.warnings.push_back({relative, 0, "orphan file: no row in frames.csv refers to it"});
    }
  }

  // Brackets.
  std::map<std::int64_t, std::pair<int, std::set<int>>> brackets;
  for (const FrameRecord& row : rows) {
    auto& bracket = brackets[row.bracket_id];
    bracket.first = row.bracket_size;
    bracket.second.insert(row.frame_in_bracket);
  }
  check.brackets = static_cast<std::int64_t>(brackets.size());
  for (const auto& [id, bracket] : brackets) {
    if (static_cast<int>(bracket.second.size()) == bracket.first) {
      ++check.complete_brackets;
    } else {
      check.warnings.push_back({kCsv, 0, "bracket " + std::to_string(id) + " is incomplete (" +
                                             std::to_string(bracket.second.size()) + " of " +
                                             std::to_string(bracket.first) + " frames)"});
    }
  }
  switch (check.completion) {
    case Completion::kRunning:
      check.warnings.push_back(
          {kYaml, 0, "completion is 'running': the writer died; the run is cut"});
      break;
    case Completion::kCut:
      check.warnings.push_back({kYaml, 0, "completion is 'cut': the run was stopped early"});
      break;
    case Completion::kComplete:
      if (header.frame_count != check.rows) {
        check.errors.push_back({kYaml, 0, "frame_count " + std::to_string(header.frame_count) +
                                              " but frames.csv has " +
                                              std::to_string(check.rows) + " rows"});
      }
      break;
  }
  return check;
}

}  // namespace irdist
