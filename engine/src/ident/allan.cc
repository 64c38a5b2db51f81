#include "insdiag/engine/ident/allan.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <numeric>
#include <string>

#include "insdiag/engine/model/parameters.h"
#include "insdiag/engine/monitor/sample_screening.h"
#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine::ident {
namespace {

constexpr int kQ = static_cast<int>(AllanParameter::kQuantization);
constexpr int kN = static_cast<int>(AllanParameter::kWhiteDensity);
constexpr int kB = static_cast<int>(AllanParameter::kBiasInstability);
constexpr int kK = static_cast<int>(AllanParameter::kRateRandomWalk);
constexpr int kR = static_cast<int>(AllanParameter::kRateRamp);
constexpr int kMs = static_cast<int>(AllanParameter::kMarkovSigma);
constexpr int kMt = static_cast<int>(AllanParameter::kMarkovTau);
constexpr int kP = kAllanParameterCount;

// (2 ln 2/π): σ²(τ) of flicker rate noise of coefficient B (IEEE 952 Annex C).
constexpr double kFlickerAvar = 2.0 * std::numbers::ln2 / std::numbers::pi;

using TermMask = std::array<bool, kP>;
using LogParameters = std::array<double, kP>;

// ---------------------------------------------------------------------------
// Special functions.

// ψ(x): recurrence up to x ≥ 6, then the asymptotic series (A&S 6.3.18).
double Digamma(double x) {
  double r = 0.0;
  while (x < 6.0) {
    r -= 1.0 / x;
    x += 1.0;
  }
  const double f = 1.0 / (x * x);
  return r + std::log(x) - 0.5 / x -
         f * (1.0 / 12 - f * (1.0 / 120 - f * (1.0 / 252 - f * (1.0 / 240 - f / 132))));
}

// ψ′(x): recurrence up to x ≥ 6, then the asymptotic series (A&S 6.4.12).
double Trigamma(double x) {
  double r = 0.0;
  while (x < 6.0) {
    r += 1.0 / (x * x);
    x += 1.0;
  }
  const double f = 1.0 / (x * x);
  return r + 1.0 / x + 0.5 * f + f / x * (1.0 / 6 - f * (1.0 / 30 - f * (1.0 / 42 - f / 30)));
}

// χ²_ν quantile. The engine's bisection is exact but needs O(√ν) terms per
// evaluation; above ν = 200 the Wilson–Hilferty cube (relative error < 1e-4
// there) is as good for a confidence interval and costs nothing.
double ChiSquareQuantileFast(double p, double dof) {
  if (dof <= 200.0) return stats::ChiSquareQuantile(p, dof);
  const double z = stats::NormalQuantile(p);
  const double c = 2.0 / (9.0 * dof);
  const double w = 1.0 - c + z * std::sqrt(c);
  return dof * w * w * w;
}

// g(u) = (2u − 3 + 4e^{−u} − e^{−2u})/u², the Markov term's AVAR shape
// (u = τ/T). Below u = 0.1 the closed form cancels to O(u³); there we use its
// Taylor series g(u) = Σ_{k≥3} (−1)^k (4 − 2^k)/k! · u^{k−2} (to k = 11).
constexpr std::array<double, 9> MarkovSeriesCoefficients() {
  std::array<double, 9> c{};
  double factorial = 2.0;
  for (int k = 3; k < 12; ++k) {
    factorial *= k;
    double two_k = 1.0;
    for (int i = 0; i < k; ++i) two_k *= 2.0;
    c[static_cast<size_t>(k - 3)] = (k % 2 == 1 ? -1.0 : 1.0) * (4.0 - two_k) / factorial;
  }
  return c;
}
constexpr std::array<double, 9> kMarkovSeries = MarkovSeriesCoefficients();

template <typename T>
T MarkovShape(const T& u) {
  using std::exp;
  if (u < T(0.1)) {
    T sum(kMarkovSeries.back());
    for (int i = static_cast<int>(kMarkovSeries.size()) - 2; i >= 0; --i) {
      sum = sum * u + T(kMarkovSeries[static_cast<size_t>(i)]);
    }
    return sum * u;
  }
  return (T(2.0) * u - T(3.0) + T(4.0) * exp(-u) - exp(T(-2.0) * u)) / (u * u);
}

// Peak of g: u* and g(u*) (golden-section search; g is unimodal on (0, ∞)).
struct MarkovPeak {
  double u = 0.0;
  double g = 0.0;
};
const MarkovPeak& MarkovShapePeak() {
  static const MarkovPeak peak = [] {
    double lo = 0.5;
    double hi = 6.0;
    const double r = 0.5 * (std::sqrt(5.0) - 1.0);
    for (int i = 0; i < 200; ++i) {
      const double a = hi - r * (hi - lo);
      const double b = lo + r * (hi - lo);
      if (MarkovShape(a) > MarkovShape(b)) {
        hi = b;
      } else {
        lo = a;
      }
    }
    const double u = 0.5 * (lo + hi);
    return MarkovPeak{u, MarkovShape(u)};
  }();
  return peak;
}

// ---------------------------------------------------------------------------
// The model in log coefficients a: a_Q = ln 3Q², a_N = ln N², a_B = ln (2ln2/π)B²,
// a_K = ln K²/3, a_R = ln R²/2, a_σ = ln σ_m², a_T = ln T.

template <typename T>
T ModelAvar(const T* a, const TermMask& on, double tau) {
  using std::exp;
  T sum(0.0);
  if (on[kQ]) sum += exp(a[kQ]) / (tau * tau);
  if (on[kN]) sum += exp(a[kN]) / tau;
  if (on[kB]) sum += exp(a[kB]);
  if (on[kK]) sum += exp(a[kK]) * tau;
  if (on[kR]) sum += exp(a[kR]) * (tau * tau);
  if (on[kMs]) sum += exp(a[kMs]) * MarkovShape(T(tau) * exp(-a[kMt]));
  return sum;
}

// Basis of the linear terms: σ² = Σ_k c_k φ_k(τ), c = e^a.
double Basis(int k, double tau, double markov_tau_s) {
  switch (k) {
    case kQ: return 1.0 / (tau * tau);
    case kN: return 1.0 / tau;
    case kB: return 1.0;
    case kK: return tau;
    case kR: return tau * tau;
    case kMs: return MarkovShape(tau / markov_tau_s);
    default: return 0.0;
  }
}

AllanNoiseTerms TermsFromLog(const LogParameters& a, const TermMask& on) {
  AllanNoiseTerms t;
  if (on[kQ]) t.quantization = std::sqrt(std::exp(a[kQ]) / 3.0);
  if (on[kN]) t.white_density = std::sqrt(std::exp(a[kN]));
  if (on[kB]) t.bias_instability = std::sqrt(std::exp(a[kB]) / kFlickerAvar);
  if (on[kK]) t.rate_random_walk = std::sqrt(3.0 * std::exp(a[kK]));
  if (on[kR]) t.rate_ramp = std::sqrt(2.0 * std::exp(a[kR]));
  if (on[kMs]) {
    t.markov_sigma = std::sqrt(std::exp(a[kMs]));
    t.markov_tau_s = std::exp(a[kMt]);
  }
  return t;
}

// One point of the curve (house style: measurement and √information as members):
//   r = (y − ln σ²(τ; a)) · √I,
//   y = ln σ̂² − [ψ(ν/2) − ln(ν/2)]   (ln σ̂² corrected for the mean of ln χ²_ν/ν)
//   √I = 1/√ψ′(ν/2)                   (the standard deviation of ln χ²_ν)
class AllanLogResidual {
 public:
  AllanLogResidual(double tau_s, double measurement, double sqrt_information, const TermMask& on)
      : tau_s_(tau_s), measurement_(measurement), sqrt_information_(sqrt_information), on_(on) {}

  template <typename T>
  bool operator()(const T* const a, T* residual) const {
    using std::log;
    residual[0] = (T(measurement_) - log(ModelAvar(a, on_, tau_s_))) * sqrt_information_;
    return true;
  }

  static ceres::CostFunction* Create(double tau_s, double measurement, double sqrt_information,
                                     const TermMask& on) {
    return new ceres::AutoDiffCostFunction<AllanLogResidual, 1, kP>(
        new AllanLogResidual(tau_s, measurement, sqrt_information, on));
  }

 private:
  double tau_s_;
  double measurement_;
  double sqrt_information_;
  TermMask on_;
};

// The curve as the fit sees it.
struct FitData {
  std::vector<size_t> point;  // index into the curve
  std::vector<int64_t> m;
  std::vector<double> tau, avar, y, s;
  double discrepancy2 = 0.0;  // δ², added to every s² (model discrepancy)
  std::vector<double> sd;     // √(s² + δ²): the weights' standard deviations

