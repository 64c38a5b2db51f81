// The covariance of the overlapping Allan variance estimator under a noise
// model (allan.h: the phase's generalised autocovariance, summed over lags).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <vector>

#include "ident/allan_model.h"

namespace insdiag::engine::ident {
namespace allan_model {
namespace {

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
class LagSum {
 public:
  LagSum(const PhaseCovariance& g, double tau0, int64_t mi, int64_t mj, int64_t Mi, int64_t Mj)
      : g_(g), tau0_(tau0), mi_(mi), mj_(mj), Mi_(Mi), Mj_(Mj) {}

  double Total() const {
    const int64_t lo = std::max(-2 * mj_, -(Mi_ - 1));
    const int64_t hi = std::min(2 * mi_, Mj_ - 1);
    if (lo > hi) return 0.0;
    std::vector<int64_t> breaks = {lo, hi};
    for (int p = 0; p < 3; ++p) {
      for (int q = 0; q < 3; ++q) breaks.push_back(p * mi_ - q * mj_);
    }
    breaks.push_back(0);
    breaks.push_back(Mj_ - Mi_);
    std::sort(breaks.begin(), breaks.end());
    breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());
    std::map<int64_t, double> break_value;
    auto at_break = [&](int64_t d) {
      auto [it, fresh] = break_value.try_emplace(d, 0.0);
      if (fresh) it->second = Term(static_cast<double>(d));
      return it->second;
    };
    double sum = 0.0;
    for (size_t b = 0; b + 1 < breaks.size(); ++b) {
      const int64_t u = std::max(breaks[b], lo);
      const int64_t v = std::min(breaks[b + 1], hi);
      if (u >= v) continue;
      if (v - u <= kExactPiece) {
        for (int64_t d = u; d < v; ++d) sum += Term(static_cast<double>(d));
        continue;
      }
      // Σ_{d=u}^{v−1} f(d) = ∫_u^v f + (f(u) − f(v))/2 + (f′(v) − f′(u))/12 + …
      // The derivative term is O(1/len²) of the piece: left out.
      sum += LongPieceIntegral(u, v) + 0.5 * (at_break(u) - at_break(v));
    }
    sum += at_break(hi);
    if (g_.q2 > 0.0) AddQuantisationAtMeetingLags(lo, hi, sum);
    return sum;
  }

 private:
  static constexpr int64_t kExactPiece = 48;

  // How many difference pairs lie d apart.
  double Count(double d) const {
    return std::max(
        0.0, std::min(static_cast<double>(Mi_), static_cast<double>(Mj_) - d) - std::max(0.0, -d));
  }
  double Covariance(double d) const {
    double c = 0.0;
    for (int p = 0; p < 3; ++p) {
      for (int q = 0; q < 3; ++q)
        c += kTap[p] * kTap[q] * g_.Smooth(tau0_ * (d + static_cast<double>(q * mj_ - p * mi_)));
    }
    return c;
  }
  double Term(double d) const {
    const double c = Covariance(d);
    return Count(d) * c * c;
  }

  // ∫_u^v n(d) c(d)² dd over a piece between two meeting lags.
  double LongPieceIntegral(int64_t u, int64_t v) const {
    // Subintervals for Gauss–Legendre: fine enough for the Markov exponential.
    const double markov_scale = g_.markov > 0.0 ? g_.markov_tau_s / tau0_ : 0.0;
    static const double kNode[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                    0.8611363115940526};
    static const double kWeight[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                      0.3478548451374538};
    // The Markov exponential and the flicker logarithm vary fast only next to
    // the piece's ends (their kinks): sub-intervals grow geometrically from
    // both ends, from T/2 (Markov) or len/32 (flicker), for six doublings.
    const double len = static_cast<double>(v - u);
    double first = len;
    // Where T is below 1/1000 of the piece, its exponential fills an O(T/len) sliver: not resolved.
    if (markov_scale > 1e-3 * len) first = std::min(first, 0.5 * markov_scale);
    if (g_.flicker > 0.0) first = std::min(first, len / 32.0);
    std::vector<double> cuts(1, 0.0);
    for (double w = first; w < 0.5 * len && w < 64.0 * first; w *= 2.0) cuts.push_back(w);
    const size_t half = cuts.size();
    for (size_t k = half; k-- > 0;) cuts.push_back(len - cuts[k]);
    // Inside the piece every tap lag d + o (o = q m_j − p m_i) keeps its sign,
    // so the nine Markov exponentials e^{−|d+o|/T} factor into two:
    // ea·e^{−(d−u)/T} + eb·e^{−(v−d)/T} (all exponents ≤ 0).
    double ea = 0.0;
    double eb = 0.0;
    if (g_.markov > 0.0) {
      const double mid = 0.5 * static_cast<double>(u + v);
      for (int p = 0; p < 3; ++p) {
        for (int q = 0; q < 3; ++q) {
          const auto o = static_cast<double>(q * mj_ - p * mi_);
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
          c += kTap[p] * kTap[q] *
               g_.Polynomial(tau0_ * (d + static_cast<double>(q * mj_ - p * mi_)));
        }
      }
      if (g_.markov > 0.0) {
        c -= g_.markov * (ea * std::exp(-(d - static_cast<double>(u)) / markov_scale) +
                          eb * std::exp(-(static_cast<double>(v) - d) / markov_scale));
      }
      return Count(d) * c * c;
    };
    double integral = 0.0;
    for (size_t k = 0; k + 1 < cuts.size(); ++k) {
      const double width = cuts[k + 1] - cuts[k];
      if (!(width > 0.0)) continue;
      const double mid = static_cast<double>(u) + 0.5 * (cuts[k] + cuts[k + 1]);
      for (int q = 0; q < 4; ++q) integral += 0.5 * width * kWeight[q] * inner(mid + 0.5 * width * kNode[q]);
    }
    return integral;
  }

  // The δ of white phase noise at the lags where taps meet.
  void AddQuantisationAtMeetingLags(int64_t lo, int64_t hi, double& sum) const {
    std::map<int64_t, double> meet;
    for (int p = 0; p < 3; ++p) {
      for (int q = 0; q < 3; ++q) {
        const int64_t d = p * mi_ - q * mj_;
        if (d >= lo && d <= hi) meet[d] += kTap[p] * kTap[q] * g_.q2;
      }
    }
    for (const auto& [d, cq] : meet) {
      const double cs = Covariance(static_cast<double>(d));
      sum += Count(static_cast<double>(d)) * ((cs + cq) * (cs + cq) - cs * cs);
    }
  }

  const PhaseCovariance& g_;
  const double tau0_;
  const int64_t mi_, mj_, Mi_, Mj_;
};

}  // namespace

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
        s += count * LagSum(g, tau0, m[i], m[j], Mi, Mj).Total();
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

}  // namespace allan_model

double AllanEstimatorCovariance(const AllanNoiseTerms& terms, double tau0_s, int64_t m_i, int64_t m_j,
                                std::span<const size_t> segment_samples) {
  const int64_t m[2] = {m_i, m_j};
  return allan_model::EstimatorCovarianceMatrix(terms, tau0_s, m, segment_samples)(0, 1);
}

}  // namespace insdiag::engine::ident
