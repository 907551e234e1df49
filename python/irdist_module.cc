// The compiled part of the Python module irdist (docs/python.md): a recording read with the
// project's own reader and checks (acquisition/recording_reader.h, recording_check.h), and a
// calibration model that gives a frame's features and a bracket's estimate through the same
// functions as measure and playback (FrameFeatures, EstimateRecordedBracket, MeasureSampleOf,
// MeasureJson). Images cross as numpy uint16 arrays: a recorded frame's pixels are handed over
// without a copy.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "acquisition/recording_check.h"
#include "acquisition/recording_reader.h"
#include "acquisition/recording_writer.h"
#include "app/inputs/errors.h"
#include "app/inputs/recipe.h"
#include "app/live/measure.h"
#include "app/processing/bracket_estimates.h"
#include "app/processing/frame_features.h"
#include "app/processing/position.h"
#include "base/bounds.h"
#include "base/utc_time.h"
#include "estimator/model_file.h"

namespace py = pybind11;

namespace irdist {
namespace {

// A CV_16UC1 frame as a numpy uint16 array sharing its pixels: the capsule holds a reference to
// the Mat's buffer for as long as the array lives.
py::array_t<std::uint16_t> ArrayOf(const cv::Mat& image) {
  auto* owner = new cv::Mat(image);
  const py::capsule release(owner, [](void* mat) { delete static_cast<cv::Mat*>(mat); });
  return py::array_t<std::uint16_t>(
      {static_cast<py::ssize_t>(image.rows), static_cast<py::ssize_t>(image.cols)},
      {static_cast<py::ssize_t>(image.step[0]), static_cast<py::ssize_t>(image.step[1])},
      owner->ptr<std::uint16_t>(), release);
}

// A gray image as numpy gives it to the estimator: C-contiguous uint16 (numpy's cast otherwise).
using Gray16 = py::array_t<std::uint16_t, py::array::c_style | py::array::forcecast>;

// A 2-D array as the CV_16UC1 image the estimator takes: a C-contiguous uint16 array is used in
// place, any other is converted (numpy's cast) into `*keep`, which must outlive the Mat.
cv::Mat MatOf(const py::handle& image, Gray16* keep) {
  *keep = Gray16::ensure(image);
  if (!*keep || keep->ndim() != 2) {
    throw py::value_error("an image must be a 2-D array of gray levels (numpy uint16, rows x "
                          "columns), as Recording gives them");
  }
  return cv::Mat(static_cast<int>(keep->shape(0)), static_cast<int>(keep->shape(1)), CV_16UC1,
                 const_cast<std::uint16_t*>(keep->data()));  // read only by the estimator
}

py::object NoneIfZero(std::int64_t value) {
  return value == 0 ? py::object(py::none()) : py::object(py::int_(value));
}

// One frames.csv row with its columns' types (docs/recording-format.md); NaN for an empty float,
// None for an absent timestamp.
py::dict RowDict(const FrameRecord& r) {
  py::dict d;
  d["index"] = r.index;
  d["file"] = r.file;
  d["bracket_id"] = r.bracket_id;
  d["frame_in_bracket"] = r.frame_in_bracket;
  d["bracket_size"] = r.bracket_size;
  d["role"] = FrameRoleName(r.role);
  d["requested_exposure_us"] = r.requested_exposure_us;
  d["actual_exposure_us"] = r.actual_exposure_us;
  d["exposure_source"] = r.exposure_from_chunk ? "chunk" : "readback";
  d["bias_ma_set"] = r.bias_ma_set;
  d["bias_ma_measured"] = r.bias_ma_measured;
  d["slide_mm"] = r.slide_mm;
  d["pan_deg"] = r.pan_deg;
  d["tilt_deg"] = r.tilt_deg;
  d["theta_deg"] = r.theta_deg;
  d["repeat"] = r.repeat;
  d["camera_frame_id"] = r.camera_frame_id;
  d["camera_timestamp_ns"] = NoneIfZero(static_cast<std::int64_t>(r.camera_timestamp_ns));
  d["host_time_ns"] = r.host_time_ns;
  d["status"] = r.status;
  d["utc_time"] = FormatUtcIso8601(r.host_time_ns);
  d["host_monotonic_ns"] = NoneIfZero(r.host_monotonic_ns);
  d["sha256"] = r.sha256.empty() ? py::object(py::none()) : py::object(py::str(r.sha256));
  return d;
}

py::dict HeaderDict(const RecordingHeader& h) {
  py::dict d;
  d["format_version"] = h.format_version;
  d["completion"] = CompletionName(h.completion);
  d["software_version"] = h.software_version;
  d["start_time"] = h.start_time;
  d["end_time"] = h.end_time;
  d["frame_count"] = h.frame_count;
  d["bit_depth"] = h.bit_depth;
  d["pixel_format"] = h.pixel_format;
  d["camera"] = py::dict(py::arg("vendor") = h.camera.vendor, py::arg("model") = h.camera.model,
                         py::arg("serial") = h.camera.serial,
                         py::arg("firmware") = h.camera.firmware);
  d["station_identity"] = h.station_identity;
  d["recipe_path"] = h.recipe_path;
  d["rig_path"] = h.rig_path;
  d["command"] = h.run_command;
  d["unverified_rows"] = h.unverified_rows;
  return d;
}

// irdist.Recording: the rows of frames.csv and their frames, checked as fit and playback check.
class PyRecording {
 public:
  PyRecording(const std::string& path, bool check) : reader_(Checked(path, check)) {
    for (std::size_t i = 0; i < reader_.rows().size(); ++i) position_[reader_.rows()[i].index] = i;
  }

