#pragma once
// Synthetic features for the estimator's tests: E_rel, F(0,0) and Sigma generated from the
// product form of Table 2 with known factors (one common Gaussian sigma, so the I0-free models of
// Eq. 17-18 hold exactly), and the exact q and p derived from them by polynomial algebra (which
// also checks the monomial tables: every derived term must find its table entry).

#include <array>
#include <map>
#include <stdexcept>
#include <vector>

#include "estimator/fit.h"
#include "estimator/models.h"

namespace irdist::testing {

using Exponents = std::array<int, kNumModelVars>;
using Poly = std::map<Exponents, double>;

inline Poly Mul(const Poly& a, const Poly& b) {
  Poly out;
  for (const auto& [ea, ca] : a) {
    for (const auto& [eb, cb] : b) {
      Exponents e;
      for (int v = 0; v < kNumModelVars; ++v) e[v] = ea[v] + eb[v];
      out[e] += ca * cb;
    }
  }
  return out;
}

inline Poly Add(const Poly& a, const Poly& b, double sb = 1.0) {
  Poly out = a;
  for (const auto& [e, c] : b) out[e] += sb * c;
  return out;
}

inline Poly Term(double c, int d, int rho, int t, int i0, int dt, int df) {
  return Poly{{Exponents{d, rho, t, i0, dt, df}, c}};
}

// Linear factor c1 * var + c0 (var at exponent 1 of index v).
inline Poly Linear(int v, double c1, double c0) {
  Exponents one{};
  one[v] = 1;
  return Poly{{one, c1}, {Exponents{}, c0}};
}

// Coefficients of `spec` (numerator part from num, denominator from den); throws if a term of the
// polynomials has no entry in the table.
inline std::vector<double> ToCoefficients(const ModelSpec& spec, const Poly& num, const Poly& den) {
  std::vector<double> c(spec.num_coefficients(), 0.0);
  auto place = [&](const Poly& p, int first, int count) {
    for (const auto& [e, value] : p) {
      if (value == 0.0) continue;
      bool found = false;
      for (int j = first; j < first + count; ++j) {
        bool same = true;
        for (int v = 0; v < kNumModelVars; ++v) same = same && spec.terms[j].exponent[v] == e[v];
        if (same) {
          c[j] += value;
          found = true;
        }
      }
      if (!found) throw std::logic_error("a derived monomial is missing from the model table");
    }
  };
  place(num, 0, spec.num_numerator);
  if (spec.has_denominator()) place(den, spec.num_numerator, spec.num_denominator);
  return c;
}

// Terms of p with exponent `e` of variable v, that exponent removed.
inline Poly Select(const Poly& p, int v, int e) {
  Poly out;
  for (const auto& [key, c] : p) {
    if (key[v] != e) continue;
    Exponents ex = key;
    ex[v] = 0;
    out[ex] += c;
  }
  return out;
}

struct SyntheticRig {
  ModelScaling scaling;  // the scaled variables the factors below are written in
  double sigma_deg = 25.0;
  // Factors of Table 2 per feature: (tau1 t + tau2)(r1 I0 + r2)(delta(D))(g1 rho + g2).
  struct Factors {
    double tau1, tau2, r1, r2;
    std::vector<double> delta;  // ascending powers of D
    double g1, g2;
  };
  Factors e{1.0e-3, 0.2e-3, 1.0, 0.15, {0.3, 1.0}, 1.0, 0.35};
  Factors f{40.0, 6.0, 1.0, 0.05, {0.05, 1.0}, 1.0, 0.10};
  Factors s{0.02, 0.004, 1.0, 0.25, {0.6, 1.0, 0.4}, 1.0, 0.6};

  SyntheticRig() {
    scaling.d_scale = 0.25;
    scaling.t_scale_ms = 30.0;
    scaling.i0_scale_ma = 500.0;
    scaling.df_scale = 1.0;
  }

  // The direct model of one feature as a polynomial in the scaled variables.
  static Poly Direct(const Factors& x) {
    Poly delta;
    for (size_t k = 0; k < x.delta.size(); ++k)
      delta[Exponents{static_cast<int>(k), 0, 0, 0, 0, 0}] = x.delta[k];
    return Mul(Mul(Linear(kVarT, x.tau1, x.tau2), Linear(kVarI0, x.r1, x.r2)),
               Mul(delta, Linear(kVarRho, x.g1, x.g2)));
  }
  // The differential model: the t terms, t -> dt.
  static Poly Differential(const Factors& x) {
    Poly out;
    for (const auto& [key, c] : Direct(x)) {
      if (key[kVarT] != 1) continue;
      Exponents e = key;
      e[kVarT] = 0;
      e[kVarDt] = 1;
      out[e] += c;
    }
    return out;
  }
  // I0-free form of feature x given F: Num = dF dt X1 + dt^2 (X0 B1 - B0 X1), Den = dt B1.
  void Free(const Factors& x, Poly* num, Poly* den) const {
    const Poly dx = Select(Differential(x), kVarDt, 1);
    const Poly df = Select(Differential(f), kVarDt, 1);
    const Poly x1 = Select(dx, kVarI0, 1), x0 = Select(dx, kVarI0, 0);
    const Poly b1 = Select(df, kVarI0, 1), b0 = Select(df, kVarI0, 0);
    const Poly dt_df = Term(1.0, 0, 0, 0, 0, 1, 1);
    const Poly dt2 = Term(1.0, 0, 0, 0, 0, 2, 0);
    *num = Add(Mul(dt_df, x1), Mul(dt2, Add(Mul(x0, b1), Mul(b0, x1), -1.0)));
    *den = Mul(Term(1.0, 0, 0, 0, 0, 1, 0), b1);
  }