  void SetDiscrepancy(double d2) {
    discrepancy2 = d2;
    sd.resize(s.size());
    for (size_t j = 0; j < s.size(); ++j) sd[j] = std::sqrt(s[j] * s[j] + d2);
  }
};

int TermCount(const TermMask& on) {
  int n = 0;
  for (int k = 0; k < kMs; ++k) n += on[static_cast<size_t>(k)] ? 1 : 0;
  return n + (on[kMs] ? 1 : 0);
}
int ParameterCount(const TermMask& on) { return static_cast<int>(std::count(on.begin(), on.end(), true)); }

// ---------------------------------------------------------------------------
// Covariance of the estimator under the model.

// Generalised autocovariance of the phase θ without the quantisation δ
// (see the header): G(h) = −N²|h|/2 + (B²/2π) h² ln|h| + K²|h|³/12 − σ_m²T²(|h|/T − 1 + e^{−|h|/T}).
struct PhaseCovariance {
  double q2 = 0.0;
  double half_n2 = 0.0;
  double flicker = 0.0;
  double walk = 0.0;
  double markov = 0.0;  // σ_m² T²
  double markov_tau_s = 0.0;

  explicit PhaseCovariance(const AllanNoiseTerms& t) {
    q2 = t.quantization * t.quantization;
    half_n2 = 0.5 * t.white_density * t.white_density;
    flicker = t.bias_instability * t.bias_instability / (2.0 * std::numbers::pi);
    walk = t.rate_random_walk * t.rate_random_walk / 12.0;
    if (t.markov_sigma > 0.0 && t.markov_tau_s > 0.0) {
      markov = t.markov_sigma * t.markov_sigma * t.markov_tau_s * t.markov_tau_s;
      markov_tau_s = t.markov_tau_s;
    }
  }

  // G without its Markov exponential and constant (second differences
  // annihilate constants): −(N²/2 + σ_m²T)|h| + K²|h|³/12 + (B²/2π) h² ln|h|;
  // G = Polynomial(h) − σ_m²T² e^{−|h|/T} + const.
  double Polynomial(double h) const {
    h = std::abs(h);
    double g = -(half_n2 + (markov > 0.0 ? markov / markov_tau_s : 0.0)) * h + walk * h * h * h;
    if (flicker > 0.0 && h > 0.0) g += flicker * h * h * std::log(h);
    return g;
  }

  // G without the quantisation δ, each term in its cancellation-free form.
  double Smooth(double h) const {
    h = std::abs(h);
    double g = -half_n2 * h + walk * h * h * h;
    if (flicker > 0.0 && h > 0.0) g += flicker * h * h * std::log(h);
    if (markov > 0.0) {
      const double u = h / markov_tau_s;
      g -= markov * (u > 40.0 ? u - 1.0 : u + std::expm1(-u));  // e^{−40} is below double precision of u − 1
    }
    return g;
  }
};

constexpr double kTap[3] = {1.0, -2.0, 1.0};

// Σ_d n(d) c(d)² for one pair of cluster sizes and one segment with M_i, M_j
// differences, c(d) = Cov(D_i(a), D_j(a + d)). c is smooth between the lags
// where a tap of D_i meets one of D_j (d = p m_i − q m_j) and n(d) is linear
// between 0 and M_j − M_i, so the sum is taken piece by piece: exactly on
// short pieces, by 4-point Gauss–Legendre (exact up to degree 7: N and K
// pieces are polynomials of degree ≤ 7) with the Euler–Maclaurin endpoint
// terms on long ones. The quantisation δ adds only at the meeting lags.
double LagSum(const PhaseCovariance& g, double tau0, int64_t mi, int64_t mj, int64_t Mi, int64_t Mj) {
  const int64_t lo = std::max(-2 * mj, -(Mi - 1));
  const int64_t hi = std::min(2 * mi, Mj - 1);
  if (lo > hi) return 0.0;
  auto n_of = [&](double d) {
    return std::max(0.0, std::min(static_cast<double>(Mi), static_cast<double>(Mj) - d) - std::max(0.0, -d));
  };
  auto c_of = [&](double d) {
    double c = 0.0;
    for (int p = 0; p < 3; ++p) {
      for (int q = 0; q < 3; ++q) {
        c += kTap[p] * kTap[q] * g.Smooth(tau0 * (d + static_cast<double>(q * mj - p * mi)));
      }
    }
    return c;
  };
  auto term = [&](double d) {
    const double c = c_of(d);
    return n_of(d) * c * c;
  };

  std::vector<int64_t> breaks = {lo, hi};
  for (int p = 0; p < 3; ++p) {
    for (int q = 0; q < 3; ++q) breaks.push_back(p * mi - q * mj);
  }
  breaks.push_back(0);
  breaks.push_back(Mj - Mi);
  std::sort(breaks.begin(), breaks.end());
  breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());
  std::map<int64_t, double> break_value;
  auto at_break = [&](int64_t d) {
    auto [it, fresh] = break_value.try_emplace(d, 0.0);
    if (fresh) it->second = term(static_cast<double>(d));
    return it->second;
  };

  // Subintervals for Gauss–Legendre: fine enough for the Markov exponential.
  const double markov_scale = g.markov > 0.0 ? g.markov_tau_s / tau0 : 0.0;
  static const double kNode[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                  0.8611363115940526};
  static const double kWeight[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                    0.3478548451374538};
  constexpr int64_t kExactPiece = 48;
  std::vector<double> cuts;

  double sum = 0.0;
  for (size_t b = 0; b + 1 < breaks.size(); ++b) {
    const int64_t u = std::max(breaks[b], lo);
    const int64_t v = std::min(breaks[b + 1], hi);
    if (u >= v) continue;
    if (v - u <= kExactPiece) {
      for (int64_t d = u; d < v; ++d) sum += term(static_cast<double>(d));
      continue;
    }
    // Σ_{d=u}^{v−1} f(d) = ∫_u^v f + (f(u) − f(v))/2 + (f′(v) − f′(u))/12 + …
    // The Markov exponential and the flicker logarithm vary fast only next to
    // the piece's ends (their kinks): sub-intervals grow geometrically from
    // both ends, from T/2 (Markov) or len/32 (flicker), for six doublings.
    const double len = static_cast<double>(v - u);
    double first = len;
    // Where T is below 1/1000 of the piece, its exponential fills an O(T/len) sliver: not resolved.
    if (markov_scale > 1e-3 * len) first = std::min(first, 0.5 * markov_scale);
    if (g.flicker > 0.0) first = std::min(first, len / 32.0);
    cuts.assign(1, 0.0);
    for (double w = first; w < 0.5 * len && w < 64.0 * first; w *= 2.0) cuts.push_back(w);
    const size_t half = cuts.size();
    for (size_t k = half; k-- > 0;) cuts.push_back(len - cuts[k]);
    // Inside the piece every tap lag d + o (o = q m_j − p m_i) keeps its sign,
    // so the nine Markov exponentials e^{−|d+o|/T} factor into two:
    // ea·e^{−(d−u)/T} + eb·e^{−(v−d)/T} (all exponents ≤ 0).
    double ea = 0.0;
    double eb = 0.0;
    if (g.markov > 0.0) {
      const double mid = 0.5 * static_cast<double>(u + v);
      for (int p = 0; p < 3; ++p) {
        for (int q = 0; q < 3; ++q) {
          const auto o = static_cast<double>(q * mj - p * mi);
          const double w = kTap[p] * kTap[q];
          if (mid + o >= 0.0) {
            ea += w * std::exp(-(static_cast<double>(u) + o) / markov_scale);
          } else {
            eb += w * std::exp((static_cast<double>(v) + o) / markov_scale);
          }
        }
      }
    }
    auto inner = [&](double d) {
      double c = 0.0;
      for (int p = 0; p < 3; ++p) {
        for (int q = 0; q < 3; ++q) {
          c += kTap[p] * kTap[q] * g.Polynomial(tau0 * (d + static_cast<double>(q * mj - p * mi)));
        }
      }
      if (g.markov > 0.0) {
        c -= g.markov * (ea * std::exp(-(d - static_cast<double>(u)) / markov_scale) +
                         eb * std::exp(-(static_cast<double>(v) - d) / markov_scale));
      }
      return n_of(d) * c * c;
    };
    double integral = 0.0;
    for (size_t k = 0; k + 1 < cuts.size(); ++k) {
      const double width = cuts[k + 1] - cuts[k];
      if (!(width > 0.0)) continue;
      const double mid = static_cast<double>(u) + 0.5 * (cuts[k] + cuts[k + 1]);
      for (int q = 0; q < 4; ++q) integral += 0.5 * width * kWeight[q] * inner(mid + 0.5 * width * kNode[q]);
    }
    // The derivative term is O(1/len²) of the piece: left out.
    sum += integral + 0.5 * (at_break(u) - at_break(v));
  }
  sum += at_break(hi);

