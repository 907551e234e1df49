#include "acquisition/recording_writer.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <tuple>
#include <utility>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "acquisition/content_hash.h"
#include "acquisition/recording_files.h"
#include "acquisition/recording_reader.h"
#include "base/regular_file.h"
#include "base/safe_file.h"
#include "base/utc_time.h"

namespace irdist {

namespace {

namespace fs = std::filesystem;

std::string Errno() { return std::strerror(errno); }

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
  std::string why;
  if (!irdist::SyncFolder(dir, &why)) throw RecordingError(why + ". Is the disk failing?");
}

// Writes `data` to `tmp`, created new (a stale file or planted link there is unlinked first,
// never followed), and syncs it; on failure removes it and throws.
void WriteSynced(const std::string& tmp, const void* data, size_t size) {
  std::string why;
  if (!WriteNewFileSynced(tmp, std::string_view(static_cast<const char*>(data), size), 0644,
                          &why)) {
    throw RecordingError(tmp + " " + why + ". Check the disk and the recording folder.");
  }
}

void RenameOrThrow(const std::string& from, const std::string& to) {
  if (::rename(from.c_str(), to.c_str()) != 0) {
    throw RecordingError("cannot rename " + from + " to " + to + ": " + Errno() + ".");
  }
}

// Writes `data` to path + ".tmp" (created new), syncs it, renames it to `path` and syncs the
// folder: after a crash `path` is either the old or the new file, complete. A `path` that is a
// symbolic link is refused.
void WriteFileAtomically(const std::string& path, const void* data, size_t size) {
  std::string why;
  if (!irdist::WriteFileAtomically(path, std::string_view(static_cast<const char*>(data), size),
                                   0644, &why)) {
    throw RecordingError(path + " " + why + ".");
  }
}

// An empty field for 0: the camera gave no timestamp, the host's monotonic time was not recorded.
template <typename Int>
std::string NonZeroOrEmpty(Int value) { return value == 0 ? "" : std::to_string(value); }

// One frames.csv row; with `hashed` (format 2) the time columns and the PNG's SHA-256 end it.
std::string FormatRow(const FrameRecord& r, bool hashed) {
  std::ostringstream out;
  out << r.index << ',' << r.file << ',' << r.bracket_id << ',' << r.frame_in_bracket << ','
      << r.bracket_size << ',' << FrameRoleName(r.role) << ','
      << FormatDouble(r.requested_exposure_us) << ',' << FormatDouble(r.actual_exposure_us) << ','
      << (r.exposure_from_chunk ? "chunk" : "readback") << ',' << FormatDouble(r.bias_ma_set)
      << ',' << FormatDouble(r.bias_ma_measured) << ',' << FormatDouble(r.slide_mm) << ','
      << FormatDouble(r.pan_deg) << ',' << FormatDouble(r.tilt_deg) << ','
      << FormatDouble(r.theta_deg) << ',' << r.repeat << ',' << r.camera_frame_id << ','
      << NonZeroOrEmpty(r.camera_timestamp_ns) << ',' << r.host_time_ns << ',' << r.status;
  if (hashed) {
    out << ',' << FormatUtcIso8601(r.host_time_ns) << ',' << NonZeroOrEmpty(r.host_monotonic_ns)
        << ',' << r.sha256;
  }
  out << '\n';
  return out.str();
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
  if (h.unverified_rows > 0) out << YAML::Key << "unverified_rows" << YAML::Value << h.unverified_rows;
  if (!h.run_command.empty()) out << YAML::Key << "command" << YAML::Value << h.run_command;
  if (h.format_version >= 2) {
    out << YAML::Key << "frames_csv_sha256" << YAML::Value << YAML::DoubleQuoted
        << h.frames_csv_sha256;
  }
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
            "recipe", h.recipe_path, kRecipeCopy, h.recipe_text},
        std::tuple<const char*, const std::string&, const char*, const std::string&>{
            "rig", h.rig_path, kRigCopy, h.rig_text}}) {
    out << YAML::Key << key << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "path" << YAML::Value << YAML::DoubleQuoted << path;
    out << YAML::Key << "file" << YAML::Value << file;
    out << YAML::Key << "crc32" << YAML::Value << YAML::DoubleQuoted << TextCrc32Hex(text);
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

int OpenCsvForAppend(const std::string& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_NOFOLLOW | O_CLOEXEC);
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
  for (const auto& entry : fs::directory_iterator(fs::path(dir) / kFramesFolder, ec)) {
    const std::string name = entry.path().filename().string();
    std::int64_t index = -1;
    const bool tmp = name.size() > 4 && name.substr(name.size() - 4) == ".tmp";
    const bool png = name.size() > 4 && name.substr(name.size() - 4) == ".png" &&
                     ParseCsvInt(name.substr(0, name.size() - 4), &index);
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
    fs::rename(fs::path(dir) / kFramesFolder / name, aside / name, ec);
    if (ec) {
      throw RecordingError("cannot move " + name + " to " + aside.string() + ": " + ec.message() +
                           "; nothing was deleted.");
    }
  }
  SyncFolder((fs::path(dir) / kFramesFolder).string());
  return aside.string();
}