  std::size_t size() const { return reader_.rows().size(); }

  // rec[i]: the i-th row (negative from the end) and its frame; any int, IndexError out of range.
  py::tuple At(const py::object& i) const {
    const auto n = static_cast<long long>(size());
    long long k = IndexOf(i, "recording index");
    if (k < 0) k += n;
    if (k < 0 || k >= n) {
      throw py::index_error("recording index " + py::str(i).cast<std::string>() +
                            " out of range: the recording has " + std::to_string(n) +
                            " rows (0.." + std::to_string(n - 1) + ", or -" + std::to_string(n) +
                            "..-1 from the end)");
    }
    const FrameRecord& row = reader_.rows()[static_cast<std::size_t>(k)];
    return py::make_tuple(ArrayOf(reader_.LoadImage(row)), RowDict(row));
  }

  // rec.image(frame_index): the frame of that index (frames.csv's index column); IndexError
  // when the recording has no such frame.
  py::array_t<std::uint16_t> Image(const py::object& frame_index) const {
    const auto it = position_.find(IndexOf(frame_index, "frame_index"));
    if (it == position_.end()) {
      throw py::index_error("no frame " + py::str(frame_index).cast<std::string>() + " in " +
                            reader_.dir() + ": its frames.csv has the indices " + IndexRange());
    }
    return ArrayOf(reader_.LoadImage(reader_.rows()[it->second]));
  }

  py::list Rows() const {
    py::list rows;
    for (const FrameRecord& row : reader_.rows()) rows.append(RowDict(row));
    return rows;
  }

  // The reader's brackets (a resumed run's last complete set of rows wins), as lists of rows.
  py::list BracketRows(bool complete_only) const {
    py::list brackets;
    for (const RecordedBracket& bracket : reader_.Brackets()) {
      if (complete_only && !bracket.complete) continue;
      py::list rows;
      for (const FrameRecord& row : bracket.frames) rows.append(RowDict(row));
      brackets.append(rows);
    }
    return brackets;
  }

  py::dict Header() const { return HeaderDict(reader_.header()); }
  const std::string& dir() const { return reader_.dir(); }

 private:
  // An index (a Python int, or any object with __index__ such as numpy's integers) as a C++ one;
  // out of its range, a value no index has (LLONG_MIN). TypeError for a float or a str, as
  // Python's sequences raise.
  static long long IndexOf(const py::object& i, const char* what) {
    if (!PyIndex_Check(i.ptr())) {
      throw py::type_error(std::string(what) + " must be an integer, not " +
                           py::str(py::type::of(i).attr("__name__")).cast<std::string>());
    }
    const py::object index = py::reinterpret_steal<py::object>(PyNumber_Index(i.ptr()));
    if (!index) throw py::error_already_set();
    int overflow = 0;
    const long long k = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
    if (overflow != 0) return std::numeric_limits<long long>::min();
    return k;
  }

