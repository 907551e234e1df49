#include "sim/rig_physics.h"

#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <string>
#include <vector>

#include "base/bounds.h"
#include "base/input_error.h"
#include "base/yaml_fields.h"

namespace irdist::sim {
namespace {

bool Fail(std::string* why, const std::string& message) {
  if (why != nullptr) *why = message;
  return false;
}

constexpr const char* kFix =
    "; fix the value in the rig file (docs/virtual-rig.md lists the ranges)";

bool Positive(double value) { return std::isfinite(value) && value > 0.0; }
bool Fraction(double value) { return std::isfinite(value) && value >= 0.0 && value <= 1.0; }

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
  if (psf_sigma_minor_px != 0.0 &&
      !(std::isfinite(psf_sigma_minor_px) && psf_sigma_minor_px >= 0.1 && psf_sigma_minor_px <= 20.0)) {
    return Fail(why, "optics.psf_sigma_minor_px must be 0 (a round PSF) or lie in [0.1, 20]");
  }
  if (psf_sigma_minor_px != 0.0 && !(psf_sigma_px >= 0.1)) {
    return Fail(why, "optics.psf_sigma_px must be >= 0.1 with psf_sigma_minor_px");
  }
  if (!std::isfinite(psf_angle_deg) || std::fabs(psf_angle_deg) > 180.0) {
    return Fail(why, "optics.psf_angle_deg must lie in [-180, 180]");
  }
  if (!std::isfinite(halo_share) || halo_share < 0.0 || halo_share > 0.5) {
    return Fail(why, "optics.halo_share must lie in [0, 0.5]");
  }
  if (!std::isfinite(halo_sigma_px) || halo_sigma_px < 0.5 || halo_sigma_px > 50.0) {
    return Fail(why, "optics.halo_sigma_px must lie in [0.5, 50]");
  }
  if (!std::isfinite(focus_mm) || (focus_mm != 0.0 && focus_mm <= 2.0 * focal_length_mm)) {
    return Fail(why, "optics.focus_mm must be 0 (no defocus) or beyond twice the focal length");
  }
  if (supersample < 1 || supersample > 32) return Fail(why, "optics.supersample must be 1..32");
  if (airy_first_zero_px != 0.0 && !(std::isfinite(airy_first_zero_px) &&
                                     airy_first_zero_px >= 0.3 && airy_first_zero_px <= 3.0)) {
    return Fail(why, "optics.airy_first_zero_px must be 0 (no Airy pattern) or lie in [0.3, 3]");
  }
  if (airy_first_zero_px != 0.0 && (defocus_disc || !(psf_sigma_px >= 0.3))) {
    return Fail(why, "optics.airy_first_zero_px needs psf_sigma_px >= 0.3 and no defocus_disc");
  }
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
  if (!std::isfinite(crosstalk_sigma_px) || crosstalk_sigma_px < 0.0 || crosstalk_sigma_px > 5.0) {
    return Fail(why, "sensor.crosstalk_sigma_px must lie in [0, 5]");
  }
  if (!std::isfinite(pixel_aperture) || pixel_aperture < 0.3 || pixel_aperture > 1.0) {
    return Fail(why, "sensor.pixel_aperture must lie in [0.3, 1] (a share of the pixel pitch)");
  }
  if (!defects.IsValid(AdcMax(), why)) return false;
  if (defects.Count() > static_cast<double>(width_px) * height_px / 4.0) {
    return Fail(why, "sensor.hot_pixels + stuck_pixels must be at most a quarter of the pixels");
  }
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
  if (!(lut_gamma >= 0.1 && lut_gamma <= 10.0) || !(fixed_gamma >= 0.1 && fixed_gamma <= 10.0)) {
    return Fail(why, "camera.lut_gamma and camera.fixed_gamma must lie in [0.1, 10]");
  }
  if (drop_exposure_chunks_from_frame < 0) {
    return Fail(why, "camera.drop_exposure_chunks_from_frame must be >= 0 (0 = never)");
  }
  return true;
}

bool RigPhysics::IsValid(std::string* why) const {
  if (!bounds::kTimeScale.Contains(time_scale)) {
    return Fail(why, "time_scale must lie in [0.01, 1000]");
  }
  return emitter.IsValid(why) && optics.IsValid(why) && sensor.IsValid(why) &&
         camera.IsValid(why) && scene.IsValid(why);
}

namespace {

using yaml_fields::MapReader;

// The `seed` key: a whole number in [0, 2^64).
std::uint64_t ReadSeed(const MapReader& keys, const std::string& key, std::uint64_t fallback) {
  if (!keys.Has(key)) return fallback;
  const YAML::Node node = keys.Get(key);
  std::uint64_t value = 0;
  if (!node.IsScalar() || node.Scalar().find('-') != std::string::npos ||
      !YAML::convert<std::uint64_t>::decode(node, value)) {
    yaml_fields::Fail(keys.File(), node.Mark(), key + " must be a whole number >= 0");
  }
  return value;
}

std::string FormatNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", value);
  return text;
}

// A number checked against [lo, hi] at its own line.
double CheckedNumber(const MapReader& keys, const std::string& context, const std::string& key,
                     double fallback, double lo, double hi) {
  if (!keys.Has(key)) return fallback;
  const double value = keys.Number(key, fallback);
  if (!std::isfinite(value) || value < lo || value > hi) {
    yaml_fields::Fail(keys.File(), keys.Get(key).Mark(),
                      context + "." + key + " must lie in [" + FormatNumber(lo) +
                          ", " + FormatNumber(hi) + "], not " +
                          FormatNumber(value) + kFix);
  }
  return value;
}

// A whole number checked against [lo, hi] at its own line.
int CheckedInteger(const MapReader& keys, const std::string& context, const std::string& key,
                   int fallback, int lo, int hi) {
  if (!keys.Has(key)) return fallback;
  const int value = keys.Integer(key, fallback);
  if (value < lo || value > hi) {
    yaml_fields::Fail(keys.File(), keys.Get(key).Mark(),
                      context + "." + key + " must be " + std::to_string(lo) + ".." +
                          std::to_string(hi) + ", not " + std::to_string(value) + kFix);
  }
  return value;
}

// A list of N finite numbers, e.g. [lo, hi] or [x, y, z].
template <size_t N>
std::array<double, N> ReadNumbers(const MapReader& keys, const std::string& context,
                                  const std::string& key, const std::array<double, N>& fallback) {
  if (!keys.Has(key)) return fallback;
  const YAML::Node node = keys.Get(key);
  const std::string what = context + "." + key;
  if (!node.IsSequence() || node.size() != N) {
    yaml_fields::Fail(keys.File(), node.Mark(),
                      what + " must be a list of " + std::to_string(N) + " numbers" + kFix);
  }
  std::array<double, N> values{};
  for (size_t i = 0; i < N; ++i) {
    values[i] = yaml_fields::AsNumber(node[i], keys.File(), what);
    if (!std::isfinite(values[i])) {
      yaml_fields::Fail(keys.File(), node[i].Mark(), what + " must hold finite numbers" + kFix);
    }
  }
  return values;
}

// A subsection's combined check (ranges, sums), at the line of the first of `keys_named` that the
// reason names and the map holds, else at the subsection's first key.
void CheckAt(const MapReader& keys, bool valid, const std::string& why,
             const std::vector<std::string>& keys_named) {
  if (valid) return;
  YAML::Mark mark = keys.Mark();
  for (const std::string& key : keys_named) {
    if (why.find("." + key + " ") != std::string::npos && keys.Has(key)) {
      mark = keys.Get(key).Mark();
      break;
    }
  }
  yaml_fields::Fail(keys.File(), mark, "virtual." + why + kFix);
}

EmissionPattern ReadPattern(const MapReader& keys, EmissionPattern fallback) {
  if (!keys.Has("pattern")) return fallback;
  const YAML::Node node = keys.Get("pattern");
  const std::string name = yaml_fields::AsString(node, keys.File(), "virtual.emitter.pattern");
  if (name == "gaussian") return EmissionPattern::kGaussian;
  if (name == "cos_power") return EmissionPattern::kCosPower;
  yaml_fields::Fail(keys.File(), node.Mark(),
                    "virtual.emitter.pattern must be 'gaussian' or 'cos_power', not '" + name + "'");
}

void ReadEmitter(const YAML::Node& node, const std::string& file, EmitterOptions* e) {
  const MapReader k(node, file, "virtual.emitter",
                    {"diameter_mm", "threshold_ma", "slope_mw_sr_per_ma", "sublinear_per_ma",
                     "pattern", "pattern_sigma_deg", "pattern_cos_power", "wavelength_nm",
                     "temp_coeff_per_k", "ambient_c", "forward_voltage_v",
                     "thermal_resistance_k_per_w", "thermal_time_constant_s", "offset_x_mm",
                     "offset_y_mm"});
  e->diameter_mm = k.Number("diameter_mm", e->diameter_mm);
  e->threshold_ma = k.Number("threshold_ma", e->threshold_ma);
  e->slope_mw_sr_per_ma = k.Number("slope_mw_sr_per_ma", e->slope_mw_sr_per_ma);
  e->sublinear_per_ma = k.Number("sublinear_per_ma", e->sublinear_per_ma);
  e->pattern = ReadPattern(k, e->pattern);
  e->pattern_sigma_deg = k.Number("pattern_sigma_deg", e->pattern_sigma_deg);
  e->pattern_cos_power = k.Number("pattern_cos_power", e->pattern_cos_power);
  e->wavelength_nm = k.Number("wavelength_nm", e->wavelength_nm);
  e->temp_coeff_per_k = k.Number("temp_coeff_per_k", e->temp_coeff_per_k);
  e->ambient_c = k.Number("ambient_c", e->ambient_c);
  e->forward_voltage_v = k.Number("forward_voltage_v", e->forward_voltage_v);
  e->thermal_resistance_k_per_w =
      k.Number("thermal_resistance_k_per_w", e->thermal_resistance_k_per_w);
  e->thermal_time_constant_s = k.Number("thermal_time_constant_s", e->thermal_time_constant_s);
  e->offset_x_mm = k.Number("offset_x_mm", e->offset_x_mm);
  e->offset_y_mm = k.Number("offset_y_mm", e->offset_y_mm);
}

void ReadOptics(const YAML::Node& node, const std::string& file, OpticsOptions* o) {
  const MapReader k(
      node, file, "virtual.optics",
      {"focal_length_mm", "f_number", "lens_transmission", "filter_transmission", "psf_sigma_px",
       "psf_sigma_minor_px", "psf_angle_deg", "focus_mm", "defocus_disc", "airy_first_zero_px",
       "halo_share", "halo_sigma_px", "vignetting", "supersample"});
  o->focal_length_mm = k.Number("focal_length_mm", o->focal_length_mm);
  o->f_number = k.Number("f_number", o->f_number);
  o->lens_transmission = k.Number("lens_transmission", o->lens_transmission);
  o->filter_transmission = k.Number("filter_transmission", o->filter_transmission);
  o->psf_sigma_px = k.Number("psf_sigma_px", o->psf_sigma_px);
  o->psf_sigma_minor_px = k.Number("psf_sigma_minor_px", o->psf_sigma_minor_px);
  o->psf_angle_deg = k.Number("psf_angle_deg", o->psf_angle_deg);
  o->focus_mm = k.Number("focus_mm", o->focus_mm);
  o->defocus_disc = k.Boolean("defocus_disc", o->defocus_disc);
  o->airy_first_zero_px = k.Number("airy_first_zero_px", o->airy_first_zero_px);
  o->halo_share = k.Number("halo_share", o->halo_share);
  o->halo_sigma_px = k.Number("halo_sigma_px", o->halo_sigma_px);
  o->vignetting = k.Boolean("vignetting", o->vignetting);
  o->supersample = k.Integer("supersample", o->supersample);
  std::string why;
  CheckAt(k, o->IsValid(&why), why,
          {"psf_sigma_px", "psf_sigma_minor_px", "psf_angle_deg", "halo_share", "halo_sigma_px",
           "focal_length_mm", "f_number", "focus_mm", "supersample", "airy_first_zero_px"});
}

// The defect pixels' keys, flat in `virtual.sensor:` (sim/defect_pixels.h).
void ReadDefects(const MapReader& k, SensorOptions* s) {
  const std::string at = "virtual.sensor";
  DefectPixelOptions& d = s->defects;
  d.hot_pixels = CheckedInteger(k, at, "hot_pixels", d.hot_pixels, 0, 100000);
  d.hot_rate_e_per_s = ReadNumbers(k, at, "hot_rate_e_per_s", d.hot_rate_e_per_s);
  d.stuck_pixels = CheckedInteger(k, at, "stuck_pixels", d.stuck_pixels, 0, 100000);
  d.stuck_level_dn = ReadNumbers(k, at, "stuck_level_dn", d.stuck_level_dn);
  d.defect_seed = ReadSeed(k, "defect_seed", d.defect_seed);
  d.defects_near_blob =
      CheckedInteger(k, at, "defects_near_blob", d.defects_near_blob, 0, 100000);
  d.near_blob_radius_px =
      CheckedNumber(k, at, "near_blob_radius_px", d.near_blob_radius_px, 1.0, 200.0);
  std::string why;
  CheckAt(k, d.IsValid(s->AdcMax(), &why), why,
          {"hot_rate_e_per_s", "stuck_level_dn", "defects_near_blob"});
}

void ReadSensor(const YAML::Node& node, const std::string& file, SensorOptions* s) {
  const MapReader k(node, file, "virtual.sensor",
                    {"width_px", "height_px", "pixel_pitch_um", "quantum_efficiency",
                     "full_well_e", "system_gain_dn_per_e", "read_noise_e",
                     "dark_current_e_per_s", "black_level_dn", "adc_bits", "nonlinearity",
                     "background_e_per_s", "temperature_c", "prnu_percent", "dsnu_e",
                     "crosstalk_sigma_px", "crosstalk_shape", "pixel_aperture", "hot_pixels",
                     "hot_rate_e_per_s", "stuck_pixels", "stuck_level_dn", "defect_seed",
                     "defects_near_blob", "near_blob_radius_px"});
  s->width_px = k.Integer("width_px", s->width_px);
  s->height_px = k.Integer("height_px", s->height_px);
  s->pixel_pitch_um = k.Number("pixel_pitch_um", s->pixel_pitch_um);
  s->quantum_efficiency = k.Number("quantum_efficiency", s->quantum_efficiency);
  s->full_well_e = k.Number("full_well_e", s->full_well_e);
  s->system_gain_dn_per_e = k.Number("system_gain_dn_per_e", s->system_gain_dn_per_e);
  s->read_noise_e = k.Number("read_noise_e", s->read_noise_e);
  s->dark_current_e_per_s = k.Number("dark_current_e_per_s", s->dark_current_e_per_s);
  s->black_level_dn = k.Number("black_level_dn", s->black_level_dn);
  s->adc_bits = k.Integer("adc_bits", s->adc_bits);
  s->nonlinearity = k.Number("nonlinearity", s->nonlinearity);
  s->background_e_per_s = k.Number("background_e_per_s", s->background_e_per_s);
  s->temperature_c = k.Number("temperature_c", s->temperature_c);
  s->prnu_percent = k.Number("prnu_percent", s->prnu_percent);
  s->dsnu_e = k.Number("dsnu_e", s->dsnu_e);
  s->crosstalk_sigma_px = k.Number("crosstalk_sigma_px", s->crosstalk_sigma_px);
  s->pixel_aperture = k.Number("pixel_aperture", s->pixel_aperture);
  if (k.Has("crosstalk_shape")) {
    const std::string shape = k.String("crosstalk_shape", "");
    if (shape != "lattice_walk" && shape != "sampled_gaussian") {
      yaml_fields::Fail(file, k.Get("crosstalk_shape").Mark(),
                        "virtual.sensor.crosstalk_shape '" + shape.substr(0, 40) +
                            "' is neither lattice_walk (charge diffusing pixel to pixel) nor "
                            "sampled_gaussian (a Gaussian sampled on the pixels, cut at 4 sd)");
    }
    s->crosstalk_shape = shape == "sampled_gaussian" ? CrosstalkShape::kSampledGaussian
                                                     : CrosstalkShape::kLatticeWalk;
  }
  ReadDefects(k, s);
}

void ReadCamera(const YAML::Node& node, const std::string& file, CameraOptions* c) {
  const MapReader k(node, file, "virtual.camera",
                    {"readout_ms", "trigger_frequency_hz", "drop_frame_rate",
                     "lost_packet_ratio", "exposure_write_delay_ms", "lut_enable", "lut_gamma",
                     "fixed_gamma", "drop_exposure_chunks_from_frame", "packet_resend"});
  c->readout_ms = k.Number("readout_ms", c->readout_ms);
  c->trigger_frequency_hz = k.Number("trigger_frequency_hz", c->trigger_frequency_hz);
  c->drop_frame_rate = k.Number("drop_frame_rate", c->drop_frame_rate);
  c->lost_packet_ratio = k.Number("lost_packet_ratio", c->lost_packet_ratio);
  c->exposure_write_delay_ms = k.Number("exposure_write_delay_ms", c->exposure_write_delay_ms);
  c->lut_enable = k.Boolean("lut_enable", c->lut_enable);
  c->lut_gamma = CheckedNumber(k, "virtual.camera", "lut_gamma", c->lut_gamma, 0.1, 10.0);
  c->fixed_gamma = CheckedNumber(k, "virtual.camera", "fixed_gamma", c->fixed_gamma, 0.1, 10.0);
  c->drop_exposure_chunks_from_frame =
      CheckedInteger(k, "virtual.camera", "drop_exposure_chunks_from_frame",
                     c->drop_exposure_chunks_from_frame, 0, 1000000000);
  c->packet_resend = k.Boolean("packet_resend", c->packet_resend);
}

void ReadAmbient(const YAML::Node& node, const std::string& file, AmbientOptions* a) {
  const std::string at = "virtual.scene.ambient";
  const MapReader k(node, file, at, {"center_e_per_s", "gradient_x_percent", "gradient_y_percent"});
  a->center_e_per_s = CheckedNumber(k, at, "center_e_per_s", a->center_e_per_s, 0.0, 1e8);
  a->gradient_x_percent =
      CheckedNumber(k, at, "gradient_x_percent", a->gradient_x_percent, -200.0, 200.0);
  a->gradient_y_percent =
      CheckedNumber(k, at, "gradient_y_percent", a->gradient_y_percent, -200.0, 200.0);
  std::string why;
  CheckAt(k, a->IsValid(&why), why, {"gradient_x_percent"});
}

void ReadReflection(const YAML::Node& node, const std::string& file, ReflectionOptions* r) {
  const std::string at = "virtual.scene.reflection";
  const MapReader k(node, file, at, {"plane_below_mm", "reflectance"});
  r->plane_below_mm = CheckedNumber(k, at, "plane_below_mm", r->plane_below_mm, 0.0, 1000.0);
  r->reflectance = CheckedNumber(k, at, "reflectance", r->reflectance, 0.0, 1.0);
}

void ReadSecondSource(const YAML::Node& node, const std::string& file, SecondSourceOptions* o) {
  const std::string at = "virtual.scene.second_source";
  const MapReader k(node, file, at, {"position_mm", "diameter_mm", "intensity_mw_sr"});
  o->position_mm = ReadNumbers(k, at, "position_mm", o->position_mm);
  o->diameter_mm = CheckedNumber(k, at, "diameter_mm", o->diameter_mm, 1e-3, 1000.0);
  o->intensity_mw_sr = CheckedNumber(k, at, "intensity_mw_sr", o->intensity_mw_sr, 0.0, 1e6);
  std::string why;
  CheckAt(k, o->IsValid(&why), why, {"position_mm", "diameter_mm"});
}

void ReadOccluder(const YAML::Node& node, const std::string& file, OccluderOptions* o) {
  const std::string at = "virtual.scene.occluder";
  const MapReader k(node, file, at, {"covered_fraction", "edge_angle_deg"});
  o->covered_fraction = CheckedNumber(k, at, "covered_fraction", o->covered_fraction, 0.0, 0.95);
  o->edge_angle_deg = CheckedNumber(k, at, "edge_angle_deg", o->edge_angle_deg, -360.0, 360.0);
}

// `virtual.scene:` (sim/lab_scene_options.h), every key checked at its own line.
void ReadScene(const YAML::Node& node, const std::string& file, LabSceneOptions* s) {
  const MapReader k(node, file, "virtual.scene",
                    {"ambient", "reflection", "second_source", "occluder"});
  if (k.Has("ambient")) ReadAmbient(k.Get("ambient"), file, &s->ambient);
  if (k.Has("reflection")) ReadReflection(k.Get("reflection"), file, &s->reflection);
  if (k.Has("second_source")) ReadSecondSource(k.Get("second_source"), file, &s->second_source);
  if (k.Has("occluder")) ReadOccluder(k.Get("occluder"), file, &s->occluder);
}

// The `virtual:` section. `devices` (the device emulators', sim/line_device.cc) and `station`
// (the station emulator's, LoadEmulatorOptions) are skipped here: their owners read them strictly.
RigPhysics ReadVirtualSection(const YAML::Node& section, const std::string& file) {
  RigPhysics physics;
  const MapReader k(section, file, "virtual",
                    {"time_scale", "seed", "serial", "emitter", "optics", "sensor", "camera",
                     "scene", "devices", "station"});
  physics.time_scale = k.Number("time_scale", physics.time_scale);
  physics.sensor.seed = ReadSeed(k, "seed", physics.sensor.seed);
  physics.camera.serial = k.String("serial", physics.camera.serial);
  if (k.Has("emitter")) ReadEmitter(k.Get("emitter"), file, &physics.emitter);
  if (k.Has("optics")) ReadOptics(k.Get("optics"), file, &physics.optics);
  if (k.Has("sensor")) ReadSensor(k.Get("sensor"), file, &physics.sensor);
  if (k.Has("camera")) ReadCamera(k.Get("camera"), file, &physics.camera);
  if (k.Has("scene")) ReadScene(k.Get("scene"), file, &physics.scene);
  std::string why;
  if (!physics.IsValid(&why)) {
    yaml_fields::Fail(file, section.Mark(),
                      "virtual: " + why +
                          "; fix the value in the rig file (docs/virtual-rig.md lists the ranges)");
  }
  return physics;
}

RigPhysics ReadRigPhysics(const std::string& rig_path) {
  const YAML::Node root = yaml_fields::Parse(yaml_fields::ReadFile(rig_path), rig_path);
  const YAML::Node section = root.IsMap() ? root["virtual"] : YAML::Node();
  if (!section || section.IsNull()) return RigPhysics();
  return ReadVirtualSection(section, rig_path);
}

}  // namespace

RigPhysics LoadRigPhysics(const std::string& rig_path) {
  try {
    return ReadRigPhysics(rig_path);
  } catch (const RigFileError&) {
    throw;
  } catch (const InputError& e) {
    throw RigFileError(e.File(), e.Line(), e.Column(), e.Message());
  }
}

}  // namespace irdist::sim
