// A ratio model's poles inside its calibrated domain (estimator/model_poles.h).
#include "estimator/model_poles.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

namespace irdist {
namespace {

constexpr double kDRefMm = 1000.0;
constexpr double kDScale = 0.25;
constexpr double kMargin = 0.10;  // the estimator's range_margin

// D for a distance in mm, as the fit scales it: (d_ref / d)^2 / d_scale.
double BigD(double d_mm) { return (kDRefMm / d_mm) * (kDRefMm / d_mm) / kDScale; }

// Eq. 18's samples on a 3-distance grid (1500, 2000, 2500 mm) x thetas 0..30, dt 1, dF 1.
void Grid(std::vector<std::array<double, kNumModelVars>>* vars, std::vector<double>* thetas) {
  for (double d : {1500.0, 2000.0, 2500.0}) {
    for (double theta : {0.0, 10.0, 20.0, 30.0}) {
      std::array<double, kNumModelVars> v{};
      v[kVarD] = BigD(d);
      v[kVarDt] = 1.0;
      v[kVarDF] = 1.0;
      vars->push_back(v);
      thetas->push_back(theta);
    }
  }
}

// Eq. 18 with numerator p18 dF^2 and the denominator dF (p19 D rho + p20 rho + p21 D + p22).
std::vector<double> Sigma(double p19, double p20, double p21, double p22) {
  const ModelSpec& spec = GetModelSpec(ModelKind::kFreeSigma);
  std::vector<double> c(spec.num_coefficients(), 0.0);
  c[17] = 1.0;
  c[18] = p19;
  c[19] = p20;
  c[20] = p21;
  c[21] = p22;
  return c;
}

// Eq. 18 whose denominator is dF (rho + 0.38)(D - D(zero_mm)): a zero at zero_mm for every theta.
std::vector<double> SigmaWithZeroAt(double zero_mm) {
  const double d0 = BigD(zero_mm);
  return Sigma(1.0, -d0, 0.38, -0.38 * d0);
}

// The scan of the Eq. 18 model `c` (sigma 30 deg) over the 3-distance grid.
PoleScan ScanGrid(const std::vector<double>& c, double margin = kMargin,
                  ModelKind kind = ModelKind::kFreeSigma) {
  std::vector<std::array<double, kNumModelVars>> vars;
  std::vector<double> thetas;
  Grid(&vars, &thetas);
  return ScanForPoles(GetModelSpec(kind), c, 30.0, vars, thetas, kDRefMm, kDScale, margin);
}

// The denominator a 3-distance calibration fitted (dF (rho + 0.38)(D - D(2000 mm))): a pole at
// 2000 mm, found and placed; one positive over the whole domain has none; one whose zero lies
// beyond the calibrated distances (at 1000 mm) has none inside them.
TEST(ScanForPoles, FindsADenominatorsZeroInsideTheCalibratedRange) {
  const PoleScan pole = ScanGrid(SigmaWithZeroAt(2000.0));
  ASSERT_TRUE(pole.pole);
  EXPECT_NEAR(pole.d_mm, 2000.0, 20.0);
  EXPECT_NE(pole.Note().find("vanishes at d = "), std::string::npos) << pole.Note();
  EXPECT_FALSE(ScanGrid(Sigma(0.0, 0.0, 1.0, 1.0)).pole);
  EXPECT_FALSE(ScanGrid(SigmaWithZeroAt(1000.0)).pole);
  // A zero only at large theta (rho small): p19 D rho + p22 with p22 < 0 vanishes where rho is
  // small enough, inside the thetas' range.
  const double rho_30 = Rho(30.0, 30.0), rho_0 = Rho(0.0, 30.0);
  const double mid = 0.5 * (rho_30 + rho_0) * BigD(2000.0);
  EXPECT_TRUE(ScanGrid(Sigma(1.0, 0.0, 0.0, -mid)).pole);
  EXPECT_FALSE(ScanGrid({}, kMargin, ModelKind::kDiffF).pole);  // no denominator
}

// The estimator takes roots within 10% beyond the calibrated distances, so a zero there is a pole
// too: one just beyond the grid's 2500 mm (at 2520 mm, where a halo lens's calibration once put
// Num's and Den's common zero) is found with the margin and not without it; one beyond the margin
// (3000 mm) is not.
TEST(ScanForPoles, FindsAZeroJustBeyondTheGridInsideTheEstimatorsMargin) {
  const PoleScan pole = ScanGrid(SigmaWithZeroAt(2520.0));
  ASSERT_TRUE(pole.pole);
  EXPECT_NEAR(pole.d_mm, 2520.0, 20.0);
  EXPECT_FALSE(ScanGrid(SigmaWithZeroAt(2520.0), 0.0).pole);
  EXPECT_FALSE(ScanGrid(SigmaWithZeroAt(3000.0)).pole);
  // And at the grid's own edge, where the sweep starts.
  EXPECT_TRUE(ScanGrid(SigmaWithZeroAt(2500.0)).pole);
}

}  // namespace
}  // namespace irdist