  std::string IndexRange() const {
    if (position_.empty()) return "none (no rows)";
    return std::to_string(position_.begin()->first) + ".." +
           std::to_string(position_.rbegin()->first);
  }

  // check=False opens a recording a live run is writing, but says so (a Python warning).
  static void WarnIfLive(const std::string& path) {
    const std::string pid = LiveWriterOf(path);
    if (pid.empty()) return;
    const std::string text = path + " is being written by process " + pid +
                             " (a live run holds its writer.lock): the rows are those written so "
                             "far, and its last bracket may be incomplete";
    if (PyErr_WarnEx(PyExc_UserWarning, text.c_str(), 1) != 0) throw py::error_already_set();
  }

  static std::string Checked(const std::string& path, bool check) {
    if (path.find('\0') != std::string::npos) {
      throw py::value_error("the recording path contains a NUL character (\\0), which no file "
                            "name can hold; give the folder's path without it");
    }
    const RecordingCheck result = check ? CheckRecording(path) : RecordingCheck{};
    if (!result.live_writer.empty()) {
      throw RecordingError(path + " is being written by process " + result.live_writer +
                           " (a live run holds its writer.lock); open it once that run has "
                           "ended, or with check=False to read the rows written so far.");
    }
    if (!check) {
      WarnIfLive(path);
      return path;
    }
    if (!result.ok()) {
      throw RecordingError(path + " has errors (irdist check " + path + " lists them):\n" +
                           result.BriefReport() + "Open it with check=False to read it anyway.");
    }
    return path;
  }

  RecordingReader reader_;
  std::map<std::int64_t, std::size_t> position_;  // frame index -> position in rows()
};

py::dict EllipseDict(const EllipseFit& e) {
  return py::dict(py::arg("valid") = e.valid,
                  py::arg("center_px") = py::make_tuple(e.center_px.x, e.center_px.y),
                  py::arg("major_px") = e.major_px, py::arg("minor_px") = e.minor_px,
                  py::arg("angle_deg") = e.angle_deg, py::arg("theta0_deg") = e.theta0_deg);
}

// estimator/features.h's Features, by field name.
py::dict FeaturesDict(const Features& f) {
  py::dict d;
  d["blob_found"] = f.blob_found;
  d["usable"] = f.Usable();
  d["touches_border"] = f.touches_border;
  d["blob_clipped_by_roi"] = f.blob_clipped_by_roi;
  d["saturated_pixels"] = f.saturated_pixels;
  d["bit_depth"] = f.bit_depth;
  d["roi"] = py::make_tuple(f.roi.x, f.roi.y, f.roi.width, f.roi.height);
  d["roi_area_px"] = f.roi_area_px;
  d["background"] = f.background;
  d["peak"] = f.peak;
  d["e_rel"] = f.e_rel;
  d["f00"] = f.f00;
  d["sigma"] = f.sigma;
  d["centroid_px"] = py::make_tuple(f.centroid_px.x, f.centroid_px.y);
  d["moment_major_var_px2"] = f.moment_major_var_px2;
  d["moment_minor_var_px2"] = f.moment_minor_var_px2;
  d["blur_var_px2"] = f.blur_var_px2;
  d["size_blur_var_px2"] = f.size_blur_var_px2;  // the calibrated blur the blob fit was given
  d["own_blur_var_px2"] = f.own_blur_var_px2;    // the blob fit's own blur (estimator/refocus.h)
  d["own_blur_se_px2"] = f.own_blur_se_px2;
  d["ellipse_moments"] = EllipseDict(f.ellipse_moments);
  d["ellipse_contour"] = EllipseDict(f.ellipse_contour);
  d["ellipse_model"] = EllipseDict(f.ellipse_model);
  d["model_blur_px"] = f.model_blur_px;
  d["model_rms"] = f.model_rms;
  d["theta0_deg"] = f.theta0_deg;
  return d;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in.is_open()) throw RecipeError(path, 0, 0, "cannot read the rig file; check the path.");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// irdist.Model: a calibration (model.yaml) as measure and playback use it.
class PyModel {
 public:
  PyModel(const std::string& path, const std::optional<std::string>& rig)
      : path_(path), model_(LoadModel(path)) {
    geometry_.roi_offset_x = model_.provenance.roi_offset_x;
    geometry_.roi_offset_y = model_.provenance.roi_offset_y;
    if (rig) {
      const std::string rig_path = FindRigFile(*rig, std::filesystem::current_path().string());
      if (rig_path.empty()) {
        throw RecipeError(*rig, 0, 0, "no such rig: give a rig file or the name of one in " +
                                          ShippedRecipesDir() + "/rigs/ (e.g. virtual).");
      }
      geometry_ = GeometryOfRigText(ReadText(rig_path), rig_path);
    }
  }

