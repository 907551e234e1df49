#include "sim/defect_pixels.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <unordered_set>
#include <vector>

#include "base/check.h"

namespace irdist::sim {
namespace {

constexpr int kMaxAttemptsPerPixel = 100000;

// The defects' kinds and values (rates, levels), shuffled so that the near ones are a mix.
std::vector<DefectPixel> DrawKinds(const DefectPixelOptions& o, std::mt19937_64& rng) {
  std::vector<DefectPixel> defects;
  std::uniform_real_distribution<double> rate(o.hot_rate_e_per_s[0], o.hot_rate_e_per_s[1]);
  std::uniform_real_distribution<double> level(o.stuck_level_dn[0], o.stuck_level_dn[1]);
  for (int k = 0; k < o.hot_pixels; ++k) {
    defects.push_back({0, 0, DefectPixel::Kind::kHot, rate(rng)});
  }
  for (int k = 0; k < o.stuck_pixels; ++k) {
    defects.push_back({0, 0, DefectPixel::Kind::kStuck, std::round(level(rng))});
  }
  std::shuffle(defects.begin(), defects.end(), rng);
  return defects;
}

}  // namespace

std::vector<DefectPixel> PlaceDefectPixels(const DefectPixelOptions& options, int width_px,
                                           int height_px, double near_x_px, double near_y_px) {
  std::string why;
  IRDIST_CHECK(options.IsValid(1 << 16, &why), why);
  std::mt19937_64 rng(options.defect_seed ^ 0xD1FEC7ED5EEDull);
  std::vector<DefectPixel> defects = DrawKinds(options, rng);
  const double r = options.near_blob_radius_px;
  IRDIST_CHECK(options.defects_near_blob == 0 ||
                   (near_x_px > -r && near_x_px < width_px + r && near_y_px > -r &&
                    near_y_px < height_px + r),
               "the emitter's image centre (", near_x_px, ", ", near_y_px,
               ") px is off the sensor: no defect pixel can lie near it; set "
               "defects_near_blob to 0 or bring the emitter's offset into the field of view");
  std::unordered_set<std::int64_t> used;
  // Uniform over the square around the centre (near) or the sensor (far), kept when on the right
  // side of the radius and not yet taken.
  auto place = [&](DefectPixel& d, bool near) {
    std::uniform_real_distribution<double> x(near ? near_x_px - r : 0.0,
                                             near ? near_x_px + r : width_px);
    std::uniform_real_distribution<double> y(near ? near_y_px - r : 0.0,
                                             near ? near_y_px + r : height_px);
    for (int attempt = 0; attempt < kMaxAttemptsPerPixel; ++attempt) {
      const int px = static_cast<int>(std::floor(x(rng)));
      const int py = static_cast<int>(std::floor(y(rng)));
      if (px < 0 || py < 0 || px >= width_px || py >= height_px) continue;
      const double dx = px + 0.5 - near_x_px, dy = py + 0.5 - near_y_px;
      if ((dx * dx + dy * dy <= r * r) != near) continue;
      if (!used.insert(static_cast<std::int64_t>(py) * width_px + px).second) continue;
      d.x_px = px;
      d.y_px = py;
      return;
    }
    IRDIST_CHECK(false, "no room on the sensor for the defect pixels ", near ? "near" : "away from",
                 " the emitter's image; lower defects_near_blob or the defect count");
  };
  for (size_t k = 0; k < defects.size(); ++k) {
    place(defects[k], static_cast<int>(k) < options.defects_near_blob);
  }
  return defects;
}

}  // namespace irdist::sim