  if (g.q2 > 0.0) {
    // The δ of white phase noise at the lags where taps meet.
    std::map<int64_t, double> meet;
    for (int p = 0; p < 3; ++p) {
      for (int q = 0; q < 3; ++q) {
        const int64_t d = p * mi - q * mj;
        if (d >= lo && d <= hi) meet[d] += kTap[p] * kTap[q] * g.q2;
      }
    }
    for (const auto& [d, cq] : meet) {
      const double cs = c_of(static_cast<double>(d));
      sum += n_of(static_cast<double>(d)) * ((cs + cq) * (cs + cq) - cs * cs);
    }
  }
  return sum;
}

int64_t Differences(size_t samples, int64_t m) {
  return std::max<int64_t>(0, static_cast<int64_t>(samples) + 1 - 2 * m);
}

// Cov(σ̂²_i, σ̂²_j) for all pairs of `m`.
Eigen::MatrixXd EstimatorCovarianceMatrix(const AllanNoiseTerms& terms, double tau0, std::span<const int64_t> m,
                                          std::span<const size_t> segment_samples) {
  const PhaseCovariance g(terms);
  std::map<size_t, int> lengths;
  for (size_t n : segment_samples) ++lengths[n];
  const auto n = static_cast<Eigen::Index>(m.size());
  std::vector<double> total(m.size(), 0.0);
  for (size_t i = 0; i < m.size(); ++i) {
    for (const auto& [len, count] : lengths) total[i] += static_cast<double>(count * Differences(len, m[i]));
  }
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(n, n);
  for (size_t i = 0; i < m.size(); ++i) {
    for (size_t j = i; j < m.size(); ++j) {
      if (total[i] <= 0.0 || total[j] <= 0.0) continue;
      double s = 0.0;
      for (const auto& [len, count] : lengths) {
        const int64_t Mi = Differences(len, m[i]);
        const int64_t Mj = Differences(len, m[j]);
        if (Mi < 1 || Mj < 1) continue;
        s += count * LagSum(g, tau0, m[i], m[j], Mi, Mj);
      }
      const double ti = tau0 * static_cast<double>(m[i]);
      const double tj = tau0 * static_cast<double>(m[j]);
      const double c = 2.0 * s / (4.0 * ti * ti * tj * tj * total[i] * total[j]);
      cov(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = c;
      cov(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(i)) = c;
    }
  }
  return cov;
}

// V: the covariance of ln σ̂² under the model with log parameters a.
// Terms below 1e-6 of σ² at every τ are left out: they change V by less than
// that and would cost logarithms and exponentials for nothing.
Eigen::MatrixXd LogAvarCovariance(const FitData& data, const LogParameters& a, const TermMask& on, double tau0,
                                  std::span<const size_t> segment_samples) {
  TermMask used = on;
  for (int k = 0; k < kMt; ++k) {
    if (!on[static_cast<size_t>(k)]) continue;
    TermMask alone{};
    alone[static_cast<size_t>(k)] = true;
    if (k == kMs) alone[kMt] = true;
    double share = 0.0;
    for (double tau : data.tau) share = std::max(share, ModelAvar(a.data(), alone, tau) / ModelAvar(a.data(), on, tau));
    if (share < 1e-6) {
      used[static_cast<size_t>(k)] = false;
      if (k == kMs) used[kMt] = false;
    }
  }
  Eigen::MatrixXd v = EstimatorCovarianceMatrix(TermsFromLog(a, used), tau0, data.m, segment_samples);
  Eigen::VectorXd f(static_cast<Eigen::Index>(data.tau.size()));
  for (size_t j = 0; j < data.tau.size(); ++j) f[static_cast<Eigen::Index>(j)] = ModelAvar(a.data(), on, data.tau[j]);
  return f.cwiseInverse().asDiagonal() * v * f.cwiseInverse().asDiagonal();
}

// ---------------------------------------------------------------------------
// Fitting.

struct Bounds {
  LogParameters lower{};
  LogParameters upper{};
  std::array<double, kP> envelope{};  // largest coefficient each term may take alone
};

// Non-negative least squares of the relative AVAR residuals,
//   min Σ_j (1/s_j²) ((σ̂²_j − Σ_k c_k φ_k(τ_j))/σ̂²_j)²,  c ≥ 0,
// by trying every active set (at most 2⁵): the optimum satisfies the KKT
// conditions of one of them. Returns the cost; `c` gets the coefficients.
double NonNegativeFit(const FitData& data, const std::vector<int>& terms, double markov_tau_s,
                      std::array<double, kP>& c) {
  const auto n = static_cast<Eigen::Index>(data.tau.size());
  const auto p = static_cast<int>(terms.size());
  Eigen::MatrixXd A(n, p);
  Eigen::VectorXd b(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const auto jj = static_cast<size_t>(j);
    const double w = 1.0 / data.sd[jj];
    b[j] = w;
    for (int k = 0; k < p; ++k) A(j, k) = w * Basis(terms[static_cast<size_t>(k)], data.tau[jj], markov_tau_s) / data.avar[jj];
  }
  double best = b.squaredNorm();
  c.fill(0.0);
  for (int set = 1; set < (1 << p); ++set) {
    std::vector<int> cols;
    for (int k = 0; k < p; ++k) {
      if (set & (1 << k)) cols.push_back(k);
    }
    Eigen::MatrixXd As(n, static_cast<Eigen::Index>(cols.size()));
    Eigen::VectorXd scale(static_cast<Eigen::Index>(cols.size()));
    for (size_t k = 0; k < cols.size(); ++k) {
      const auto kk = static_cast<Eigen::Index>(k);
      As.col(kk) = A.col(cols[k]);
      scale[kk] = As.col(kk).norm();
      if (!(scale[kk] > 0.0)) scale[kk] = 1.0;
      As.col(kk) /= scale[kk];
    }
    const Eigen::VectorXd x = As.colPivHouseholderQr().solve(b);
    if (!x.allFinite() || (x.array() <= 0.0).any()) continue;
    const double cost = (As * x - b).squaredNorm();
    if (cost < best) {
      best = cost;
      c.fill(0.0);
      for (size_t k = 0; k < cols.size(); ++k) {
        c[static_cast<size_t>(terms[static_cast<size_t>(cols[k])])] = x[static_cast<Eigen::Index>(k)] / scale[static_cast<Eigen::Index>(k)];
      }
    }
  }
  return best;
}

// Largest coefficient of term k the curve allows on its own.
double Envelope(const FitData& data, int k, double markov_tau_s) {
  double env = std::numeric_limits<double>::infinity();
  for (size_t j = 0; j < data.tau.size(); ++j) {
    const double phi = Basis(k, data.tau[j], markov_tau_s);
    if (phi > 0.0) env = std::min(env, data.avar[j] / phi);
  }
  return env;
}

// The Markov term is told from N (τ ≫ T) and K (τ ≪ T) only by its peak at
// τ ≈ u*·T, so T is confined to put the peak between 3τ_min and τ_max; a
// solution on these bounds is not resolved.
double MarkovTauMin(const FitData& data) { return 3.0 * data.tau.front() / MarkovShapePeak().u; }
double MarkovTauMax(const FitData& data) { return data.tau.back() / MarkovShapePeak().u; }

struct Start {
  LogParameters a{};
  Bounds bounds;
};

// Starting values and bounds for the candidate set `on` (NNLS, with a
// half-decade grid over T for the Markov term).
Start StartingValues(const FitData& data, const TermMask& on) {
  const double tau_min = data.tau.front();
  const double tau_max = data.tau.back();
  std::vector<int> linear;
  for (int k = 0; k < kMs; ++k) {
    if (on[static_cast<size_t>(k)]) linear.push_back(k);
  }
  std::array<double, kP> c{};
  double markov_tau = std::sqrt(tau_min * tau_max);
  if (on[kMs]) {
    std::vector<int> with_markov = linear;
    with_markov.push_back(kMs);
    double best = std::numeric_limits<double>::infinity();
    for (double t = MarkovTauMin(data); t <= MarkovTauMax(data); t *= std::sqrt(10.0)) {
      std::array<double, kP> ct{};
      const double cost = NonNegativeFit(data, with_markov, t, ct);
      if (cost < best) {
        best = cost;
        c = ct;
        markov_tau = t;
      }
    }
  } else {
    NonNegativeFit(data, linear, markov_tau, c);
  }

  const double avar_max = *std::max_element(data.avar.begin(), data.avar.end());
  const double avar_min = *std::min_element(data.avar.begin(), data.avar.end());
  Start s;
  for (int k = 0; k < kP; ++k) {
    const auto kk = static_cast<size_t>(k);
    double env = 0.0;
    if (k == kMt) {
      s.bounds.lower[kk] = std::log(MarkovTauMin(data));
      s.bounds.upper[kk] = std::log(MarkovTauMax(data));
      s.a[kk] = std::clamp(std::log(markov_tau), s.bounds.lower[kk] + 0.1, s.bounds.upper[kk] - 0.1);
      continue;
    }
    if (k == kMs) {
      s.bounds.lower[kk] = std::log(avar_min) - 40.0;
      s.bounds.upper[kk] = std::log(avar_max) + std::log(100.0 * tau_max / tau_min) + 5.0;
      env = Envelope(data, kMs, markov_tau);
    } else {
      env = Envelope(data, k, markov_tau);
      s.bounds.envelope[kk] = env;
      s.bounds.lower[kk] = std::log(env) - 40.0;
      s.bounds.upper[kk] = std::log(env) + 5.0;
    }
    const double start = c[kk] > 0.0 ? c[kk] : 1e-3 * env;
    s.a[kk] = std::clamp(std::log(start), s.bounds.lower[kk] + 1.0, s.bounds.upper[kk] - 1.0);
  }
  return s;
}

// Weighted least squares in Ceres; returns Σ r².
double Solve(const FitData& data, const TermMask& on, const Bounds& bounds, int max_iterations, LogParameters& a) {
  ceres::Problem problem;
  for (size_t j = 0; j < data.tau.size(); ++j) {
    problem.AddResidualBlock(AllanLogResidual::Create(data.tau[j], data.y[j], 1.0 / data.sd[j], on), nullptr,
                             a.data());
  }
  // Terms outside `on` have zero Jacobian columns and stay where they are.
  for (int k = 0; k < kP; ++k) {
    const auto kk = static_cast<size_t>(k);
    a[kk] = std::clamp(a[kk], bounds.lower[kk], bounds.upper[kk]);
    problem.SetParameterLowerBound(a.data(), k, bounds.lower[kk]);
    problem.SetParameterUpperBound(a.data(), k, bounds.upper[kk]);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = max_iterations;
  options.function_tolerance = 1e-12;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-12;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  const LogParameters start = a;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (summary.IsSolutionUsable()) return 2.0 * summary.final_cost;
  // A failed solve (a numerical failure, not a slow one) may leave anything
  // in `a`: the fit stays at its start, with the cost of the start, so that
  // model selection compares a cost with the parameters it belongs to.
  a = start;
  double cost = std::numeric_limits<double>::infinity();
  problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
  return 2.0 * cost;
}

// Largest element (Eigen's maxCoeff trips GCC's -Wnull-dereference on dynamic vectors).
double LargestOf(const Eigen::VectorXd& v) {
  double m = -std::numeric_limits<double>::infinity();
  for (Eigen::Index k = 0; k < v.size(); ++k) m = std::max(m, v[k]);
  return m;
}

// ∂ ln σ²(τ_j)/∂a_k for the parameters in `on` (columns in parameter order).
Eigen::MatrixXd LogJacobian(const FitData& data, const LogParameters& a, const TermMask& on) {
  using Jet = ceres::Jet<double, kP>;
  std::array<Jet, kP> aj;
  for (int k = 0; k < kP; ++k) aj[static_cast<size_t>(k)] = Jet(a[static_cast<size_t>(k)], k);
  const int p = ParameterCount(on);
  Eigen::MatrixXd J(static_cast<Eigen::Index>(data.tau.size()), p);
  for (size_t j = 0; j < data.tau.size(); ++j) {
    const Jet f = ceres::log(ModelAvar(aj.data(), on, data.tau[j]));
    int col = 0;
    for (int k = 0; k < kP; ++k) {
      if (on[static_cast<size_t>(k)]) J(static_cast<Eigen::Index>(j), col++) = f.v[k];
    }
  }
  return J;
}

// Sandwich covariance of the log parameters in `on` (parameter order);
// directions the curve does not determine get infinite variance.
Eigen::MatrixXd SandwichCovariance(const FitData& data, const LogParameters& a, const TermMask& on,
                                   const Eigen::MatrixXd& V) {
  const Eigen::MatrixXd J = LogJacobian(data, a, on);
  Eigen::VectorXd w(J.rows());
  for (Eigen::Index j = 0; j < J.rows(); ++j) w[j] = 1.0 / (data.sd[static_cast<size_t>(j)] * data.sd[static_cast<size_t>(j)]);
  const Eigen::MatrixXd WJ = w.asDiagonal() * J;
  const Eigen::MatrixXd H = J.transpose() * WJ;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(H);
  const Eigen::VectorXd lambda = eig.eigenvalues();
  const double lmax = LargestOf(lambda);
  Eigen::VectorXd inv = Eigen::VectorXd::Zero(lambda.size());
  std::vector<bool> undetermined(static_cast<size_t>(H.rows()), false);
  for (Eigen::Index k = 0; k < lambda.size(); ++k) {
    if (lambda[k] > 1e-12 * lmax) {
      inv[k] = 1.0 / lambda[k];
    } else {
      for (Eigen::Index r = 0; r < H.rows(); ++r) {
        if (std::abs(eig.eigenvectors()(r, k)) > 1e-6) undetermined[static_cast<size_t>(r)] = true;
      }
    }
  }
  const Eigen::MatrixXd Hinv = eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
  Eigen::MatrixXd cov = Hinv * (WJ.transpose() * V * WJ) * Hinv;
  for (size_t r = 0; r < undetermined.size(); ++r) {
    if (undetermined[r]) cov(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(r)) = std::numeric_limits<double>::infinity();
  }
  return cov;
}

// Wald z of each parameter in `on` (indexed by parameter; 0 outside `on`).
std::array<double, kP> WaldZ(const Eigen::MatrixXd& cov, const TermMask& on) {
  std::array<double, kP> z{};
  int col = 0;
  for (int k = 0; k < kP; ++k) {
    if (!on[static_cast<size_t>(k)]) continue;
    const double var = cov(col, col);
    z[static_cast<size_t>(k)] = var > 0.0 && std::isfinite(var) ? 1.0 / std::sqrt(var) : 0.0;
    ++col;
  }
  return z;
}

Eigen::MatrixXd WithDiscrepancy(const Eigen::MatrixXd& V, double d2) {
  Eigen::MatrixXd out = V;
  out.diagonal().array() += d2;
  return out;
}

struct StructureFit {
  TermMask on{};
  LogParameters a{};
  Bounds bounds;
  double cost = 0.0;
  std::vector<std::pair<int, double>> dropped;  // term, z when dropped
};

// Fits the candidate set and drops insignificant terms one at a time.
// `V` is the working covariance of ln σ̂² (with δ²I); empty: computed from
// the full candidate fit and returned (without δ²I) in `V_model`.
StructureFit FitStructure(const FitData& data, const TermMask& candidates, double tau0,
                          std::span<const size_t> segment_samples, const AllanOptions& options,
                          Eigen::MatrixXd& V_model) {
  StructureFit fit;
  fit.on = candidates;
  const Start start = StartingValues(data, candidates);
  fit.a = start.a;
  fit.bounds = start.bounds;
  fit.cost = Solve(data, fit.on, start.bounds, options.max_solver_iterations, fit.a);
  if (V_model.size() == 0) V_model = LogAvarCovariance(data, fit.a, fit.on, tau0, segment_samples);
  const Eigen::MatrixXd V = WithDiscrepancy(V_model, data.discrepancy2);
  while (TermCount(fit.on) > 1) {
    std::array<double, kP> z = WaldZ(SandwichCovariance(data, fit.a, fit.on, V), fit.on);
    if (fit.on[kMt] && (fit.a[kMt] <= start.bounds.lower[kMt] + 1e-3 || fit.a[kMt] >= start.bounds.upper[kMt] - 1e-3)) {
      z[kMt] = 0.0;  // T on a bound: the peak is outside the curve
    }
    int worst = -1;
    double worst_z = std::numeric_limits<double>::infinity();
    for (int k = 0; k < kMt; ++k) {
      if (!fit.on[static_cast<size_t>(k)]) continue;
      const double zk = k == kMs ? std::min(z[kMs], z[kMt]) : z[static_cast<size_t>(k)];
      if (zk < worst_z) {
        worst_z = zk;
        worst = k;
      }
    }
    if (worst < 0 || worst_z >= options.significance_z) break;
    fit.dropped.emplace_back(worst, worst_z);
    fit.on[static_cast<size_t>(worst)] = false;
    if (worst == kMs) fit.on[kMt] = false;
    fit.cost = Solve(data, fit.on, start.bounds, options.max_solver_iterations, fit.a);
  }
  return fit;
}

std::string FormatG(double v, int digits = 3) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.*g", digits, v);
  return buf;
}

// ---------------------------------------------------------------------------
// Curve.

// Least-squares slope of ln σ̂ against ln τ within ± `window` decades of each point.
std::vector<double> LocalSlopes(const std::vector<AllanPoint>& curve, double window) {
  std::vector<double> slope(curve.size(), -0.5);
  for (size_t j = 0; j < curve.size(); ++j) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int n = 0;
    for (const AllanPoint& p : curve) {
      if (!(p.adev > 0.0) || std::abs(std::log10(p.tau_s / curve[j].tau_s)) > window + 1e-12) continue;
      const double x = std::log(p.tau_s);
      const double y = std::log(p.adev);
      sx += x;
      sy += y;
      sxx += x * x;
      sxy += x * y;
      ++n;
    }
    const double den = n * sxx - sx * sx;
    if (n >= 2 && den > 0.0) slope[j] = (n * sxy - sx * sy) / den;
  }
  return slope;
}