// A resume hashes frames.csv again at its close: it appends only to rows it can vouch for. A
// frames.csv edited since its hash was written, or a header that claims an older format than its
// rows (the hashes dropped), is refused with the fix.
void RefuseUnverifiedResume(const std::string& dir, const RecordingHeader& header,
                            const std::string& csv_text, const FramesCsv& csv) {
  const std::string yaml = (fs::path(dir) / kRecordingYaml).string();
  if (csv.hashed && header.format_version < 2) {
    throw RecordingError(yaml + ": format_version " + std::to_string(header.format_version) +
                         " but frames.csv has format 2's sha256 column: the header was edited "
                         "(its hashes dropped). Restore recording.yaml from a copy of the "
                         "recording; it is not resumed.");
  }
  if (header.frames_csv_sha256.empty() || Sha256Hex(csv_text) == header.frames_csv_sha256) return;
  throw RecordingError((fs::path(dir) / kFramesCsv).string() + ": its SHA-256 is " +
                       Sha256Hex(csv_text) + ", recording.yaml's frames_csv_sha256 is " +
                       header.frames_csv_sha256 + ": frames.csv was edited after the recording "
                       "was closed, and a resume would hash the edit as its own. Restore it from "
                       "a copy of the recording (irdist check lists the problems).");
}

}  // namespace

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
  WriteFileAtomically((fs::path(dir_) / kRecordingYaml).string(), text.data(), text.size());
}

// recipe.yaml and rig.yaml beside recording.yaml: the texts as used, byte for byte.
static void WriteTextsBeside(const std::string& dir, const RecordingHeader& header) {
  WriteFileAtomically((fs::path(dir) / kRecipeCopy).string(), header.recipe_text.data(),
                      header.recipe_text.size());
  WriteFileAtomically((fs::path(dir) / kRigCopy).string(), header.rig_text.data(),
                      header.rig_text.size());
}

