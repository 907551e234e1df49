#include "sim/rig_physics.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <functional>
#include <map>
#include <sstream>

namespace irdist::sim {
namespace {

bool Fail(std::string* why, const std::string& message) {
  if (why != nullptr) *why = message;
  return false;
}

bool Positive(double value) { return std::isfinite(value) && value > 0.0; }
bool Fraction(double value) { return std::isfinite(value) && value >= 0.0 && value <= 1.0; }

class SectionReader {
 public:
  using Setter = std::function<void(const YAML::Node&, const std::string& key)>;

  SectionReader(std::string path, std::string section) : path_(std::move(path)),
                                                         section_(std::move(section)) {}

  std::string Where(const YAML::Node& node) const {
    std::ostringstream out;
    out << path_;
    if (!node.Mark().is_null()) out << ":" << node.Mark().line + 1;
    return out.str();
  }
  [[noreturn]] void Throw(const YAML::Node& node, const std::string& message) const {
    throw RigFileError(Where(node) + ": " + section_ + ": " + message);
  }

  template <typename T>
  Setter Scalar(T* target) const {
    return [this, target](const YAML::Node& node, const std::string& key) {
      if (!node.IsScalar()) Throw(node, key + ": expected a scalar value");
      try {
        *target = node.as<T>();
      } catch (const YAML::Exception&) {
        Throw(node, key + ": cannot read '" + node.Scalar() + "' as a number or flag");
      }
    };
  }
  Setter String(std::string* target) const {
    return [this, target](const YAML::Node& node, const std::string& key) {
      if (!node.IsScalar()) Throw(node, key + ": expected a string");
      *target = node.Scalar();
    };
  }

  // Applies every key of `node` through `setters`; unknown keys are errors (except `skip`).
  void Read(const YAML::Node& node, const std::map<std::string, Setter>& setters,
            const std::string& skip = "") const {
    if (!node.IsMap()) Throw(node, "expected a map of keys");
    for (const auto& item : node) {
      const std::string key = item.first.as<std::string>();
      if (!skip.empty() && key == skip) continue;
      const auto it = setters.find(key);
      if (it == setters.end()) {
        std::string known;
        for (const auto& [name, unused] : setters) known += (known.empty() ? "" : ", ") + name;
        Throw(item.first, "unknown key '" + key + "' (known keys: " + known + ")");
      }
      try {
        it->second(item.second, key);
      } catch (const RigFileError&) {
        throw;
      } catch (const std::exception& e) {
        Throw(item.second, "bad value for '" + key + "': " + e.what());
      }
    }
  }

  SectionReader Sub(const std::string& name) const {
    return SectionReader(path_, section_ + "." + name);
  }