PowerLawNoise NoiseFromSlope(double mu) {
  if (mu < -0.75) return PowerLawNoise::kWhitePhase;  // phase noise: see AllanEdf's caller
  if (mu < -0.25) return PowerLawNoise::kWhiteRate;
  if (mu < 0.25) return PowerLawNoise::kFlickerRate;
  return PowerLawNoise::kRandomWalkRate;
}

// Angle of the rotation between two attitudes, for the stillness test.
class AttitudeTest {
 public:
  explicit AttitudeTest(double tolerance_rad) : tolerance_rad_(tolerance_rad) {}
  void SetAnchor(const Eigen::Vector3d& rpy) {
    anchor_rpy_ = rpy;
    anchor_ready_ = false;
  }
  bool Within(const Eigen::Vector3d& rpy) {
    if (rpy == anchor_rpy_) return true;
    if (!anchor_ready_) {
      C_anchor_t_ = nav::EulerToDcm(anchor_rpy_).transpose();
      anchor_ready_ = true;
    }
    const Eigen::Matrix3d R = C_anchor_t_ * nav::EulerToDcm(rpy);
    if (R.trace() < 1.0) return false;  // more than 90°
    const Eigen::Vector3d v(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
    return std::asin(std::min(1.0, 0.5 * v.norm())) <= tolerance_rad_;
  }

 private:
  double tolerance_rad_;
  Eigen::Vector3d anchor_rpy_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d C_anchor_t_ = Eigen::Matrix3d::Identity();
  bool anchor_ready_ = false;
};

// Still spans before the guard and the length rule.
std::vector<StaticSegment> StillSpans(const BenchRun& run, double tau0, const AllanOptions& options) {
  std::vector<StaticSegment> spans;
  const auto& s = run.samples;
  AttitudeTest test(options.attitude_tolerance_rad);
  size_t start = 0;
  test.SetAnchor(s[0].ref_rpy_rad);
  auto close = [&](size_t end) {
    if (end > start) spans.push_back({start, end, 0.0, 0.0});
  };
  for (size_t k = 1; k < s.size(); ++k) {
    const bool gap = s[k].t_s - s[k - 1].t_s > options.gap_factor * tau0;
    if (!gap && test.Within(s[k].ref_rpy_rad)) continue;
    // Sample k moved (or follows a gap): the next hold starts with sample k + 1,
    // whose interval begins at epoch k.
    close(k);
    start = k + 1;
    test.SetAnchor(s[k].ref_rpy_rad);
  }
  close(s.size());
  return spans;
}

std::string ChannelUnit(Sensor sensor) { return sensor == Sensor::kGyro ? "rad/s" : "m/s^2"; }

}  // namespace

