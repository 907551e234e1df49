#pragma once
// Every physical parameter of the virtual rig's camera side (emitter, optics, sensor, timing,
// camera faults), read from the `virtual:` section of a rig file (recipes/rigs/virtual.yaml).
// docs/virtual-rig.md explains each field, its physical meaning and the source of its default.
// The `virtual.station:` subsection belongs to the station emulator (LoadEmulatorOptions).

#include <cstdint>
#include <string>

#include "base/check.h"
#include "base/input_error.h"
#include "sim/lab_scene_options.h"

namespace irdist::sim {

// A rig file that cannot be read or holds a bad `virtual:` key or value: an InputError naming the
// file and line and saying what to change.
class RigFileError : public InputError {
 public:
  using InputError::InputError;
};

enum class EmissionPattern {
  kGaussian,  // rho(a) = exp(-a^2 / (2 sigma^2))
  kCosPower,  // rho(a) = cos(a)^m (m = 1 is a Lambertian emitter)
};

struct EmitterOptions {
  double diameter_mm = 10.0;  // diameter of the uniformly bright circular emitting disc
  // Radiant intensity on the emission axis at the reference temperature:
  // I0 = slope * (i - threshold) * (1 - sublinear_per_ma * (i - threshold)), 0 below threshold.
  double threshold_ma = 50.0;
  double slope_mw_sr_per_ma = 0.5;
  double sublinear_per_ma = 0.0;  // droop at high current (0 = linear)
  EmissionPattern pattern = EmissionPattern::kGaussian;
  double pattern_sigma_deg = 30.0;  // Gaussian width of the emission pattern
  double pattern_cos_power = 4.0;   // exponent m of the cos^m pattern
  double wavelength_nm = 850.0;     // peak emission wavelength (photon energy)
  // Thermal model: junction temperature T = ambient + dT, dT' = (R_th * i * V_f - dT) / tau;
  // intensity scales by (1 + temp_coeff_per_k * dT).
  double temp_coeff_per_k = -0.005;
  double ambient_c = 25.0;
  double forward_voltage_v = 1.6;             // electrical power i * V_f heats the junction
  double thermal_resistance_k_per_w = 20.0;   // steady-state junction rise per watt
  double thermal_time_constant_s = 60.0;      // first-order time constant of the rise
  // Lateral offset of the emitter centre from the optical axis (the slide runs along the axis).
  double offset_x_mm = 0.0;
  double offset_y_mm = 0.0;
  bool IsValid(std::string* why) const;
};

struct OpticsOptions {
  double focal_length_mm = 16.0;
  double f_number = 8.0;              // working aperture N: irradiance ~ pi L / (4 N^2)
  double lens_transmission = 0.9;     // transmission of the lens at the emitter wavelength
  double filter_transmission = 1.6e-4;  // band-pass + neutral-density filter stack in front
  // In-focus lens PSF: Gaussian sigma (diffraction at N = 8 plus residual aberrations), pixels.
  // With psf_sigma_minor_px set, the sd along psf_angle_deg's direction.
  double psf_sigma_px = 0.7;
  // An astigmatic lens: the PSF an ellipse, sd psf_sigma_px along the direction psf_angle_deg
  // (degrees from the sensor's rows, +x towards +y) and psf_sigma_minor_px across it, the same at
  // every distance (in pixels). 0 = round (psf_sigma_px both ways).
  double psf_sigma_minor_px = 0.0;
  double psf_angle_deg = 0.0;
  // Thin-lens focus: the object distance (mm, along the optical axis) imaged sharply. An object at
  // d is blurred by a circle of confusion of diameter c = (f / N) f |d - s| / (d (s - f)) on the
  // sensor, added to the PSF as a Gaussian of the same per-axis variance c^2 / 16 (Scene::BlurSigmaPx).
  // 0 = no defocus: the blur is psf_sigma_px at every distance (recipes/rigs/virtual-fixed-blur.yaml).
  double focus_mm = 2000.0;
  // The defocus as the geometric optics has it: false, the Gaussian of variance c^2 / 16 above;
  // true, the uniform disc of diameter c itself (a defocused lens's PSF), convolved with the
  // in-focus PSF (sim/lens_psf.h).
  bool defocus_disc = false;
  // A diffraction-limited lens: the Airy pattern (2 J1(x) / x)^2, its first dark ring at this
  // radius (px; 1.22 lambda N / pitch), out to its third dark ring (2.66x), convolved with the
  // in-focus PSF above (>= 0.3 px: it smooths the pattern's quadrature). 0 = none; else [0.3, 3].
  // Not with defocus_disc.
  double airy_first_zero_px = 0.0;
  // Veiling glare: this share of the light (0..0.5) spread by a round Gaussian of halo_sigma_px
  // (scatter in the lens and the filters), the rest through the PSF above. 0 = none.
  double halo_share = 0.0;
  double halo_sigma_px = 8.0;
  bool vignetting = true;             // cos^4 of the field angle
  int supersample = 8;  // integration strips per pixel of the disc image's height (>= 32 in all)
  bool IsValid(std::string* why) const;
};

enum class PixelFormat { kMono8, kMono12, kMono16 };

// The per-axis shape of the crosstalk's kernel (sim/sensor.h CrosstalkKernel).
enum class CrosstalkShape {
  kLatticeWalk,      // charge diffusing pixel to pixel: e^-t I_n(t), t = sigma^2
  kSampledGaussian,  // a Gaussian sampled on the pixel grid and truncated at 4 sd
};

struct SensorOptions {
  int width_px = 1280;
  int height_px = 1024;
  double pixel_pitch_um = 5.3;
  double quantum_efficiency = 0.35;   // electrons per photon at the emitter wavelength
  double full_well_e = 10500.0;       // electrons at which a pixel saturates
  double system_gain_dn_per_e = 0.39; // K, ADC counts per electron
  double read_noise_e = 7.0;          // temporal dark noise, electrons rms
  double dark_current_e_per_s = 20.0; // at the sensor temperature below
  double black_level_dn = 16.0;       // offset added before the ADC, ADC counts
  int adc_bits = 12;                  // Mono12 carries the ADC value, Mono8/Mono16 are shifted
  double nonlinearity = 0.0;          // y = x - nonlinearity * x^2 / x_max (0 = linear)
  double background_e_per_s = 0.0;    // uniform background photo-electrons per pixel
  double temperature_c = 40.0;        // sensor temperature, reported as DeviceTemperature
  // Fixed-pattern noise (EMVA 1288), drawn once per camera from `seed` (its own stream): PRNU, the
  // per-pixel gain's sd in percent; DSNU, the per-pixel dark offset's sd in electrons. 0 = off.
  double prnu_percent = 0.0;
  double dsnu_e = 0.0;
  // Inter-pixel crosstalk (charge diffusion between neighbouring pixels after the photons are
  // counted, before read-out): the per-axis sd (px) of the kernel each pixel's photo-electrons
  // spread by (sim/sensor.h CrosstalkKernel; its shape crosstalk_shape). 0 = none.
  double crosstalk_sigma_px = 0.0;
  CrosstalkShape crosstalk_shape = CrosstalkShape::kLatticeWalk;  // key crosstalk_shape
  // The pixel's sensitive square (a fill factor), a share of the pitch per side, centred: its
  // response to an edge is that square's, normalised so that a flat field reads the same (the
  // quantum efficiency is the whole pixel's). 1 = the whole pixel.
  double pixel_aperture = 1.0;
  std::uint64_t seed = 1;             // noise of frame n is drawn from (seed, n)
  // Hot and stuck pixels (sim/defect_pixels.h), none by default; keys flat in `virtual.sensor:`.
  DefectPixelOptions defects;
  bool IsValid(std::string* why) const;
  int AdcMax() const { return (1 << adc_bits) - 1; }
};

struct CameraOptions {
  std::string serial = "IRDV0001";     // GigE serial number (< 16 characters)
  double readout_ms = 12.0;            // sensor readout after the exposure ends
  double trigger_frequency_hz = 2000;  // unused (the camera reacts at once); kept for rig files
  double drop_frame_rate = 0.0;        // probability that a whole frame is never sent
  double lost_packet_ratio = 0.0;      // probability that each GVSP packet is lost
  double exposure_write_delay_ms = 0.0;  // ExposureTime writes applied after up to this (fault)
  // Pixel-shaping faults (docs/virtual-rig.md): a LUT left on by a previous user (LUTEnable true at
  // start, writable) holding the curve DN' = FS (DN / FS)^lut_gamma; and a gamma curve the camera
  // applies always, with no feature to switch it (fixed_gamma; 1 = none).
  bool lut_enable = false;
  double lut_gamma = 0.45;
  double fixed_gamma = 1.0;
  // Exposure chunks sent while the host asks for them (ChunkModeActive, ChunkEnable), dropped
  // from this frame on (frames counted from 1 as exposed, warm-up frames included; 1 = every
  // frame, as a NIC or firmware that loses them; 0 = never dropped). The image chunk stays.
  int drop_exposure_chunks_from_frame = 0;
  // GVCP packet resend declared and served; false = a camera without it (resend requests unheard).
  bool packet_resend = true;
  bool IsValid(std::string* why) const;
};

struct RigPhysics {
  double time_scale = 1.0;  // simulated seconds per host second (1 = real time)
  EmitterOptions emitter;
  OpticsOptions optics;
  SensorOptions sensor;
  CameraOptions camera;
  LabSceneOptions scene;  // `virtual.scene:`: the lab's extra light and the occluder, all off
  bool IsValid(std::string* why) const;
};

// Reads the `virtual:` section of a rig file (keys: time_scale, seed, serial, emitter:, optics:,
// sensor:, camera:, scene:, and station:, which is left to LoadEmulatorOptions). Absent keys keep their
// defaults; an unknown key, a wrong type or an invalid combination throws RigFileError naming
// the file and line.
RigPhysics LoadRigPhysics(const std::string& rig_path);

const char* PixelFormatName(PixelFormat format);

}  // namespace irdist::sim