  std::vector<double> Coefficients(ModelKind kind) const {
    const ModelSpec& spec = GetModelSpec(kind);
    Poly num, den;
    switch (kind) {
      case ModelKind::kDirectE:
        num = Direct(e);
        break;
      case ModelKind::kDirectF:
        num = Direct(f);
        break;
      case ModelKind::kDirectSigma:
        num = Direct(s);
        break;
      case ModelKind::kDiffE:
        num = Differential(e);
        break;
      case ModelKind::kDiffF:
        num = Differential(f);
        break;
      case ModelKind::kDiffSigma:
        num = Differential(s);
        break;
      case ModelKind::kFreeE:
        Free(e, &num, &den);
        break;
      case ModelKind::kFreeSigma:
        Free(s, &num, &den);
        break;
    }
    return ToCoefficients(spec, num, den);
  }

  double Feature(ModelKind direct_kind, double t_ms, double bias_ma, double d_mm,
                 double theta_deg) const {
    ModelInputs in;
    in.t_ms = t_ms;
    in.bias_ma = bias_ma;
    in.d_mm = d_mm;
    in.theta_deg = theta_deg;
    return PredictModel(direct_kind, Coefficients(direct_kind), sigma_deg, scaling, in);
  }

  Features Frame(double t_ms, double bias_ma, double d_mm, double theta_deg,
                 double theta0_deg) const {
    Features x;
    x.blob_found = true;
    x.e_rel = Feature(ModelKind::kDirectE, t_ms, bias_ma, d_mm, theta_deg);
    x.f00 = Feature(ModelKind::kDirectF, t_ms, bias_ma, d_mm, theta_deg);
    x.sigma = Feature(ModelKind::kDirectSigma, t_ms, bias_ma, d_mm, theta_deg);
    x.theta0_deg = theta0_deg;
    // A disc whose image variance is 30 px^2 at 1 m, plus 1 px^2 of blur.
    x.moment_major_var_px2 = 30.0 * (1000.0 / d_mm) * (1000.0 / d_mm) + 1.0;
    return x;
  }

  // The Table 3 grid: t_r = 8 ms; t_n = 30..36 ms; 475, 500 mA; 1500..3000 mm; 0..35 deg.
  std::vector<CalibrationSample> Table3() const {
    std::vector<CalibrationSample> out;
    for (double bias : {475.0, 500.0}) {
      for (double d : {1500.0, 2000.0, 2500.0, 3000.0}) {
        for (double theta = 0.0; theta <= 35.0; theta += 5.0) {
          const Features ref = Frame(8.0, bias, d, theta, theta);
          for (double t : {30.0, 32.0, 34.0, 36.0}) {
            CalibrationSample s;
            s.reference = ref;
            s.measurement = Frame(t, bias, d, theta, theta);
            s.t_ref_ms = 8.0;
            s.t_ms = t;
            s.bias_ma = bias;
            s.d_mm = d;
            s.theta_deg = theta;
            out.push_back(s);
          }
        }
      }
    }
    return out;
  }

  // A calibration model holding the exact generating coefficients (full forms).
  CalibrationModel ExactModel() const {
    CalibrationModel m;
    m.scaling = scaling;
    m.ranges.d_min_mm = 1500.0;
    m.ranges.d_max_mm = 3000.0;
    m.ranges.theta_min_deg = 0.0;
    m.ranges.theta_max_deg = 35.0;
    m.ranges.t_min_ms = 30.0;
    m.ranges.t_max_ms = 36.0;
    m.ranges.t_ref_min_ms = m.ranges.t_ref_max_ms = 8.0;
    m.ranges.bias_min_ma = 475.0;
    m.ranges.bias_max_ma = 500.0;
    for (ModelKind k : {ModelKind::kFreeE, ModelKind::kFreeSigma}) {
      FittedModel fm;
      fm.kind = k;
      fm.form = ModelForm::kFull;
      fm.coefficients = Coefficients(k);
      fm.sigma_deg = sigma_deg;
      fm.summary.termination = FitSummary::Termination::kConverged;  // exact: a failed fit is unused
      m.models.push_back(fm);
    }
    return m;
  }
};

}  // namespace irdist::testing