// ---------------------------------------------------------------------------

absl::Status AllanOptions::Validate() const {
  if (!(attitude_tolerance_rad > 0.0)) return absl::InvalidArgumentError("Allan: the attitude tolerance must be positive");
  if (!(min_segment_s > 0.0)) return absl::InvalidArgumentError("Allan: the minimum segment length must be positive");
  if (!(motion_guard_s >= 0.0)) return absl::InvalidArgumentError("Allan: the motion guard must be non-negative");
  if (!(gap_factor > 1.0)) return absl::InvalidArgumentError("Allan: the gap factor must exceed 1");
  if (points_per_decade < 1 || points_per_decade > 100) {
    return absl::InvalidArgumentError("Allan: points per decade must be in [1, 100]");
  }
  if (!(max_cluster_fraction > 0.0 && max_cluster_fraction <= 0.5)) {
    return absl::InvalidArgumentError("Allan: the largest cluster fraction must be in (0, 0.5]");
  }
  if (!(confidence > 0.0 && confidence < 1.0)) return absl::InvalidArgumentError("Allan: confidence must be in (0, 1)");
  if (!(slope_window_decades > 0.0)) return absl::InvalidArgumentError("Allan: the slope window must be positive");
  if (!(significance_z >= 0.0)) return absl::InvalidArgumentError("Allan: the significance z must be non-negative");
  if (!(adequacy_alpha > 0.0 && adequacy_alpha < 1.0)) {
    return absl::InvalidArgumentError("Allan: the adequacy level must be in (0, 1)");
  }
  if (max_solver_iterations < 1) return absl::InvalidArgumentError("Allan: the solver needs at least one iteration");
  return absl::OkStatus();
}

double AllanEdf(PowerLawNoise noise, int64_t phase_points, int64_t m) {
  const auto N = static_cast<double>(phase_points);
  const auto dm = static_cast<double>(m);
  const double M = N - 2.0 * dm;
  if (M < 1.0 || m < 1) return 0.0;
  double edf = 1.0;
  switch (noise) {
    case PowerLawNoise::kWhitePhase:
      edf = (N + 1.0) * (N - 2.0 * dm) / (2.0 * (N - dm));
      break;
    case PowerLawNoise::kFlickerPhase: {
      const double a = std::log((N - 1.0) / (2.0 * dm));
      const double b = std::log((2.0 * dm + 1.0) * (N - 1.0) / 4.0);
      edf = a > 0.0 && b > 0.0 ? std::exp(std::sqrt(a * b)) : 1.0;
      break;
    }
    case PowerLawNoise::kWhiteRate:
      edf = (3.0 * (N - 1.0) / (2.0 * dm) - 2.0 * (N - 2.0) / N) * 4.0 * dm * dm / (4.0 * dm * dm + 5.0);
      break;
    case PowerLawNoise::kFlickerRate:
      edf = m == 1 ? 2.0 * (N - 2.0) * (N - 2.0) / (2.3 * N - 4.9) : 5.0 * N * N / (4.0 * dm * (N + 3.0 * dm));
      break;
    case PowerLawNoise::kRandomWalkRate:
      edf = N > 3.0 ? (N - 2.0) / (dm * (N - 3.0) * (N - 3.0)) *
                          ((N - 1.0) * (N - 1.0) - 3.0 * dm * (N - 1.0) + 4.0 * dm * dm)
                    : 1.0;
      break;
  }
  return std::clamp(edf, 1.0, M);
}

double ModelAllanVariance(const AllanNoiseTerms& t, double tau_s) {
  double s = 3.0 * t.quantization * t.quantization / (tau_s * tau_s) + t.white_density * t.white_density / tau_s +
             kFlickerAvar * t.bias_instability * t.bias_instability +
             t.rate_random_walk * t.rate_random_walk * tau_s / 3.0 + 0.5 * t.rate_ramp * t.rate_ramp * tau_s * tau_s;
  if (t.markov_sigma > 0.0 && t.markov_tau_s > 0.0) {
    s += t.markov_sigma * t.markov_sigma * MarkovShape(tau_s / t.markov_tau_s);
  }
  return s;
}

double AllanEstimatorCovariance(const AllanNoiseTerms& terms, double tau0_s, int64_t m_i, int64_t m_j,
                                std::span<const size_t> segment_samples) {
  const int64_t m[2] = {m_i, m_j};
  return EstimatorCovarianceMatrix(terms, tau0_s, m, segment_samples)(0, 1);
}

const char* AllanParameterName(AllanParameter p) {
  static constexpr const char* kNames[kP] = {"Q", "N", "B", "K", "R", "markov_sigma", "markov_tau"};
  return kNames[static_cast<int>(p)];
}