  py::dict Features(const py::handle& image, int bit_depth) const {
    Gray16 keep;
    const cv::Mat mat = ImageOf(image, &keep);
    const int bits = BitDepth(bit_depth);
    irdist::Features f;
    {
      const py::gil_scoped_release unlocked;
      f = FrameFeatures(mat, bits, model_.features, BlobFitModelOf(model_));
    }
    return FeaturesDict(f);
  }

  py::object EstimateBracket(const py::sequence& images, const std::vector<double>& exposures_us,
                             int bit_depth,
                             const std::optional<std::vector<std::string>>& roles) const;
  const std::string& path() const { return path_; }

 private:
  int BitDepth(int given) const {
    if (given != 0) {
      const std::string refusal = bounds::kFrameBitDepth.Refusal("bit_depth", given);
      if (!refusal.empty()) throw py::value_error(refusal + "; give the camera's (12: Mono12)");
      return given;
    }
    if (model_.provenance.bit_depth > 0) return model_.provenance.bit_depth;
    throw py::value_error("the model " + path_ +
                          " does not record its camera's bit depth; give bit_depth= (12: Mono12)");
  }
  // An image at least as large as the features' window (a smaller one holds no blob).
  cv::Mat ImageOf(const py::handle& image, Gray16* keep) const {
    const cv::Mat mat = MatOf(image, keep);
    const int side_px = model_.features.window_side_px;
    if (mat.rows < side_px || mat.cols < side_px) {
      throw py::value_error("the image is " + std::to_string(mat.rows) + " x " +
                            std::to_string(mat.cols) + " px, smaller than the model's window (" +
                            "features.window_side_px " + std::to_string(side_px) + " x " +
                            std::to_string(side_px) + "); give whole frames of the ROI");
    }
    return mat;
  }
  // The bracket as measure records it: frame i taken at exposures_us[i]; roles "ref"/"meas"
  // (default: the first a reference, the others measurements).
  RecordedBracket BracketOf(const std::vector<double>& exposures_us,
                            const std::optional<std::vector<std::string>>& roles) const;