 private:
  std::string path_;
  std::string section_;
};

}  // namespace

const char* PixelFormatName(PixelFormat format) {
  switch (format) {
    case PixelFormat::kMono8:
      return "Mono8";
    case PixelFormat::kMono12:
      return "Mono12";
    case PixelFormat::kMono16:
      return "Mono16";
  }
  return "unknown";
}

bool EmitterOptions::IsValid(std::string* why) const {
  if (!Positive(diameter_mm)) return Fail(why, "emitter.diameter_mm must be > 0");
  if (!std::isfinite(threshold_ma) || threshold_ma < 0.0) {
    return Fail(why, "emitter.threshold_ma must be >= 0");
  }
  if (!Positive(slope_mw_sr_per_ma)) return Fail(why, "emitter.slope_mw_sr_per_ma must be > 0");
  if (!std::isfinite(sublinear_per_ma) || sublinear_per_ma < 0.0 || sublinear_per_ma > 1e-3) {
    return Fail(why, "emitter.sublinear_per_ma must lie in [0, 0.001]");
  }
  if (!Positive(pattern_sigma_deg)) return Fail(why, "emitter.pattern_sigma_deg must be > 0");
  if (!Positive(pattern_cos_power)) return Fail(why, "emitter.pattern_cos_power must be > 0");
  if (!Positive(wavelength_nm)) return Fail(why, "emitter.wavelength_nm must be > 0");
  if (!std::isfinite(temp_coeff_per_k) || std::fabs(temp_coeff_per_k) > 0.05) {
    return Fail(why, "emitter.temp_coeff_per_k must lie in [-0.05, 0.05]");
  }
  if (!std::isfinite(ambient_c)) return Fail(why, "emitter.ambient_c must be finite");
  if (!std::isfinite(forward_voltage_v) || forward_voltage_v < 0.0) {
    return Fail(why, "emitter.forward_voltage_v must be >= 0");
  }
  if (!std::isfinite(thermal_resistance_k_per_w) || thermal_resistance_k_per_w < 0.0) {
    return Fail(why, "emitter.thermal_resistance_k_per_w must be >= 0");
  }
  if (!Positive(thermal_time_constant_s)) {
    return Fail(why, "emitter.thermal_time_constant_s must be > 0");
  }
  if (!std::isfinite(offset_x_mm) || !std::isfinite(offset_y_mm)) {
    return Fail(why, "emitter.offset_x_mm/offset_y_mm must be finite");
  }
  return true;
}

bool OpticsOptions::IsValid(std::string* why) const {
  if (!Positive(focal_length_mm)) return Fail(why, "optics.focal_length_mm must be > 0");
  if (!std::isfinite(f_number) || f_number < 0.5) return Fail(why, "optics.f_number must be >= 0.5");
  if (!Positive(lens_transmission) || lens_transmission > 1.0) {
    return Fail(why, "optics.lens_transmission must lie in (0, 1]");
  }
  if (!Positive(filter_transmission) || filter_transmission > 1.0) {
    return Fail(why, "optics.filter_transmission must lie in (0, 1]");
  }
  if (!std::isfinite(psf_sigma_px) || psf_sigma_px < 0.0 || psf_sigma_px > 20.0) {
    return Fail(why, "optics.psf_sigma_px must lie in [0, 20]");
  }
  if (!std::isfinite(focus_mm) || (focus_mm != 0.0 && focus_mm <= 2.0 * focal_length_mm)) {
    return Fail(why, "optics.focus_mm must be 0 (no defocus) or beyond twice the focal length");
  }
  if (supersample < 1 || supersample > 32) return Fail(why, "optics.supersample must be 1..32");
  return true;
}

bool SensorOptions::IsValid(std::string* why) const {
  if (width_px < 16 || width_px > 8192 || height_px < 16 || height_px > 8192) {
    return Fail(why, "sensor.width_px/height_px must be 16..8192");
  }
  if (!Positive(pixel_pitch_um)) return Fail(why, "sensor.pixel_pitch_um must be > 0");
  if (!Positive(quantum_efficiency) || quantum_efficiency > 1.0) {
    return Fail(why, "sensor.quantum_efficiency must lie in (0, 1]");
  }
  if (!Positive(full_well_e)) return Fail(why, "sensor.full_well_e must be > 0");
  if (!Positive(system_gain_dn_per_e)) return Fail(why, "sensor.system_gain_dn_per_e must be > 0");
  if (!std::isfinite(read_noise_e) || read_noise_e < 0.0) {
    return Fail(why, "sensor.read_noise_e must be >= 0");
  }
  if (!std::isfinite(dark_current_e_per_s) || dark_current_e_per_s < 0.0) {
    return Fail(why, "sensor.dark_current_e_per_s must be >= 0");
  }
  if (adc_bits < 8 || adc_bits > 16) return Fail(why, "sensor.adc_bits must be 8..16");
  if (!std::isfinite(black_level_dn) || black_level_dn < 0.0 || black_level_dn > AdcMax()) {
    return Fail(why, "sensor.black_level_dn must lie in [0, 2^adc_bits - 1]");
  }
  if (!std::isfinite(nonlinearity) || nonlinearity < 0.0 || nonlinearity > 0.5) {
    return Fail(why, "sensor.nonlinearity must lie in [0, 0.5]");
  }
  if (!std::isfinite(background_e_per_s) || background_e_per_s < 0.0) {
    return Fail(why, "sensor.background_e_per_s must be >= 0");
  }
  if (!std::isfinite(temperature_c)) return Fail(why, "sensor.temperature_c must be finite");
  if (!std::isfinite(prnu_percent) || prnu_percent < 0.0 || prnu_percent > 10.0) {
    return Fail(why, "sensor.prnu_percent must lie in [0, 10]");
  }
  if (!std::isfinite(dsnu_e) || dsnu_e < 0.0) return Fail(why, "sensor.dsnu_e must be >= 0");
  return true;
}

bool CameraOptions::IsValid(std::string* why) const {
  if (serial.empty() || serial.size() >= 16) {
    return Fail(why, "camera serial must have 1..15 characters");
  }
  if (!std::isfinite(readout_ms) || readout_ms < 0.0) {
    return Fail(why, "camera.readout_ms must be >= 0");
  }
  if (!std::isfinite(trigger_frequency_hz) || trigger_frequency_hz < 25.0 ||
      trigger_frequency_hz > 20000.0) {
    return Fail(why, "camera.trigger_frequency_hz must lie in [25, 20000]");
  }
  if (!Fraction(drop_frame_rate)) return Fail(why, "camera.drop_frame_rate must lie in [0, 1]");
  if (!Fraction(lost_packet_ratio)) {
    return Fail(why, "camera.lost_packet_ratio must lie in [0, 1]");
  }
  if (!std::isfinite(exposure_write_delay_ms) || exposure_write_delay_ms < 0.0) {
    return Fail(why, "camera.exposure_write_delay_ms must be >= 0");
  }
  return true;
}

bool RigPhysics::IsValid(std::string* why) const {
  if (!std::isfinite(time_scale) || time_scale < 0.01 || time_scale > 1000.0) {
    return Fail(why, "time_scale must lie in [0.01, 1000]");
  }
  return emitter.IsValid(why) && optics.IsValid(why) && sensor.IsValid(why) &&
         camera.IsValid(why);
}

RigPhysics LoadRigPhysics(const std::string& rig_path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(rig_path);
  } catch (const YAML::BadFile&) {
    throw RigFileError(rig_path + ": cannot open the rig file; check the path (e.g. "
                       "recipes/rigs/virtual.yaml)");
  } catch (const YAML::Exception& e) {
    throw RigFileError(rig_path + ":" + std::to_string(e.mark.line + 1) +
                       ": not valid YAML: " + e.msg);
  }
  RigPhysics physics;
  const YAML::Node section = root.IsMap() ? root["virtual"] : YAML::Node();
  if (!section || section.IsNull()) return physics;