AllanNoiseTerms AllanFit::Terms() const {
  auto v = [&](AllanParameter p) { return (*this)[p].included ? (*this)[p].value : 0.0; };
  AllanNoiseTerms t;
  t.quantization = v(AllanParameter::kQuantization);
  t.white_density = v(AllanParameter::kWhiteDensity);
  t.bias_instability = v(AllanParameter::kBiasInstability);
  t.rate_random_walk = v(AllanParameter::kRateRandomWalk);
  t.rate_ramp = v(AllanParameter::kRateRamp);
  t.markov_sigma = v(AllanParameter::kMarkovSigma);
  t.markov_tau_s = v(AllanParameter::kMarkovTau);
  return t;
}

absl::StatusOr<std::vector<StaticSegment>> FindStaticSegments(const BenchRun& run, const AllanOptions& options) {
  if (auto st = options.Validate(); !st.ok()) return st;
  if (run.samples.size() < 2) return absl::InvalidArgumentError("Allan: the run has fewer than two samples");
  const double tau0 = run.NominalIntervalS();
  if (!(tau0 > 0.0)) return absl::InvalidArgumentError("Allan: the run has no positive sample interval");
  const auto guard = static_cast<size_t>(std::ceil(options.motion_guard_s / tau0 - 1e-9));
  const auto min_samples = static_cast<size_t>(std::ceil(options.min_segment_s / tau0 - 1e-6));
  const size_t n = run.samples.size();
  std::vector<StaticSegment> out;
  for (StaticSegment s : StillSpans(run, tau0, options)) {
    if (s.first_sample > 0) s.first_sample += guard;
    if (s.end_sample < n) s.end_sample = s.end_sample > guard ? s.end_sample - guard : 0;
    if (s.end_sample <= s.first_sample || s.Samples() < min_samples) continue;
    s.start_s = run.samples[s.first_sample].t_s - tau0;
    s.end_s = run.samples[s.end_sample - 1].t_s;
    out.push_back(s);
  }
  return out;
}

std::vector<int64_t> AllanClusterSizes(size_t longest_samples, const AllanOptions& options) {
  const auto m_max = static_cast<int64_t>(std::floor(options.max_cluster_fraction * static_cast<double>(longest_samples)));
  std::vector<int64_t> m;
  for (int k = 0;; ++k) {
    const auto mk = static_cast<int64_t>(std::llround(std::pow(10.0, static_cast<double>(k) / options.points_per_decade)));
    if (mk > m_max) break;
    if (m.empty() || mk > m.back()) m.push_back(mk);
  }
  return m;
}

std::vector<AllanPoint> OverlappingAllanCurve(std::span<const std::vector<double>> segment_rates, double tau0_s,
                                              std::span<const int64_t> cluster_sizes, const AllanOptions& options) {
  // Phase θ/τ₀ per segment (rate × samples): cumulative sums of the mean-free
  // rates, compensated (Neumaier), so that second differences keep full
  // precision however far θ wanders.
  std::vector<std::vector<double>> theta(segment_rates.size());
  for (size_t s = 0; s < segment_rates.size(); ++s) {
    const std::vector<double>& y = segment_rates[s];
    double mean = 0.0;
    double mean_c = 0.0;
    for (double v : y) {
      const double t = mean + v;
      mean_c += std::abs(mean) >= std::abs(v) ? (mean - t) + v : (v - t) + mean;
      mean = t;
    }
    mean = (mean + mean_c) / static_cast<double>(y.size());
    std::vector<double>& th = theta[s];
    th.resize(y.size() + 1);
    th[0] = 0.0;
    double sum = 0.0;
    double comp = 0.0;
    for (size_t k = 0; k < y.size(); ++k) {
      const double v = y[k] - mean;
      const double t = sum + v;
      comp += std::abs(sum) >= std::abs(v) ? (sum - t) + v : (v - t) + sum;
      sum = t;
      th[k + 1] = sum + comp;
    }
  }

  std::vector<AllanPoint> curve;
  for (int64_t m : cluster_sizes) {
    double sum = 0.0;
    int64_t count = 0;
    for (const std::vector<double>& th : theta) {
      const int64_t M = static_cast<int64_t>(th.size()) - 2 * m;
      if (M < 1) continue;
      const double* x0 = th.data();
      const double* x1 = x0 + m;
      const double* x2 = x0 + 2 * m;
      double acc[4] = {0.0, 0.0, 0.0, 0.0};
      int64_t k = 0;
      for (; k + 4 <= M; k += 4) {
        for (int l = 0; l < 4; ++l) {
          const double d = x2[k + l] - 2.0 * x1[k + l] + x0[k + l];
          acc[l] += d * d;
        }
      }
      for (; k < M; ++k) {
        const double d = x2[k] - 2.0 * x1[k] + x0[k];
        acc[0] += d * d;
      }
      sum += (acc[0] + acc[1]) + (acc[2] + acc[3]);
      count += M;
    }
    if (count < 1) continue;
    AllanPoint p;
    p.m = m;
    p.tau_s = tau0_s * static_cast<double>(m);
    p.differences = count;
    const double md = static_cast<double>(m);
    p.adev = std::sqrt(sum / (2.0 * md * md * static_cast<double>(count)));
    curve.push_back(p);
  }

  // Noise type from the local slope, ν summed over segments, χ² interval.
  const std::vector<double> slope = LocalSlopes(curve, options.slope_window_decades);
  for (size_t j = 0; j < curve.size(); ++j) {
    AllanPoint& p = curve[j];
    p.noise = NoiseFromSlope(slope[j]);
    double edf = 0.0;
    double edf_flicker_phase = 0.0;
    for (const std::vector<double>& th : theta) {
      const auto N = static_cast<int64_t>(th.size());
      edf += AllanEdf(p.noise, N, p.m);
      if (p.noise == PowerLawNoise::kWhitePhase) edf_flicker_phase += AllanEdf(PowerLawNoise::kFlickerPhase, N, p.m);
    }
    // Slope −1: white or flicker phase noise; take the smaller ν.
    if (p.noise == PowerLawNoise::kWhitePhase && edf_flicker_phase < edf) {
      edf = edf_flicker_phase;
      p.noise = PowerLawNoise::kFlickerPhase;
    }
    p.edf = edf;
    const double hi_q = ChiSquareQuantileFast(0.5 * (1.0 + options.confidence), edf);
    const double lo_q = ChiSquareQuantileFast(0.5 * (1.0 - options.confidence), edf);
    p.ci_low = p.adev * std::sqrt(edf / hi_q);
    p.ci_high = lo_q > 0.0 ? p.adev * std::sqrt(edf / lo_q) : std::numeric_limits<double>::infinity();
  }
  return curve;
}