  std::string path_;
  CalibrationModel model_;
  CameraGeometry geometry_;
};

RecordedBracket PyModel::BracketOf(const std::vector<double>& exposures_us,
                                   const std::optional<std::vector<std::string>>& roles) const {
  const int n = static_cast<int>(exposures_us.size());
  if (roles && static_cast<int>(roles->size()) != n) {
    throw py::value_error("roles must give one role ('ref' or 'meas') per image");
  }
  RecordedBracket bracket;
  bracket.bracket_size = n;
  bracket.complete = true;
  for (int i = 0; i < n; ++i) {
    FrameRecord r;
    r.index = i;
    r.frame_in_bracket = i;
    r.bracket_size = n;
    const std::string role = roles ? (*roles)[i] : (i == 0 ? "ref" : "meas");
    if (role != "ref" && role != "meas") {
      throw py::value_error("role '" + role + "' is not 'ref' or 'meas'");
    }
    r.role = role == "ref" ? FrameRole::kReference : FrameRole::kMeasurement;
    r.requested_exposure_us = r.actual_exposure_us = exposures_us[i];
    r.bias_ma_set = r.slide_mm = r.pan_deg = r.tilt_deg = r.theta_deg = std::nan("");  // unknown
    bracket.frames.push_back(r);
  }
  return bracket;
}

py::object PyModel::EstimateBracket(const py::sequence& images,
                                    const std::vector<double>& exposures_us, int bit_depth,
                                    const std::optional<std::vector<std::string>>& roles) const {
  if (py::len(images) != exposures_us.size() || exposures_us.size() < 2) {
    throw py::value_error("estimate_bracket needs one exposure (us) per image and at least two "
                          "images (a reference and a measurement)");
  }
  const RecordedBracket bracket = BracketOf(exposures_us, roles);
  std::vector<Gray16> keep(exposures_us.size());
  std::vector<cv::Mat> mats;
  for (std::size_t i = 0; i < keep.size(); ++i) mats.push_back(ImageOf(images[i], &keep[i]));
  const int bits = BitDepth(bit_depth);
  std::string json;
  {
    const py::gil_scoped_release unlocked;
    FeatureMap features;
    for (std::size_t i = 0; i < mats.size(); ++i) {
      features[static_cast<std::int64_t>(i)] =
          FrameFeatures(mats[i], bits, model_.features, BlobFitModelOf(model_));
    }
    const BracketEstimateRows rows = EstimateRecordedBracket(bracket, features, model_, geometry_);
    MeasureSample sample = MeasureSampleOf(bracket, features, rows, model_, geometry_);
    sample.time_s = std::nan("");  // not a live bracket: no time, no latency (JSON null)
    json = MeasureJson(sample);
  }
  return py::module_::import("json").attr("loads")(json);
}

}  // namespace
}  // namespace irdist

PYBIND11_MODULE(_irdist, m) {
  using irdist::PyModel;
  using irdist::PyRecording;
  m.doc() = "irdist's recordings and calibration models (docs/python.md)";
  auto& error = py::register_exception<irdist::Error>(m, "Error", PyExc_RuntimeError);
  py::register_exception<irdist::RecordingError>(m, "RecordingError", error.ptr());
  py::register_exception<irdist::ModelFileError>(m, "ModelFileError", error.ptr());

  py::class_<PyRecording>(m, "Recording")
      .def(py::init<const std::string&, bool>(), py::arg("path"), py::arg("check") = true)
      .def("__len__", &PyRecording::size)
      .def("__getitem__", &PyRecording::At, py::arg("i"))
      .def("image", &PyRecording::Image, py::arg("frame_index"))
      .def_property_readonly("rows", &PyRecording::Rows)
      .def_property_readonly("header", &PyRecording::Header)
      .def_property_readonly("path", &PyRecording::dir)
      .def("_bracket_rows", &PyRecording::BracketRows, py::arg("complete_only") = true);

  py::class_<PyModel>(m, "Model")
      .def(py::init<const std::string&, const std::optional<std::string>&>(), py::arg("path"),
           py::arg("rig") = py::none())
      .def("features", &PyModel::Features, py::arg("image"), py::arg("bit_depth") = 0)
      .def("estimate_bracket", &PyModel::EstimateBracket, py::arg("images"),
           py::arg("exposures_us"), py::arg("bit_depth") = 0, py::arg("roles") = py::none())
      .def_property_readonly("path", &PyModel::path);

  m.def(
      "_check_argument",
      [](const std::string& name, double value) {
        const irdist::Bound& bound =
            name == "count" ? irdist::bounds::kCount : irdist::bounds::kDurationS;
        const std::string refusal = bound.Refusal(name, value);
        if (!refusal.empty()) throw py::value_error(refusal);
      },
      py::arg("name"), py::arg("value"),
      "Refuses (ValueError) a measure() argument outside its bound (base/bounds.h): count or "
      "duration_s");
  m.attr("MEASURE_JSON_SCHEMA") = "irdist.measure/" + std::to_string(irdist::kMeasureJsonVersion);
  m.def("format_utc", &irdist::FormatUtcIso8601, py::arg("unix_ns"),
        "ns since the Unix epoch as ISO 8601 UTC with microseconds (frames.csv's utc_time)");
}
