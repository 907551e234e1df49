#include "app/processing/track_truth.h"

#include <cmath>
#include <map>
#include <utility>

#include "app/processing/crb.h"
#include "base/check.h"
#include "sim/motion_profile.h"
#include "sim/rig_physics.h"
#include "sim/trajectory.h"
#include "sim/trajectory_file.h"

namespace irdist {

namespace {

// The bound's grid: every 250 mm in d and every degree of theta; linear in d between the
// grid's points (the bound varies smoothly with the distance: tests/integration's measured
// track compares with the same interpolation).
constexpr double kBoundStepMm = 250.0;

class OneFrameBound {
 public:
  OneFrameBound(const std::string& rig_path, double bias_ma)
      : physics_(sim::LoadRigPhysics(rig_path)),
        bias_ma_(bias_ma),
        rise_k_(SteadyJunctionRiseK(physics_, bias_ma)) {}

  // The bound on d (mm) of one frame exposed `exposure_ms` at (d_mm, theta_deg).
  double At(double d_mm, double theta_deg, double exposure_ms) {
    const double x = d_mm / kBoundStepMm;
    const long below = static_cast<long>(std::floor(x));
    const double w = x - static_cast<double>(below);
    const long theta = std::lround(theta_deg);
    const double lo = Grid(below, theta, exposure_ms);
    return w == 0.0 ? lo : lo + w * (Grid(below + 1, theta, exposure_ms) - lo);
  }

 private:
  double Grid(long d_index, long theta_deg, double exposure_ms) {
    const auto key = std::make_pair(std::make_pair(d_index, theta_deg), exposure_ms);
    const auto it = cache_.find(key);
    if (it != cache_.end()) return it->second;
    const CrbResult r = ComputeCrb(
        physics_, {static_cast<double>(d_index) * kBoundStepMm, static_cast<double>(theta_deg),
                   bias_ma_, rise_k_, {exposure_ms}});
    return cache_[key] = r.valid ? r.d_sd_mm : NAN;
  }

  sim::RigPhysics physics_;
  double bias_ma_, rise_k_;
  std::map<std::pair<std::pair<long, long>, double>, double> cache_;
};

// Seconds since the slide's cruise began at `time_s` (NaN when not cruising).
double CruiseSeconds(const sim::Trajectory& trajectory, double time_s) {
  for (const sim::MotionProfile& p : trajectory.Profiles(sim::RigAxis::kSlide)) {
    const double cruise_start_s = p.start_s + p.t_acc;
    if (p.t_cruise > 0.0 && time_s >= cruise_start_s && time_s < cruise_start_s + p.t_cruise) {
      return time_s - cruise_start_s;
    }
  }
  return NAN;
}

}  // namespace

std::vector<TrackTruth> VirtualTrackTruths(const std::vector<TrackFrameRow>& rows,
                                           const std::string& trajectory_csv,
                                           const std::string& rig_path, double bias_ma) {
  const sim::Trajectory trajectory = sim::ReadTrajectoryFile(trajectory_csv);
  OneFrameBound bound(rig_path, bias_ma);
  std::vector<TrackTruth> truths(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const TrackFrameRow& r = rows[i];
    if (r.camera_timestamp_ns == 0 || !std::isfinite(r.exposure_ms)) continue;
    const sim::TrajectoryPoint p =
        sim::MidExposure(trajectory, r.camera_timestamp_ns, r.exposure_ms * 1000.0);
    if (!p.known) continue;
    TrackTruth& t = truths[i];
    t.known = true;
    t.d_mm = p.slide_mm;
    t.v_mm_per_s = p.slide_mm_s;
    t.sd_mm = 0.0;  // the emulator's own profile: exact
    t.cruise_s = CruiseSeconds(trajectory, p.time_s);
    t.bound_mm = bound.At(p.slide_mm, p.theta_deg, r.exposure_ms);
  }
  return truths;
}

std::vector<TrackTruth> CommandedTrackTruths(const std::vector<TrackFrameRow>& rows,
                                             const std::vector<std::int64_t>& monotonic_ns,
                                             const std::vector<CommandedMove>& moves,
                                             double readout_ms, double truth_sd_mm) {
  IRDIST_CHECK(rows.size() == monotonic_ns.size(), "rows ", rows.size());
  std::vector<sim::MotionProfile> profiles;
  for (const CommandedMove& m : moves) {
    profiles.push_back(sim::MotionProfile::Make(m.from_mm, m.to_mm,
                                                static_cast<double>(m.start_monotonic_ns) * 1e-9,
                                                0.0, m.speed_mm_s, m.accel_mm_s2));
  }
  std::vector<TrackTruth> truths(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (monotonic_ns[i] <= 0 || !std::isfinite(rows[i].exposure_ms)) continue;
    const double t_s = static_cast<double>(monotonic_ns[i]) * 1e-9 -
                       (readout_ms + 0.5 * rows[i].exposure_ms) * 1e-3;
    const sim::MotionProfile* under_way = nullptr;
    for (const sim::MotionProfile& p : profiles) {
      if (p.start_s <= t_s) under_way = &p;
    }
    if (under_way == nullptr) continue;  // before the first commanded move: not known
    TrackTruth& t = truths[i];
    t.known = true;
    t.d_mm = under_way->PositionAt(t_s);
    t.v_mm_per_s = under_way->VelocityAt(t_s);
    t.sd_mm = truth_sd_mm;
    const double cruise_start_s = under_way->start_s + under_way->t_acc;
    if (t_s >= cruise_start_s && t_s < cruise_start_s + under_way->t_cruise) {
      t.cruise_s = t_s - cruise_start_s;
    }
    t.bound_mm = rows[i].d_se_mm;  // no physics on a real rig: the calibration's noise model
  }
  return truths;
}

}  // namespace irdist