absl::StatusOr<AllanFit> FitAllanCurve(std::vector<AllanPoint>& curve, double tau0_s,
                                       std::span<const size_t> segment_samples, const AllanOptions& options) {
  if (auto st = options.Validate(); !st.ok()) return st;
  FitData data;
  for (size_t j = 0; j < curve.size(); ++j) {
    const AllanPoint& p = curve[j];
    if (!(p.adev > 0.0) || !(p.edf >= 1.0)) continue;
    const double half = 0.5 * p.edf;
    data.point.push_back(j);
    data.m.push_back(p.m);
    data.tau.push_back(p.tau_s);
    data.avar.push_back(p.adev * p.adev);
    data.y.push_back(std::log(p.adev * p.adev) - (Digamma(half) - std::log(half)));
    data.s.push_back(std::sqrt(Trigamma(half)));
  }
  if (data.tau.size() < 2) {
    return absl::FailedPreconditionError("Allan fit: fewer than two points with a positive Allan deviation");
  }
  data.SetDiscrepancy(0.0);
  const auto n = static_cast<Eigen::Index>(data.tau.size());

  // The random terms first; the deterministic ramp is tested last, against them.
  const AllanOptions::Terms& cand = options.candidates;
  TermMask markov{};
  markov[kQ] = cand.quantization;
  markov[kN] = cand.white;
  markov[kK] = cand.rate_random_walk;
  markov[kMs] = markov[kMt] = cand.markov;
  TermMask flicker = markov;
  flicker[kMs] = flicker[kMt] = false;
  flicker[kB] = cand.bias_instability;
  TermMask all = markov;
  all[kB] = cand.bias_instability;
  all[kR] = cand.rate_ramp;

  if (std::none_of(all.begin(), all.end(), [](bool b) { return b; })) {
    return absl::InvalidArgumentError("Allan fit: no candidate term");
  }

  // One working covariance (of the full Markov candidate fit) serves the
  // eliminations of both structures: they describe the same curve, and it
  // only has to reflect the estimator's noise.
  Eigen::MatrixXd V_work;
  struct Selection {
    StructureFit fit;
    bool markov = false;
    TermMask candidates{};
    Eigen::MatrixXd V_model;  // V of the selected model (no δ²)
    std::vector<std::string> unresolved_extra;
  };
  auto select = [&]() {
    Selection sel;
    if (!options.select_terms) {
      // Every candidate, fitted once.
      sel.fit.on = all;
      const Start start = StartingValues(data, all);
      sel.fit.a = start.a;
      sel.fit.bounds = start.bounds;
      sel.fit.cost = Solve(data, all, start.bounds, options.max_solver_iterations, sel.fit.a);
      sel.markov = all[kMs];
      sel.candidates = all;
      sel.V_model = LogAvarCovariance(data, sel.fit.a, sel.fit.on, tau0_s, segment_samples);
      return sel;
    }
    bool have = false;
    StructureFit markov_fit;
    if (cand.markov) {
      markov_fit = FitStructure(data, markov, tau0_s, segment_samples, options, V_work);
      have = markov_fit.on[kMs];
    }
    const bool flicker_empty = std::none_of(flicker.begin(), flicker.end(), [](bool b) { return b; });
    if (have || flicker_empty) {
      sel.fit = markov_fit;
      sel.markov = markov_fit.on[kMs];
      sel.candidates = markov;
    } else {
      sel.fit = FitStructure(data, flicker, tau0_s, segment_samples, options, V_work);
      sel.candidates = flicker;
      for (const auto& [k, z] : markov_fit.dropped) {
        if (k == kMs) sel.unresolved_extra.push_back("markov (z = " + FormatG(z, 2) + ")");
      }
    }
    sel.V_model = LogAvarCovariance(data, sel.fit.a, sel.fit.on, tau0_s, segment_samples);
    if (cand.rate_ramp) {
      // Ramp test: R's Wald z under the covariance of the model without it
      // (the null hypothesis), since a deterministic ramp's own model claims
      // the large-τ estimates are nearly exact.
      sel.candidates[kR] = true;
      StructureFit ramp = sel.fit;
      ramp.on[kR] = true;
      double best = std::numeric_limits<double>::infinity();
      for (double fraction : {1e-1, 1e-4}) {
        LogParameters a = sel.fit.a;
        a[kR] = std::log(fraction * ramp.bounds.envelope[kR]);
        const double cost = Solve(data, ramp.on, ramp.bounds, options.max_solver_iterations, a);
        if (cost < best) {
          best = cost;
          ramp.a = a;
          ramp.cost = cost;
        }
      }
      const Eigen::MatrixXd V0 = WithDiscrepancy(sel.V_model, data.discrepancy2);
      const double z = WaldZ(SandwichCovariance(data, ramp.a, ramp.on, V0), ramp.on)[kR];
      if (z >= options.significance_z) {
        sel.fit = ramp;
        sel.V_model = LogAvarCovariance(data, sel.fit.a, sel.fit.on, tau0_s, segment_samples);
      } else {
        sel.fit.dropped.emplace_back(kR, z);
      }
    }
    return sel;
  };
  auto residuals = [&](const StructureFit& f) {
    Eigen::VectorXd e(n);
    for (Eigen::Index j = 0; j < n; ++j) {
      const auto jj = static_cast<size_t>(j);
      e[j] = data.y[jj] - std::log(ModelAvar(f.a.data(), f.on, data.tau[jj]));
    }
    return e;
  };

  Selection sel = select();
  Eigen::VectorXd e = residuals(sel.fit);
  AllanFit out;
  out.points = static_cast<int>(n);

  // χ²_g = eᵀV⁻¹e over the directions V resolves (eigenvalues above 1e-9 of the largest).
  {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(sel.V_model);
    const double lmax = LargestOf(eig.eigenvalues());
    double chi2 = 0.0;
    int rank = 0;
    for (Eigen::Index k = 0; k < n; ++k) {
      const double l = eig.eigenvalues()[k];
      if (!(l > 1e-9 * lmax)) continue;
      const double proj = eig.eigenvectors().col(k).dot(e);
      chi2 += proj * proj / l;
      ++rank;
    }
    out.generalized_chi2 = chi2;
    out.dof = std::max(1, rank - ParameterCount(sel.fit.on));
    out.p_value = stats::ChiSquareSurvival(chi2, out.dof);
    out.adequate = out.p_value >= options.adequacy_alpha;
  }

  if (!out.adequate) {
    // Model discrepancy: δ² with eᵀ(V + δ²I)⁻¹e = n − p (a random-effects
    // variance: the share of ln σ̂² the model cannot explain). The weights
    // become 1/(s² + δ²), so the most precise points no longer pull the fit
    // alone, and the terms are selected again. Two rounds.
    for (int round = 0; round < 2; ++round) {
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(sel.V_model);
      const Eigen::VectorXd proj = eig.eigenvectors().transpose() * e;
      const double target = std::max(1.0, static_cast<double>(n - ParameterCount(sel.fit.on)));
      auto chi2_at = [&](double d2) {
        double c = 0.0;
        for (Eigen::Index k = 0; k < n; ++k) c += proj[k] * proj[k] / (std::max(0.0, eig.eigenvalues()[k]) + d2);
        return c;
      };
      double lo = std::log(1e-12);
      double hi = std::log(1e2);
      for (int i = 0; i < 100; ++i) {
        const double mid = 0.5 * (lo + hi);
        (chi2_at(std::exp(mid)) > target ? lo : hi) = mid;
      }
      data.SetDiscrepancy(std::exp(0.5 * (lo + hi)));
      if (round == 0) {
        sel = select();
      } else {
        const Start start = StartingValues(data, sel.fit.on);
        sel.fit.cost = Solve(data, sel.fit.on, start.bounds, options.max_solver_iterations, sel.fit.a);
        sel.V_model = LogAvarCovariance(data, sel.fit.a, sel.fit.on, tau0_s, segment_samples);
      }
      e = residuals(sel.fit);
    }
  }
  out.discrepancy = std::sqrt(data.discrepancy2);
  out.markov_structure = sel.markov;
  const StructureFit& chosen = sel.fit;
  const Eigen::MatrixXd V = WithDiscrepancy(sel.V_model, data.discrepancy2);
  const Eigen::MatrixXd cov = SandwichCovariance(data, chosen.a, chosen.on, V);
  out.free_parameters = ParameterCount(chosen.on);
  out.weighted_sse = chosen.cost;

  // Per-point fit and standardised residuals.
  std::vector<bool> disagree(curve.size(), false);
  for (Eigen::Index j = 0; j < n; ++j) {
    const auto jj = static_cast<size_t>(j);
    AllanPoint& p = curve[data.point[jj]];
    p.fitted_adev = std::sqrt(ModelAvar(chosen.a.data(), chosen.on, data.tau[jj]));
    p.log_residual = e[j] / std::sqrt(sel.V_model(j, j));
    disagree[data.point[jj]] = std::abs(p.log_residual) > 3.0;
  }

  const AllanNoiseTerms terms = TermsFromLog(chosen.a, chosen.on);
  const double values[kP] = {terms.quantization,     terms.white_density, terms.bias_instability,
                             terms.rate_random_walk, terms.rate_ramp,     terms.markov_sigma,
                             terms.markov_tau_s};
  int col = 0;
  for (int k = 0; k < kP; ++k) {
    AllanTermEstimate& t = out.parameters[static_cast<size_t>(k)];
    t.tried = sel.candidates[static_cast<size_t>(k)];
    if (!chosen.on[static_cast<size_t>(k)]) continue;
    const double var = cov(col, col);
    ++col;
    t.included = true;
    t.value = values[k];
    const double se_log = var >= 0.0 ? std::sqrt(var) : std::numeric_limits<double>::infinity();
    t.z = se_log > 0.0 ? 1.0 / se_log : std::numeric_limits<double>::infinity();
    // Amplitudes are square roots of their AVAR coefficient: SE = v·SE(a)/2; T = e^a.
    t.std_error = t.value * se_log * (k == kMt ? 1.0 : 0.5);
  }
  for (const auto& [k, z] : chosen.dropped) {
    out.unresolved.push_back(std::string(AllanParameterName(static_cast<AllanParameter>(k))) + " (z = " +
                             FormatG(z, 2) + ")");
  }
  for (const std::string& u : sel.unresolved_extra) out.unresolved.push_back(u);

  if (!out.adequate) {
    std::string ranges;
    for (size_t j = 0; j < curve.size();) {
      if (!disagree[j]) {
        ++j;
        continue;
      }
      size_t end = j;
      while (end + 1 < curve.size() && disagree[end + 1]) ++end;
      ranges += (ranges.empty() ? "" : ", ") + FormatG(curve[j].tau_s) + "–" + FormatG(curve[end].tau_s) + " s";
      j = end + 1;
    }
    out.notes.push_back("the noise model does not explain the curve (χ² = " + FormatG(out.generalized_chi2) +
                        " on " + std::to_string(out.dof) + " dof, p = " + FormatG(out.p_value, 2) +
                        "): fitted again with a model discrepancy of " + FormatG(100.0 * out.discrepancy, 2) +
                        "% in σ² added to every point" +
                        (ranges.empty() ? std::string() : "; departures beyond 3σ at τ = " + ranges));
  }
  return out;
}