static void CreateCsv(const std::string& csv_path) {
  const std::string line = FramesCsvHeader() + "\n";
  const int fd =
      ::open(csv_path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
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
  fs::create_directories(fs::path(dir) / kFramesFolder, ec);
  if (ec) {
    throw RecordingError("cannot create " + (fs::path(dir) / kFramesFolder).string() + ": " +
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
  const std::string csv_path = (fs::path(dir) / kFramesCsv).string();
  CreateCsv(csv_path);
  WriteTextsBeside(dir, writer->header_);
  writer->WriteHeader();
  writer->csv_fd_ = OpenCsvForAppend(csv_path);
  return writer;
}

std::unique_ptr<RecordingWriter> RecordingWriter::Resume(const std::string& dir) {
  RefuseLinkedRecordingParts(dir);
  const int lock_fd = AcquireWriterLock(dir);
  std::unique_ptr<RecordingWriter> writer(new RecordingWriter(dir, RecordingHeader{}, 0));
  writer->lock_fd_ = lock_fd;  // released by the writer's destructor on every path
  RecordingHeader header = ReadRecordingHeader(dir);
  if (header.completion == Completion::kComplete) {
    throw RecordingError((fs::path(dir) / kRecordingYaml).string() +
                         ": the recording is complete; there is nothing to resume. "
                         "Start a new recording instead.");
  }
  const std::string csv_path = (fs::path(dir) / kFramesCsv).string();
  const std::string csv_text = ReadFramesCsvText(dir);
  const FramesCsv csv = ParseFramesCsv(csv_text);
  if (!csv.errors.empty()) ThrowRecordingIssue(dir, csv.errors.front());
  RefuseUnverifiedResume(dir, header, csv_text, csv);
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
  if (header.frames_csv_sha256.empty()) {  // the writer died: its rows stay marked unverified
    header.unverified_rows = std::max<std::int64_t>(header.unverified_rows, csv.rows.size());
  }
  writer->header_ = std::move(header);
  writer->header_.frames_csv_sha256.clear();  // frames.csv grows again: hashed at Close()
  writer->hashed_ = csv.hashed;
  writer->next_index_ = next_index;
  writer->WriteHeader();
  writer->csv_fd_ = OpenCsvForAppend(csv_path);
  return writer;
}

// Checks the row against the reader's rules: a row the reader would refuse is a bug of the
// caller, refused before anything reaches the disk.
static void CheckRowReadable(const std::string& row, std::int64_t index, bool hashed) {
  FrameRecord parsed;
  std::string why;
  std::string line = row;
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
  IRDIST_CHECK(ParseFramesCsvRow(line, &parsed, &why, hashed), "frame ", index,
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
  staged_sha256_.push_back(
      Sha256Hex(std::string_view(reinterpret_cast<const char*>(png.data()), png.size())));
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
    record.sha256 = hashed_ ? staged_sha256_[i] : "";
    rows.push_back(FormatRow(record, hashed_));
    CheckRowReadable(rows.back(), record.index, hashed_);
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
    if (!staged_.empty()) SyncFolder((fs::path(dir_) / kFramesFolder).string());
    // The rows only after their files are durable: a row never names a missing frame.
    if (!WriteAll(csv_fd_, rows.data(), rows.size()) || ::fsync(csv_fd_) != 0) {
      throw RecordingError("cannot append to " + (fs::path(dir_) / kFramesCsv).string() + ": " +
                           Errno() + ". Is the disk full?");
    }
  } catch (const RecordingError& error) {
    first_error_ = error.what();
    throw;
  }
  next_index_ += static_cast<std::int64_t>(staged_.size());
  staged_.clear();
  staged_sha256_.clear();
  return records;
}

void RecordingWriter::DropStaged() {
  for (const std::string& tmp : staged_) ::unlink(tmp.c_str());  // never visible; best effort
  staged_.clear();
  staged_sha256_.clear();
}

FrameRecord RecordingWriter::Append(const cv::Mat& image, FrameRecord record) {
  IRDIST_CHECK(staged_.empty(), "Append() with staged frames: commit or drop them first");
  record.index = next_index_;
  record.file = FrameFileName(record.index);
  FrameRecord probe = record;  // its hash is known once encoded: any well-formed one here
  probe.sha256 = std::string(64, '0');
  CheckRowReadable(FormatRow(probe, hashed_), record.index, hashed_);  // before the disk
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
  header_.frames_csv_sha256.clear();
  std::string csv_text, why;
  if (header_.format_version >= 2 && ReadRegularFile((fs::path(dir_) / kFramesCsv).string(),
                                                     kMaxRecordingTextBytes, &csv_text, &why)) {
    header_.frames_csv_sha256 = Sha256Hex(csv_text);  // frames.csv as closed (check verifies it)
  }
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

std::string LiveWriterOf(const std::string& dir) {
  const std::string path = (fs::path(dir) / "writer.lock").string();
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return "";
  std::string holder;
  if (::flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK) {
    char pid[32] = {0};
    const ssize_t n = ::pread(fd, pid, sizeof(pid) - 1, 0);
    holder = n > 0 ? std::string(pid, static_cast<size_t>(n)) : "?";
    while (!holder.empty() && (holder.back() == '\n' || holder.back() == ' ')) holder.pop_back();
    if (holder.empty()) holder = "?";
  }
  ::close(fd);  // releases a shared lock taken here
  return holder;
}

}  // namespace irdist
