#include "estimator/models.h"

#include "base/check.h"

namespace irdist {
namespace {

// Monomial{{D, rho, t, I0, dt, dF}, name}
constexpr Monomial M(int d, int rho, int t, int i0, int dt, int df, const char* name) {
  return Monomial{{static_cast<int8_t>(d), static_cast<int8_t>(rho), static_cast<int8_t>(t),
                   static_cast<int8_t>(i0), static_cast<int8_t>(dt), static_cast<int8_t>(df)},
                  name};
}

// Eq. 8 (kappa for E_rel; the same layout with beta for F(0,0)).
#define IRDIST_DIRECT_TABLE(p)                                                                 \
  {                                                                                            \
    M(1, 1, 1, 1, 0, 0, p "1"), M(1, 1, 0, 1, 0, 0, p "2"), M(1, 1, 1, 0, 0, 0, p "3"),        \
        M(1, 1, 0, 0, 0, 0, p "4"), M(0, 1, 1, 1, 0, 0, p "5"), M(0, 1, 0, 1, 0, 0, p "6"),    \
        M(0, 1, 1, 0, 0, 0, p "7"), M(0, 1, 0, 0, 0, 0, p "8"), M(1, 0, 1, 1, 0, 0, p "9"),    \
        M(1, 0, 0, 1, 0, 0, p "10"), M(1, 0, 1, 0, 0, 0, p "11"), M(1, 0, 0, 0, 0, 0, p "12"), \
        M(0, 0, 1, 1, 0, 0, p "13"), M(0, 0, 0, 1, 0, 0, p "14"), M(0, 0, 1, 0, 0, 0, p "15"), \
        M(0, 0, 0, 0, 0, 0, p "16")                                                            \
  }
const Monomial kDirectE[] = IRDIST_DIRECT_TABLE("kappa");
const Monomial kDirectF[] = IRDIST_DIRECT_TABLE("beta");
#undef IRDIST_DIRECT_TABLE

// Table 2, Sigma: {t, 1} x {I0, 1} x {D^2, D, 1} x {rho, 1}, numbered as Eq. 12.
const Monomial kDirectSigma[] = {
    M(2, 1, 1, 1, 0, 0, "lambda1"),  M(1, 1, 1, 1, 0, 0, "lambda2"),
    M(0, 1, 1, 1, 0, 0, "lambda3"),  M(2, 1, 1, 0, 0, 0, "lambda4"),
    M(1, 1, 1, 0, 0, 0, "lambda5"),  M(0, 1, 1, 0, 0, 0, "lambda6"),
    M(2, 1, 0, 1, 0, 0, "lambda7"),  M(1, 1, 0, 1, 0, 0, "lambda8"),
    M(0, 1, 0, 1, 0, 0, "lambda9"),  M(2, 1, 0, 0, 0, 0, "lambda10"),
    M(1, 1, 0, 0, 0, 0, "lambda11"), M(0, 1, 0, 0, 0, 0, "lambda12"),
    M(2, 0, 1, 1, 0, 0, "lambda13"), M(1, 0, 1, 1, 0, 0, "lambda14"),
    M(0, 0, 1, 1, 0, 0, "lambda15"), M(2, 0, 1, 0, 0, 0, "lambda16"),
    M(1, 0, 1, 0, 0, 0, "lambda17"), M(0, 0, 1, 0, 0, 0, "lambda18"),
    M(2, 0, 0, 1, 0, 0, "lambda19"), M(1, 0, 0, 1, 0, 0, "lambda20"),
    M(0, 0, 0, 1, 0, 0, "lambda21"), M(2, 0, 0, 0, 0, 0, "lambda22"),
    M(1, 0, 0, 0, 0, 0, "lambda23"), M(0, 0, 0, 0, 0, 0, "lambda24"),
};

// Eq. 10 / 11: dt * (I0 * (c1 rho D + c5 rho + c9 D + c13) + (c3 rho D + c7 rho + c11 D + c15)).
#define IRDIST_DIFF_TABLE(p)                                                                 \
  {                                                                                          \
    M(1, 1, 0, 1, 1, 0, p "1"), M(1, 1, 0, 0, 1, 0, p "3"), M(0, 1, 0, 1, 1, 0, p "5"),      \
        M(0, 1, 0, 0, 1, 0, p "7"), M(1, 0, 0, 1, 1, 0, p "9"), M(1, 0, 0, 0, 1, 0, p "11"), \
        M(0, 0, 0, 1, 1, 0, p "13"), M(0, 0, 0, 0, 1, 0, p "15")                             \
  }
const Monomial kDiffE[] = IRDIST_DIFF_TABLE("kappa");
const Monomial kDiffF[] = IRDIST_DIFF_TABLE("beta");
#undef IRDIST_DIFF_TABLE

// Eq. 12.
const Monomial kDiffSigma[] = {
    M(2, 1, 0, 1, 1, 0, "lambda1"),  M(1, 1, 0, 1, 1, 0, "lambda2"),
    M(0, 1, 0, 1, 1, 0, "lambda3"),  M(2, 1, 0, 0, 1, 0, "lambda4"),
    M(1, 1, 0, 0, 1, 0, "lambda5"),  M(0, 1, 0, 0, 1, 0, "lambda6"),
    M(2, 0, 0, 1, 1, 0, "lambda13"), M(1, 0, 0, 1, 1, 0, "lambda14"),
    M(0, 0, 0, 1, 1, 0, "lambda15"), M(2, 0, 0, 0, 1, 0, "lambda16"),
    M(1, 0, 0, 0, 1, 0, "lambda17"), M(0, 0, 0, 0, 1, 0, "lambda18"),
};

// Eq. 17: numerator q1..q13, denominator q14..q17.
const Monomial kFreeE[] = {
    M(1, 1, 0, 0, 1, 1, "q1"),  M(2, 2, 0, 0, 2, 0, "q2"),  M(1, 2, 0, 0, 2, 0, "q3"),
    M(2, 1, 0, 0, 2, 0, "q4"),  M(1, 1, 0, 0, 2, 0, "q5"),  M(0, 1, 0, 0, 1, 1, "q6"),
    M(0, 2, 0, 0, 2, 0, "q7"),  M(0, 1, 0, 0, 2, 0, "q8"),  M(1, 0, 0, 0, 1, 1, "q9"),
    M(2, 0, 0, 0, 2, 0, "q10"), M(1, 0, 0, 0, 2, 0, "q11"), M(0, 0, 0, 0, 1, 1, "q12"),
    M(0, 0, 0, 0, 2, 0, "q13"), M(1, 1, 0, 0, 1, 0, "q14"), M(0, 1, 0, 0, 1, 0, "q15"),
    M(1, 0, 0, 0, 1, 0, "q16"), M(0, 0, 0, 0, 1, 0, "q17"),
};

// Eq. 18 with p5 = D^2 rho dt^2 (NOTES.md): numerator p1..p18, denominator p19..p22.
const Monomial kFreeSigma[] = {
    M(2, 1, 0, 0, 1, 1, "p1"),  M(3, 2, 0, 0, 2, 0, "p2"),  M(2, 2, 0, 0, 2, 0, "p3"),
    M(3, 1, 0, 0, 2, 0, "p4"),  M(2, 1, 0, 0, 2, 0, "p5"),  M(1, 1, 0, 0, 1, 1, "p6"),
    M(1, 2, 0, 0, 2, 0, "p7"),  M(1, 1, 0, 0, 2, 0, "p8"),  M(0, 1, 0, 0, 1, 1, "p9"),
    M(0, 2, 0, 0, 2, 0, "p10"), M(0, 1, 0, 0, 2, 0, "p11"), M(2, 0, 0, 0, 1, 1, "p12"),
    M(3, 0, 0, 0, 2, 0, "p13"), M(2, 0, 0, 0, 2, 0, "p14"), M(1, 0, 0, 0, 1, 1, "p15"),
    M(1, 0, 0, 0, 2, 0, "p16"), M(0, 0, 0, 0, 1, 1, "p17"), M(0, 0, 0, 0, 2, 0, "p18"),
    M(1, 1, 0, 0, 1, 0, "p19"), M(0, 1, 0, 0, 1, 0, "p20"), M(1, 0, 0, 0, 1, 0, "p21"),
    M(0, 0, 0, 0, 1, 0, "p22"),
};

template <size_t N>
constexpr int Count(const Monomial (&)[N]) {
  return static_cast<int>(N);
}

const ModelSpec kSpecs[kNumModelKinds] = {
    {ModelKind::kDirectE, kDirectE, Count(kDirectE), 0},
    {ModelKind::kDirectF, kDirectF, Count(kDirectF), 0},
    {ModelKind::kDirectSigma, kDirectSigma, Count(kDirectSigma), 0},
    {ModelKind::kDiffE, kDiffE, Count(kDiffE), 0},
    {ModelKind::kDiffF, kDiffF, Count(kDiffF), 0},
    {ModelKind::kDiffSigma, kDiffSigma, Count(kDiffSigma), 0},
    {ModelKind::kFreeE, kFreeE, 13, 4},
    {ModelKind::kFreeSigma, kFreeSigma, 18, 4},
};

const char* const kKindNames[kNumModelKinds] = {"direct_e", "direct_f",  "direct_sigma",
                                                "diff_e",   "diff_f",    "diff_sigma",
                                                "free_e",   "free_sigma"};

}  // namespace

const char* ToString(ModelKind kind) { return kKindNames[static_cast<int>(kind)]; }

const char* ToString(ModelForm form) { return form == ModelForm::kFull ? "full" : "reduced"; }

bool ParseModelKind(const std::string& name, ModelKind* kind) {
  for (int k = 0; k < kNumModelKinds; ++k) {
    if (name == kKindNames[k]) {
      *kind = static_cast<ModelKind>(k);
      return true;
    }
  }
  return false;
}

bool ParseModelForm(const std::string& name, ModelForm* form) {
  if (name == "full") {
    *form = ModelForm::kFull;
    return true;
  }
  if (name == "reduced") {
    *form = ModelForm::kReduced;
    return true;
  }
  return false;
}

const ModelSpec& GetModelSpec(ModelKind kind) {
  const int k = static_cast<int>(kind);
  IRDIST_CHECK(k >= 0 && k < kNumModelKinds, "unknown model kind ", k);
  return kSpecs[k];
}

bool IsTermActive(const ModelSpec& spec, ModelForm form, int index) {
  IRDIST_CHECK(index >= 0 && index < spec.num_coefficients(), "coefficient index ", index);
  if (form == ModelForm::kFull) return true;
  return spec.terms[index].exponent[kVarDt] < 2;
}

std::array<double, kNumModelVars> ScaleInputs(const ModelInputs& in, const ModelScaling& s) {
  std::array<double, kNumModelVars> v{};
  v[kVarD] = in.d_mm > 0.0 ? s.ScaledD(in.d_mm) : 0.0;
  v[kVarRho] = 1.0;
  v[kVarT] = in.t_ms / s.t_scale_ms;
  v[kVarI0] = in.bias_ma / s.i0_scale_ma;
  v[kVarDt] = in.dt_ms / s.t_scale_ms;
  v[kVarDF] = in.df / s.df_scale;
  return v;
}

void AlgebraicPolynomialInD(const ModelSpec& spec, const double* coefficients, const double* vars,
                            double y, double poly[4]) {
  double powers[kNumModelVars][4];
  PowerTable(vars, powers);
  for (int k = 0; k < 4; ++k) poly[k] = 0.0;
  for (int j = 0; j < spec.num_coefficients(); ++j) {
    const Monomial& m = spec.terms[j];
    double term = coefficients[j];
    for (int v = 0; v < kNumModelVars; ++v) {
      if (v != kVarD && m.exponent[v] != 0) term *= powers[v][m.exponent[v]];
    }
    poly[m.exponent[kVarD]] += j < spec.num_numerator ? -term : y * term;
  }
}

double PredictModel(ModelKind kind, const std::vector<double>& coefficients, double sigma_deg,
                    const ModelScaling& scaling, const ModelInputs& inputs) {
  const ModelSpec& spec = GetModelSpec(kind);
  IRDIST_CHECK(static_cast<int>(coefficients.size()) == spec.num_coefficients(), ToString(kind),
               " needs ", spec.num_coefficients(), " coefficients, got ", coefficients.size());
  std::array<double, kNumModelVars> v = ScaleInputs(inputs, scaling);
  v[kVarRho] = Rho(inputs.theta_deg, sigma_deg);
  return EvaluateModel(spec, coefficients.data(), v.data());
}

}  // namespace irdist