absl::StatusOr<AllanResult> AllanAnalysis(const BenchRun& run, const AllanOptions& options) {
  auto segments = FindStaticSegments(run, options);
  if (!segments.ok()) return segments.status();
  const double tau0 = run.NominalIntervalS();
  if (segments->empty()) {
    double longest = 0.0;
    for (const StaticSegment& s : StillSpans(run, tau0, options)) longest = std::max(longest, s.Samples() * tau0);
    return absl::FailedPreconditionError(
        "Allan: no static segment of at least " + FormatG(options.min_segment_s) + " s (the longest still span is " +
        FormatG(longest) + " s with an attitude tolerance of " + FormatG(options.attitude_tolerance_rad) + " rad)");
  }
  AllanResult result;
  result.tau0_s = tau0;
  result.segments = *std::move(segments);
  std::vector<size_t> lengths;
  size_t longest = 0;
  for (const StaticSegment& s : result.segments) {
    lengths.push_back(s.Samples());
    longest = std::max(longest, s.Samples());
    result.samples_used += s.Samples();
  }
  const std::vector<int64_t> m = AllanClusterSizes(longest, options);
  if (m.empty()) return absl::FailedPreconditionError("Allan: the static segments are too short for any cluster");

  std::vector<std::vector<double>> rates(result.segments.size());
  for (int c = 0; c < 6; ++c) {
    AllanChannel ch;
    ch.name = std::string(kSensorChannelNames[c]);
    ch.sensor = c < 3 ? Sensor::kGyro : Sensor::kAccelerometer;
    ch.axis = c % 3;
    ch.unit = ChannelUnit(ch.sensor);
    for (size_t s = 0; s < result.segments.size(); ++s) {
      const StaticSegment& seg = result.segments[s];
      rates[s].resize(seg.Samples());
      for (size_t k = 0; k < seg.Samples(); ++k) {
        const ImuSample& sample = run.samples[seg.first_sample + k];
        rates[s][k] = c < 3 ? sample.gyro_rad_s[ch.axis] : sample.acc_mps2[ch.axis];
      }
    }
    ch.curve = OverlappingAllanCurve(rates, tau0, m, options);
    auto fit = FitAllanCurve(ch.curve, tau0, lengths, options);
    if (fit.ok()) {
      ch.fit = *std::move(fit);
    } else {
      ch.fit.notes.push_back(std::string(fit.status().message()));
    }
    result.channels.push_back(std::move(ch));
  }
  return result;
}

std::vector<ParameterEstimate> AllanParameterEstimates(const AllanResult& result, const ErrorModel* a_priori) {
  std::map<std::string, double> prior;
  if (a_priori != nullptr) {
    for (const NamedParameter& p : ParametersOf(*a_priori)) prior[p.name] = p.value;
  }
  static constexpr const char* kAxis[3] = {"x", "y", "z"};
  std::vector<ParameterEstimate> out;
  for (const AllanChannel& ch : result.channels) {
    const bool gyro = ch.sensor == Sensor::kGyro;
    const std::string s = gyro ? "gyro" : "acc";
    const std::string axis = kAxis[ch.axis];
    auto add = [&](AllanParameter p, const std::string& name, const std::string& unit) {
      const AllanTermEstimate& t = ch.fit[p];
      if (!t.included) return;
      ParameterEstimate e;
      e.name = name;
      e.value = t.value;
      e.std_error = t.std_error;
      e.method = "ALLAN";
      e.unit = unit;
      if (auto it = prior.find(name); it != prior.end()) e.a_priori = it->second;
      out.push_back(e);
    };
    add(AllanParameter::kQuantization, s + "_quantization." + axis, gyro ? "rad" : "m/s");
    add(AllanParameter::kWhiteDensity, (gyro ? "gyro_arw." : "acc_vrw.") + axis,
        gyro ? "rad/sqrt(s)" : "m/s/sqrt(s)");
    add(AllanParameter::kBiasInstability, s + "_bias_instability." + axis, gyro ? "rad/s" : "m/s^2");
    add(AllanParameter::kRateRandomWalk, s + "_rate_random_walk." + axis, gyro ? "rad/s/sqrt(s)" : "m/s^2/sqrt(s)");
    add(AllanParameter::kRateRamp, s + "_rate_ramp." + axis, gyro ? "rad/s^2" : "m/s^3");
    add(AllanParameter::kMarkovSigma, s + "_bias_gm." + axis + ".sigma", gyro ? "rad/s" : "m/s^2");
    add(AllanParameter::kMarkovTau, s + "_bias_gm." + axis + ".tau", "s");
  }
  return out;
}

absl::StatusOr<ErrorModel> ErrorModelFromAllan(const AllanResult& result, const ReferenceAccuracy& reference,
                                               std::vector<std::string>* notes) {
  if (result.channels.size() != 6) return absl::InvalidArgumentError("Allan: the result does not hold six channels");
  ErrorModel model;
  model.reference = reference;
  const MarkovPeak& peak = MarkovShapePeak();
  auto note = [&](const std::string& s) {
    if (notes != nullptr) notes->push_back(s);
  };
  for (const AllanChannel& ch : result.channels) {
    SensorTriadModel& triad = ch.sensor == Sensor::kGyro ? model.gyro : model.acc;
    const AllanFit& fit = ch.fit;
    const auto axis = static_cast<size_t>(ch.axis);
    if (ch.curve.empty()) return absl::InvalidArgumentError("Allan: channel " + ch.name + " has no curve");

    // White noise: N, else the tangent bound min σ̂ √τ.
    if (fit[AllanParameter::kWhiteDensity].included) {
      triad.white_noise_density[ch.axis] = fit[AllanParameter::kWhiteDensity].value;
    } else {
      double bound = std::numeric_limits<double>::infinity();
      for (const AllanPoint& p : ch.curve) {
        if (p.adev > 0.0) bound = std::min(bound, p.adev * std::sqrt(p.tau_s));
      }
      triad.white_noise_density[ch.axis] = std::isfinite(bound) ? bound : 0.0;
      note(ch.name + ": white noise not resolved, density set to the bound min σ̂√τ");
    }
    triad.quantization[ch.axis] =
        fit[AllanParameter::kQuantization].included ? fit[AllanParameter::kQuantization].value : 0.0;

    // Drift.
    const AllanNoiseTerms terms = fit.Terms();
    auto lowest = [&](bool fitted) {
      const AllanPoint* best = nullptr;
      for (const AllanPoint& p : ch.curve) {
        const double v = fitted ? p.fitted_adev : p.adev;
        if (!(v > 0.0)) continue;
        if (best == nullptr || v < (fitted ? best->fitted_adev : best->adev)) best = &p;
      }
      return best;
    };
    GaussMarkov& gm = triad.bias[axis];
    if (fit[AllanParameter::kMarkovSigma].included) {
      gm = {terms.markov_sigma, terms.markov_tau_s};
      note(ch.name + ": drift from the fitted Gauss–Markov term");
    } else if (fit[AllanParameter::kBiasInstability].included) {
      const AllanPoint* p = lowest(true);
      const double floor = std::sqrt(kFlickerAvar) * terms.bias_instability;
      const double tau_floor = p != nullptr ? p->tau_s : ch.curve.back().tau_s;
      gm = {floor / std::sqrt(peak.g), tau_floor / peak.u};
      note(ch.name + ": drift from the bias instability: the Markov process whose Allan peak is the flicker floor at τ = " +
           FormatG(tau_floor) + " s");
    } else if (fit[AllanParameter::kRateRandomWalk].included) {
      const double T = ch.curve.back().tau_s;
      gm = {terms.rate_random_walk * std::sqrt(0.5 * T), T};
      note(ch.name + ": drift from the rate random walk with T = the longest τ analysed (" + FormatG(T) + " s)");
    } else {
      const AllanPoint* p = lowest(false);
      if (p == nullptr) return absl::InvalidArgumentError("Allan: channel " + ch.name + " has no positive deviation");
      gm = {p->adev / std::sqrt(peak.g), p->tau_s / peak.u};
      note(ch.name + ": no drift term resolved; Gauss–Markov drift set to the bound from the curve's lowest point");
    }
  }
  return model;
}

}  // namespace insdiag::engine::ident