  SectionReader top(rig_path, "virtual");
  SectionReader em = top.Sub("emitter");
  SectionReader op = top.Sub("optics");
  SectionReader se = top.Sub("sensor");
  SectionReader ca = top.Sub("camera");
  EmitterOptions& e = physics.emitter;
  OpticsOptions& o = physics.optics;
  SensorOptions& s = physics.sensor;
  CameraOptions& c = physics.camera;

  const std::map<std::string, SectionReader::Setter> emitter_keys = {
      {"diameter_mm", em.Scalar(&e.diameter_mm)},
      {"threshold_ma", em.Scalar(&e.threshold_ma)},
      {"slope_mw_sr_per_ma", em.Scalar(&e.slope_mw_sr_per_ma)},
      {"sublinear_per_ma", em.Scalar(&e.sublinear_per_ma)},
      {"pattern",
       [&em, &e](const YAML::Node& node, const std::string&) {
         const std::string name = node.IsScalar() ? node.Scalar() : "";
         if (name == "gaussian") {
           e.pattern = EmissionPattern::kGaussian;
         } else if (name == "cos_power") {
           e.pattern = EmissionPattern::kCosPower;
         } else {
           em.Throw(node, "pattern must be 'gaussian' or 'cos_power', not '" + name + "'");
         }
       }},
      {"pattern_sigma_deg", em.Scalar(&e.pattern_sigma_deg)},
      {"pattern_cos_power", em.Scalar(&e.pattern_cos_power)},
      {"wavelength_nm", em.Scalar(&e.wavelength_nm)},
      {"temp_coeff_per_k", em.Scalar(&e.temp_coeff_per_k)},
      {"ambient_c", em.Scalar(&e.ambient_c)},
      {"forward_voltage_v", em.Scalar(&e.forward_voltage_v)},
      {"thermal_resistance_k_per_w", em.Scalar(&e.thermal_resistance_k_per_w)},
      {"thermal_time_constant_s", em.Scalar(&e.thermal_time_constant_s)},
      {"offset_x_mm", em.Scalar(&e.offset_x_mm)},
      {"offset_y_mm", em.Scalar(&e.offset_y_mm)},
  };
  const std::map<std::string, SectionReader::Setter> optics_keys = {
      {"focal_length_mm", op.Scalar(&o.focal_length_mm)},
      {"f_number", op.Scalar(&o.f_number)},
      {"lens_transmission", op.Scalar(&o.lens_transmission)},
      {"filter_transmission", op.Scalar(&o.filter_transmission)},
      {"psf_sigma_px", op.Scalar(&o.psf_sigma_px)},
      {"focus_mm", op.Scalar(&o.focus_mm)},
      {"vignetting", op.Scalar(&o.vignetting)},
      {"supersample", op.Scalar(&o.supersample)},
  };
  const std::map<std::string, SectionReader::Setter> sensor_keys = {
      {"width_px", se.Scalar(&s.width_px)},
      {"height_px", se.Scalar(&s.height_px)},
      {"pixel_pitch_um", se.Scalar(&s.pixel_pitch_um)},
      {"quantum_efficiency", se.Scalar(&s.quantum_efficiency)},
      {"full_well_e", se.Scalar(&s.full_well_e)},
      {"system_gain_dn_per_e", se.Scalar(&s.system_gain_dn_per_e)},
      {"read_noise_e", se.Scalar(&s.read_noise_e)},
      {"dark_current_e_per_s", se.Scalar(&s.dark_current_e_per_s)},
      {"black_level_dn", se.Scalar(&s.black_level_dn)},
      {"adc_bits", se.Scalar(&s.adc_bits)},
      {"nonlinearity", se.Scalar(&s.nonlinearity)},
      {"background_e_per_s", se.Scalar(&s.background_e_per_s)},
      {"temperature_c", se.Scalar(&s.temperature_c)},
      {"prnu_percent", se.Scalar(&s.prnu_percent)},
      {"dsnu_e", se.Scalar(&s.dsnu_e)},
  };
  const std::map<std::string, SectionReader::Setter> camera_keys = {
      {"readout_ms", ca.Scalar(&c.readout_ms)},
      {"trigger_frequency_hz", ca.Scalar(&c.trigger_frequency_hz)},
      {"drop_frame_rate", ca.Scalar(&c.drop_frame_rate)},
      {"lost_packet_ratio", ca.Scalar(&c.lost_packet_ratio)},
      {"exposure_write_delay_ms", ca.Scalar(&c.exposure_write_delay_ms)},
  };
  const std::map<std::string, SectionReader::Setter> top_keys = {
      {"time_scale", top.Scalar(&physics.time_scale)},
      {"seed", top.Scalar(&s.seed)},
      {"serial", top.String(&c.serial)},
      {"emitter", [&](const YAML::Node& node, const std::string&) { em.Read(node, emitter_keys); }},
      {"optics", [&](const YAML::Node& node, const std::string&) { op.Read(node, optics_keys); }},
      {"sensor", [&](const YAML::Node& node, const std::string&) { se.Read(node, sensor_keys); }},
      {"camera", [&](const YAML::Node& node, const std::string&) { ca.Read(node, camera_keys); }},
      // The device emulators' own entries, read strictly by each emulator (sim/line_device.cc).
      {"devices", [](const YAML::Node&, const std::string&) {}},
  };
  top.Read(section, top_keys, "station");

  std::string why;
  if (!physics.IsValid(&why)) {
    throw RigFileError(top.Where(section) + ": virtual: " + why +
                       "; fix the value in the rig file (docs/virtual-rig.md lists the ranges)");
  }
  return physics;
}

}  // namespace irdist::sim
