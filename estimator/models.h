#pragma once
// The paper's models, each written once as a table of monomials (docs/estimator.md):
//  - direct (Table 2, Eq. 8): E_rel (kappa 1..16), F(0,0) (beta 1..16), Sigma (lambda 1..24);
//  - differential (Eq. 10-12): the t-terms of the direct models, times dt (8, 8, 12 coefficients);
//  - I0-free (Eq. 17, 18): dE = NumE/DenE (q 1..17), dS = NumS/DenS (p 1..22), with the NOTES.md
//    fixes (p5 is the D^2 rho dt^2 term).
// A monomial is a product of powers of the model variables below; coefficient j of a model
// multiplies monomial j (numerator terms first, then denominator terms). One templated routine
// evaluates any model in double or in ceres::Jet.
//
// Variables enter scaled (ModelScaling): D = (1000 mm / d)^2 / d_scale, t / t_scale_ms,
// I0 = bias_ma / i0_scale_ma, dt / t_scale_ms, dF / df_scale. rho = exp(-theta^2 / (2 sigma^2)),
// theta and sigma in degrees (the paper prints the exponent's sign wrong).

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace irdist {

enum class ModelKind {
  kDirectE,      // E_rel(t, I0, D, rho), Eq. 8
  kDirectF,      // F(0,0)
  kDirectSigma,  // Sigma (quadratic in D)
  kDiffE,        // dE(dt, I0, D, rho), Eq. 10
  kDiffF,        // dF, Eq. 11
  kDiffSigma,    // dS, Eq. 12
  kFreeE,        // dE(dt, dF, D, rho), Eq. 17
  kFreeSigma,    // dS(dt, dF, D, rho), Eq. 18
};
constexpr int kNumModelKinds = 8;

// kFull: the paper's form. kReduced: without the dt^2 terms (they model a background that does not
// scale with I0; NOTES.md: this held up where the full form failed). Only the I0-free models have
// dt^2 terms; for the others both forms are the same.
enum class ModelForm { kFull, kReduced };

const char* ToString(ModelKind kind);
const char* ToString(ModelForm form);
bool ParseModelKind(const std::string& name, ModelKind* kind);
bool ParseModelForm(const std::string& name, ModelForm* form);

enum ModelVar : int { kVarD = 0, kVarRho, kVarT, kVarI0, kVarDt, kVarDF, kNumModelVars };

struct Monomial {
  std::array<int8_t, kNumModelVars> exponent;  // powers of D, rho, t, I0, dt, dF
  const char* name;                            // coefficient name in the paper, e.g. "q5"
};

struct ModelSpec {
  ModelKind kind;
  const Monomial* terms;  // num_numerator numerator terms, then num_denominator terms
  int num_numerator;
  int num_denominator;  // 0: the model is the numerator alone
  int num_coefficients() const { return num_numerator + num_denominator; }
  bool has_denominator() const { return num_denominator > 0; }
};

const ModelSpec& GetModelSpec(ModelKind kind);

// Whether coefficient `index` takes part in the given form (kReduced drops the dt^2 terms).
bool IsTermActive(const ModelSpec& spec, ModelForm form, int index);

// Input scalings, chosen by the fit so that each variable is of order 1, stored in the model file.
struct ModelScaling {
  double d_ref_mm = 1000.0;  // D = (d_ref_mm / d)^2 before scaling (fixed by convention)
  double d_scale = 1.0;      // the models see D / d_scale
  double t_scale_ms = 1.0;   // t and dt in ms are divided by this
  double i0_scale_ma = 1.0;  // bias current in mA divided by this
  double df_scale = 1.0;     // dF divided by this
  double ScaledD(double d_mm) const {
    const double r = d_ref_mm / d_mm;
    return r * r / d_scale;
  }
  double DistanceFromScaledD(double scaled_d) const {
    return d_ref_mm / std::sqrt(scaled_d * d_scale);
  }
};

// Raw (unscaled) inputs of one observation; unused fields are ignored by a model.
struct ModelInputs {
  double d_mm = 0.0;
  double theta_deg = 0.0;
  double t_ms = 0.0;
  double bias_ma = 0.0;
  double dt_ms = 0.0;
  double df = 0.0;
};

// The scaled variable vector (rho left to the caller, it depends on sigma).
std::array<double, kNumModelVars> ScaleInputs(const ModelInputs& in, const ModelScaling& s);

template <typename T>
T Rho(const T& theta_deg, const T& sigma_deg) {
  using std::exp;
  return exp(-(theta_deg * theta_deg) / (2.0 * sigma_deg * sigma_deg));
}

template <typename T>
T MonomialValue(const Monomial& m, const T (&powers)[kNumModelVars][4]) {
  T value = T(1.0);
  for (int v = 0; v < kNumModelVars; ++v) {
    if (m.exponent[v] != 0) value = value * powers[v][m.exponent[v]];
  }
  return value;
}

// Sum over `count` terms starting at `first` of coefficient * monomial, from a table of powers.
template <typename T, typename C>
T SumTerms(const ModelSpec& spec, int first, int count, const C* coefficients,
           const T (&powers)[kNumModelVars][4]) {
  T sum = T(0.0);
  for (int j = first; j < first + count; ++j) {
    sum = sum + T(coefficients[j]) * MonomialValue(spec.terms[j], powers);
  }
  return sum;
}

template <typename T>
void PowerTable(const T* vars, T (&powers)[kNumModelVars][4]) {
  for (int v = 0; v < kNumModelVars; ++v) {
    powers[v][0] = T(1.0);
    powers[v][1] = vars[v];
    powers[v][2] = vars[v] * vars[v];
    powers[v][3] = powers[v][2] * vars[v];
  }
}

// Evaluates a model on scaled variables (vars[kVarRho] already holds rho). The one routine every
// model goes through, in double and in ceres::Jet (coefficients C = double or T).
template <typename T, typename C>
T EvaluateModel(const ModelSpec& spec, const C* coefficients, const T* vars) {
  T powers[kNumModelVars][4];
  PowerTable(vars, powers);
  const T num = SumTerms(spec, 0, spec.num_numerator, coefficients, powers);
  if (!spec.has_denominator()) return num;
  const T den = SumTerms(spec, spec.num_numerator, spec.num_denominator, coefficients, powers);
  return num / den;
}

// Numerator and denominator separately (the algebraic residual y*Den - Num is linear in them).
template <typename T, typename C>
void EvaluateNumDen(const ModelSpec& spec, const C* coefficients, const T* vars, T* num, T* den) {
  T powers[kNumModelVars][4];
  PowerTable(vars, powers);
  *num = SumTerms(spec, 0, spec.num_numerator, coefficients, powers);
  *den = spec.has_denominator()
             ? SumTerms(spec, spec.num_numerator, spec.num_denominator, coefficients, powers)
             : T(1.0);
}

// Convenience in double: the model's prediction for raw inputs.
// Coefficients of the polynomial in D of y * Den - Num at fixed rho, dt, dF (vars[kVarD] ignored):
// poly[k] multiplies D^k, k = 0..3. For the I0-free models this is Eq. 21 (a) and Eq. 23 (c), with
// every term the table holds (so p15 is in c3).
void AlgebraicPolynomialInD(const ModelSpec& spec, const double* coefficients, const double* vars,
                            double y, double poly[4]);

double PredictModel(ModelKind kind, const std::vector<double>& coefficients, double sigma_deg,
                    const ModelScaling& scaling, const ModelInputs& inputs);

}  // namespace irdist
