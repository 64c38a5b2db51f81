#include "insdiag/engine/finder/onset_scan.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <utility>

#include "insdiag/engine/filter/observation.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine {
namespace {

// Two columns per sensor axis: the step's and the ramp's pair (header).
constexpr int kColumns = 2 * kSensorAxisCount;
using Matrix9c = Eigen::Matrix<double, kNavigationStates, kColumns>;
using MatrixCc = Eigen::Matrix<double, kColumns, kColumns>;

// Z of one interval, centred on `centre_s`.
Matrix9c FaultColumns(const EpochInterval& e, double centre_s) {
  Matrix9c Z;
  const double mid_offset_s = e.start_s + 0.5 * e.sample_interval_s - centre_s;
  for (int a = 0; a < kSensorAxisCount; ++a) {
    Z.col(2 * a) = e.moments[0].col(a);
    Z.col(2 * a + 1) = e.moments[1].col(a) + mid_offset_s * e.moments[0].col(a);
  }
  return Z;
}

// One epoch's update sequence rebuilt from its prior covariance: the rows
// H̃ (channels × n; zero where a channel is not observed) through which a navigation error before the updates reaches each
// innovation, and the map L (n × n) of the updates on the filter's error.
void UpdateSequence(const ForwardPass& fw, int k, const std::array<ObservationRow, kChannelCount>& rows,
                    Eigen::MatrixXd& P, Eigen::VectorXd& PH, Eigen::VectorXd& gain, Eigen::MatrixXd& H,
                    Eigen::MatrixXd& L) {
  const int n = fw.state_size;
  UnpackSymmetric(fw.P_pred.row(k).data(), n, P);
  L.setIdentity();
  for (int c = 0; c < kChannelCount; ++c) {
    if (!fw.Observed(k, c)) {
      H.row(c).setZero();  // no innovation: nothing reaches it, and the update is the identity
      continue;
    }
    const ObservationRow& h = rows[static_cast<size_t>(c)];
    PH = h.sign * P.col(h.state);
    const double S = fw.innovation_variance(k, c);
    gain = PH / S;
    H.row(c) = h.sign * L.row(h.state);
    L.noalias() -= gain * H.row(c);
    // With the optimal gain the Joseph form the filter used equals P − K (Phᵀ)ᵀ.
    P.noalias() -= gain * PH.transpose();
  }
}

// Per onset θ: every column's score and their information, and per sensor
// axis the covariance of the axis pair's successive scores (header).
struct OnsetSums {
  std::vector<Eigen::Matrix<double, kColumns, 1>> score;
  std::vector<MatrixCc> information;
  std::vector<std::array<Eigen::Matrix2d, kSensorAxisCount>> successive;  // Cov(s(θ), s(θ+1))
  // The adjoint's navigation part at each epoch, for an onset inside its
  // interval (TryOnsetInsideInterval): λ_k, Γ_k and m_k of the header.
  std::vector<NavigationVector> lambda;
  std::vector<Matrix9d> gamma;
  std::vector<Matrix9c> cross;

  explicit OnsetSums(int epochs)
      : score(static_cast<size_t>(epochs)),
        information(static_cast<size_t>(epochs)),
        successive(static_cast<size_t>(epochs)),
        lambda(static_cast<size_t>(epochs)),
        gamma(static_cast<size_t>(epochs)),
        cross(static_cast<size_t>(epochs)) {}
};

OnsetSums BackwardSweep(const ForwardPass& fw, const StateLayout& layout, const EpochRun& run,
                        double centre_s) {
  const int K = fw.epochs();
  const int n = fw.state_size;
  const auto rows = ObservationRows(layout);
  OnsetSums out(K);
  Eigen::MatrixXd P(n, n), H(kChannelCount, n), L(n, n), Phi(n, n), F(n, n), Gamma = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd FtGamma(n, n), adjoint_columns = Eigen::MatrixXd::Zero(n, kColumns), next_gamma_w(n, kColumns);
  Eigen::VectorXd PH(n), gain(n), lambda = Eigen::VectorXd::Zero(n), weighted(n);
  Eigen::Matrix<double, kColumns, 1> score = Eigen::Matrix<double, kColumns, 1>::Zero();
  MatrixCc information = MatrixCc::Zero();
  Matrix9c Z_next = Matrix9c::Zero();
  for (int k = K - 1; k >= 0; --k) {
    UpdateSequence(fw, k, rows, P, PH, gain, H, L);
    if (k + 1 < K) {
      fw.transitions[static_cast<size_t>(k + 1)].WriteDense(Phi);
      F.noalias() = Phi * L;
      next_gamma_w.noalias() = Gamma.leftCols<kNavigationStates>() * Z_next;
      next_gamma_w += adjoint_columns;
      adjoint_columns.noalias() = F.transpose() * next_gamma_w;
      weighted.noalias() = F.transpose() * lambda;
      lambda = weighted;
      FtGamma.noalias() = F.transpose() * Gamma;
      Gamma.noalias() = FtGamma * F;
    }
    for (int c = 0; c < kChannelCount; ++c) {
      if (!fw.Observed(k, c)) continue;
      const double S = fw.innovation_variance(k, c);
      lambda.noalias() += H.row(c).transpose() * (fw.innovation(k, c) / S);
      Gamma.noalias() += H.row(c).transpose() * (H.row(c) / S);
    }
    const Matrix9c Z = FaultColumns(run.epochs[static_cast<size_t>(k)], centre_s);
    const MatrixCc cross = Z.transpose() * adjoint_columns.topRows<kNavigationStates>();
    const MatrixCc successive = information + cross;
    score.noalias() += Z.transpose() * lambda.head<kNavigationStates>();
    information += Z.transpose() * Gamma.topLeftCorner<kNavigationStates, kNavigationStates>() * Z +
                   cross + cross.transpose();
    const auto at = static_cast<size_t>(k);
    out.score[at] = score;
    out.information[at] = information;
    out.lambda[at] = lambda.head<kNavigationStates>();
    out.gamma[at] = Gamma.topLeftCorner<kNavigationStates, kNavigationStates>();
    out.cross[at] = adjoint_columns.topRows<kNavigationStates>();
    for (int a = 0; a < kSensorAxisCount; ++a) {
      out.successive[at][static_cast<size_t>(a)] = successive.block<2, 2>(2 * a, 2 * a);
    }
    Z_next = Z;
  }
  return out;
}

// A fault's direction in its axis pair for an onset at t₀: a step is μ_0, a
// ramp from t₀ is Z (t_c − t₀, 1) (header).
Eigen::Vector2d PairDirectionFrom(const EffectTerm& term, double onset_s, double centre_s) {
  return term.family->regressor == Regressor::kRamp ? Eigen::Vector2d(centre_s - onset_s, 1.0)
                                                    : Eigen::Vector2d(1.0, 0.0);
}

// The same for the onset at the start of interval θ.
Eigen::Vector2d PairDirection(const EffectTerm& term, const EpochRun& run, int theta,
                              double centre_s) {
  return PairDirectionFrom(term, run.epochs[static_cast<size_t>(theta)].start_s, centre_s);
}

// A fault's direction among all columns for an onset at t₀.
Eigen::Matrix<double, kColumns, 1> ColumnDirectionFrom(const EffectTerm& term, double onset_s,
                                                       double centre_s) {
  Eigen::Matrix<double, kColumns, 1> e = Eigen::Matrix<double, kColumns, 1>::Zero();
  e.segment<2>(2 * SensorAxisIndex(term.family->sensor, term.axis)) =
      PairDirectionFrom(term, onset_s, centre_s);
  return e;
}

// The same for the onset at the start of interval θ.
Eigen::Matrix<double, kColumns, 1> ColumnDirection(const EffectTerm& term, const EpochRun& run,
                                                   int theta, double centre_s) {
  return ColumnDirectionFrom(term, run.epochs[static_cast<size_t>(theta)].start_s, centre_s);
}

// The likelihood ratio of a fault whose onset t₀ lies inside interval k:
// the interval's samples after t₀ (FaultColumn, w) and every later interval
// whole, so by the header's recursion with w in place of W_k:
//   s = eᵀ s(k+1) + wᵀ λ_k,   I = eᵀ I(k+1) e + wᵀ Γ_k w + 2 wᵀ m_k e
// with e the fault's direction among the columns for onset t₀.
struct OnsetTrial {
  double onset_s = 0.0;
  double statistic = 0.0;
  double estimate = 0.0;
  double std_error = 0.0;
};

std::optional<OnsetTrial> TryOnsetInsideInterval(const EffectTerm& term, const OnsetSums& sums,
                                                 const EpochRun& run, int k, double onset_s,
                                                 double centre_s) {
  const int axis = SensorAxisIndex(term.family->sensor, term.axis);
  const Eigen::Matrix<double, kColumns, 1> e = ColumnDirectionFrom(term, onset_s, centre_s);
  const auto at = static_cast<size_t>(k);
  double score = 0.0, information = 0.0;
  if (k + 1 < run.size()) {
    score = e.dot(sums.score[at + 1]);
    information = e.dot(sums.information[at + 1] * e);
  }
  const NavigationVector w = FaultColumn(run.epochs[at], axis, term.family->regressor, onset_s);
  score += w.dot(sums.lambda[at]);
  information += w.dot(sums.gamma[at] * w) + 2.0 * w.dot(sums.cross[at] * e);
  if (!(information > 0.0) || !std::isfinite(information)) return std::nullopt;
  return OnsetTrial{onset_s, score * score / information, score / information,
                    1.0 / std::sqrt(information)};
}

// Positions tried within a sample, either side of the best sample boundary.
constexpr int kPositionsPerSample = 16;

// The interval that holds onset t₀ strictly inside it, among k − 1 … k + 1
// and the run's intervals from `first`; −1 where none does.
int IntervalHolding(const EpochRun& run, int first, int k, double onset_s) {
  for (int i = std::max(first, k - 1); i <= std::min(k + 1, run.size() - 1); ++i) {
    const EpochInterval& e = run.epochs[static_cast<size_t>(i)];
    if (onset_s > e.start_s && onset_s < e.time_s) return i;
  }
  return -1;
}

// Moves the fit's onset from the start of its interval to where the fault
// most likely began, in that interval or the one before: an onset between
// two updates puts only part of the fault into its first interval, and
// taking all of it there biases the magnitude (towards half of it where the
// first seconds carry the evidence, as for an accelerometer step). First
// the sample boundaries, then positions within the samples either side of
// the best: a fault that begins inside a sample gives that sample its share
// (the interval means of the bench-run format), which FaultColumn weighs.
// Returns every onset it tried, for the onset's posterior.
std::vector<OnsetTrial> PlaceOnsetAtItsSample(const OnsetSums& sums, const EpochRun& run, int first,
                                              double centre_s, OnsetFit& fit) {
  OnsetTrial best{fit.onset_s, fit.estimate * fit.estimate / (fit.std_error * fit.std_error),
                  fit.estimate, fit.std_error};
  int best_interval = fit.onset_epoch;
  std::vector<OnsetTrial> tried;
  auto try_at = [&](int k, double onset_s) {
    const auto trial = TryOnsetInsideInterval(fit.term, sums, run, k, onset_s, centre_s);
    if (!trial.has_value()) return;
    tried.push_back(*trial);
    if (trial->statistic > best.statistic) {
      best = *trial;
      best_interval = k;
    }
  };
  for (int k = std::max({0, first - 1, fit.onset_epoch - 1}); k <= fit.onset_epoch; ++k) {
    const EpochInterval& e = run.epochs[static_cast<size_t>(k)];
    for (int j = 1; j < e.samples; ++j) try_at(k, e.start_s + j * e.sample_interval_s);
  }
  const double boundary_s = best.onset_s;
  const double dt = run.epochs[static_cast<size_t>(best_interval)].sample_interval_s;
  for (int i = 1; i < 2 * kPositionsPerSample; ++i) {
    if (i == kPositionsPerSample) continue;  // the boundary itself
    const double onset_s = boundary_s + (i - kPositionsPerSample) * dt / kPositionsPerSample;
    const int k = IntervalHolding(run, std::max(0, first - 1), best_interval, onset_s);
    if (k >= 0) try_at(k, onset_s);
  }
  fit.onset_s = best.onset_s;
  fit.estimate = best.estimate;
  fit.std_error = best.std_error;
  fit.statistic = std::max(fit.statistic, best.statistic);
  return tried;
}

// The onset's posterior under flat priors on the onset and the magnitude
// (header), on the onsets tried: each holds the likelihood integrated over
// the magnitude, ∝ e^{T/2} I^{−1/2}, spread evenly over its cell, from
// halfway to the onset tried before it to halfway to the one after. The
// cells weigh by their width (the prior is flat in time), so the update
// epochs' starts and the samples and fractions of a sample tried about the
// placed onset make one distribution: an onset the run places within a
// sample gets an interval that wide, not an epoch's start twice.
struct OnsetPosterior {
  double std_s = 0.0;
  double low_s = 0.0, high_s = 0.0;  // the central interval, `tail` outside it on each side
};

OnsetPosterior SummariseOnsetPosterior(std::vector<OnsetTrial> trials, double tail) {
  std::ranges::sort(trials, {}, &OnsetTrial::onset_s);
  const size_t n = trials.size();
  if (n == 0) return {};
  if (n == 1) return {0.0, trials[0].onset_s, trials[0].onset_s};
  std::vector<double> edge(n + 1);
  for (size_t i = 1; i < n; ++i) edge[i] = 0.5 * (trials[i - 1].onset_s + trials[i].onset_s);
  edge[0] = 2.0 * trials[0].onset_s - edge[1];
  edge[n] = 2.0 * trials[n - 1].onset_s - edge[n - 1];
  std::vector<double> mass(n, 0.0);
  double peak_log = -INFINITY;
  for (size_t i = 0; i < n; ++i) {
    const double width_s = edge[i + 1] - edge[i];
    mass[i] = width_s > 0.0 ? 0.5 * trials[i].statistic + std::log(trials[i].std_error * width_s)
                            : -INFINITY;
    peak_log = std::max(peak_log, mass[i]);
  }
  double total = 0.0, mean_s = 0.0, square_s2 = 0.0;
  for (size_t i = 0; i < n; ++i) {
    mass[i] = std::exp(mass[i] - peak_log);
    const double a = edge[i], b = edge[i + 1];  // uniform on [a, b]
    total += mass[i];
    mean_s += mass[i] * 0.5 * (a + b);
    square_s2 += mass[i] * (a * a + a * b + b * b) / 3.0;
  }
  mean_s /= total;
  square_s2 /= total;
  auto quantile = [&](double q) {
    double cumulative = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const double share = mass[i] / total;
      if (cumulative + share >= q && share > 0.0) {
        return edge[i] + (q - cumulative) / share * (edge[i + 1] - edge[i]);
      }
      cumulative += share;
    }
    return edge[n];
  };
  return {std::sqrt(std::max(0.0, square_s2 - mean_s * mean_s)), quantile(tail),
          quantile(1.0 - tail)};
}

// The statistic profile of one term over the onsets, and its best onset.
OnsetFit FitTerm(const EffectTerm& term, const OnsetSums& sums, const EpochRun& run, int first,
                 int last, double centre_s, const OnsetScanOptions& options) {
  OnsetFit fit;
  fit.term = term;
  const int axis = SensorAxisIndex(term.family->sensor, term.axis);
  auto direction = [&](int theta) { return PairDirection(term, run, theta, centre_s); };
  struct AxisPair {
    Eigen::Vector2d score;
    Eigen::Matrix2d information;
    const Eigen::Matrix2d& successive;
  };
  auto pair = [&](int theta) {
    const auto at = static_cast<size_t>(theta);
    return AxisPair{sums.score[at].segment<2>(2 * axis),
                    sums.information[at].block<2, 2>(2 * axis, 2 * axis),
                    sums.successive[at][static_cast<size_t>(axis)]};
  };
  const int K = run.size();
  fit.estimate_by_epoch.assign(static_cast<size_t>(K), 0.0);
  fit.std_error_by_epoch.assign(static_cast<size_t>(K), 0.0);
  for (int theta = 0; theta < K; ++theta) {
    const Eigen::Vector2d v = direction(theta);
    const double info = v.dot(pair(theta).information * v);
    if (!(info > 0.0) || !std::isfinite(info)) continue;
    fit.estimate_by_epoch[static_cast<size_t>(theta)] = v.dot(pair(theta).score) / info;
    fit.std_error_by_epoch[static_cast<size_t>(theta)] = 1.0 / std::sqrt(info);
  }
  // A run too short for both sides of any onset has no candidate (last < first).
  std::vector<double> T(static_cast<size_t>(std::max(0, last - first + 1)), 0.0);
  fit.identifiable = last >= first;
  fit.first_onset_epoch = first;
  for (int theta = first; theta <= last; ++theta) {
    const Eigen::Vector2d v = direction(theta);
    const double s = v.dot(pair(theta).score);
    const double info = v.dot(pair(theta).information * v);
    if (!(info > 0.0) || !std::isfinite(info)) {
      fit.identifiable = false;
      break;
    }
    const double t = s * s / info;
    T[static_cast<size_t>(theta - first)] = t;
    if (theta < last) {
      const Eigen::Vector2d w = direction(theta + 1);
      const double next_info = w.dot(pair(theta + 1).information * w);
      const double rho = v.dot(pair(theta).successive * w) / std::sqrt(info * next_info);
      fit.path_length += std::acos(std::clamp(rho, -1.0, 1.0));
    }
    if (t > fit.statistic || fit.onset_epoch < 0) {
      fit.statistic = t;
      fit.onset_epoch = theta;
      fit.estimate = s / info;
      fit.std_error = 1.0 / std::sqrt(info);
    }
  }
  fit.onsets_tried = std::max(0, last - first + 1);
  if (!fit.identifiable || fit.onset_epoch < 0) {
    fit.identifiable = false;
    fit.statistic = 0.0;
    fit.p_value = 1.0;
    return fit;
  }
  // The onset's posterior under a flat prior on onset and magnitude: the
  // likelihood integrated over the magnitude, ∝ e^{T/2} I^{−1/2}. The onset
  // is placed within a sample about its median epoch, and its spread and
  // interval come from the epochs and the onsets tried there: a step where
  // the run cannot place it (a still stretch that hides the axis) spreads it.
  std::vector<OnsetTrial> trials;
  trials.reserve(T.size());
  std::vector<double> weight(T.size());
  double total = 0.0;
  for (int theta = first; theta <= last; ++theta) {
    const auto j = static_cast<size_t>(theta - first);
    const Eigen::Vector2d v = direction(theta);
    const double info = v.dot(pair(theta).information * v);
    trials.push_back({run.epochs[static_cast<size_t>(theta)].start_s, T[j],
                      v.dot(pair(theta).score) / info, 1.0 / std::sqrt(info)});
    weight[j] = std::exp(0.5 * (T[j] - fit.statistic)) * trials.back().std_error / fit.std_error;
    total += weight[j];
  }
  double cumulative = 0.0;
  fit.onset_epoch = last;
  for (int theta = first; theta <= last; ++theta) {
    cumulative += weight[static_cast<size_t>(theta - first)] / total;
    if (cumulative >= 0.5) {
      fit.onset_epoch = theta;
      break;
    }
  }
  const Eigen::Vector2d v = direction(fit.onset_epoch);
  const double info = v.dot(pair(fit.onset_epoch).information * v);
  fit.estimate = v.dot(pair(fit.onset_epoch).score) / info;
  fit.std_error = 1.0 / std::sqrt(info);
  fit.onset_s = run.epochs[static_cast<size_t>(fit.onset_epoch)].start_s;
  const std::vector<OnsetTrial> within = PlaceOnsetAtItsSample(sums, run, first, centre_s, fit);
  trials.insert(trials.end(), within.begin(), within.end());
  const OnsetPosterior posterior =
      SummariseOnsetPosterior(std::move(trials), options.interval_tail);
  fit.onset_std_s = posterior.std_s;
  fit.onset_low_s = std::min(posterior.low_s, fit.onset_s);
  fit.onset_high_s = std::max(posterior.high_s, fit.onset_s);
  fit.p_value = OnsetPValue(fit.statistic, fit.path_length);
  fit.statistic_by_onset = std::move(T);
  return fit;
}

// Each identifiable fault names the others whose signature from its onset
// is nearly parallel to its own (header).
void NameAmbiguousFaults(const OnsetSums& sums, const EpochRun& run, double centre_s,
                         const OnsetScanOptions& options, std::vector<OnsetFit>& fits) {
  for (OnsetFit& a : fits) {
    if (!a.identifiable) continue;
    const MatrixCc& I = sums.information[static_cast<size_t>(a.onset_epoch)];
    const auto ea = ColumnDirection(a.term, run, a.onset_epoch, centre_s);
    const double aa = ea.dot(I * ea);
    for (const OnsetFit& b : fits) {
      if (&a == &b || !b.identifiable) continue;
      const auto eb = ColumnDirection(b.term, run, a.onset_epoch, centre_s);
      const double bb = eb.dot(I * eb);
      if (!(aa > 0.0 && bb > 0.0)) continue;
      if (std::abs(ea.dot(I * eb)) / std::sqrt(aa * bb) >= options.ambiguity_threshold) {
        a.ambiguous_with.push_back(b.term);
      }
    }
  }
}

// The peak attitude error (header) of each fit that could be a finding: A_k = Φ_k L_{k−1}
// A_{k−1} + W_k forward from the start, one column per fit, W_k the fit's
// column at its placed onset (zero before it).
void SetPeakAttitudeErrors(const ForwardPass& fw, const StateLayout& layout, const EpochRun& run,
                           double family_wise_alpha, std::vector<OnsetFit>& fits) {
  std::vector<size_t> swept;
  for (size_t j = 0; j < fits.size(); ++j) {
    if (fits[j].identifiable && fits[j].p_value <= family_wise_alpha) swept.push_back(j);  // α = 1: every fit
  }
  if (swept.empty()) return;
  const int K = fw.epochs();
  const int n = fw.state_size;
  const auto m = static_cast<Eigen::Index>(swept.size());
  const auto rows = ObservationRows(layout);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, m), updated(n, m), P(n, n), H(kChannelCount, n),
                  L(n, n);
  Eigen::VectorXd PH(n), gain(n), peak = Eigen::VectorXd::Zero(m);
  for (int k = 0; k < K; ++k) {
    const auto at = static_cast<size_t>(k);
    fw.transitions[at].PropagateRows(A);
    for (Eigen::Index j = 0; j < m; ++j) {
      const EffectTerm& term = fits[swept[static_cast<size_t>(j)]].term;
      A.col(j).head<kNavigationStates>() +=
          FaultColumn(run.epochs[at], SensorAxisIndex(term.family->sensor, term.axis),
                      term.family->regressor, fits[swept[static_cast<size_t>(j)]].onset_s);
    }
    peak = peak.cwiseMax(A.middleRows<3>(layout.attitude()).colwise().norm().transpose());
    UpdateSequence(fw, k, rows, P, PH, gain, H, L);
    updated.noalias() = L * A;
    A.swap(updated);
  }
  for (Eigen::Index j = 0; j < m; ++j) {
    OnsetFit& fit = fits[swept[static_cast<size_t>(j)]];
    fit.peak_attitude_error_rad = std::abs(fit.estimate) * peak[j];
  }
}

}  // namespace

namespace {

// The index into the fit's per-onset vectors of the first update interval
// that starts at or after `onset_s`, where the scan tried one.
std::optional<size_t> TriedOnsetAt(const OnsetFit& fit, const EpochRun& run, double onset_s) {
  const auto first_after = std::ranges::find_if(
      run.epochs, [&](const EpochInterval& e) { return e.start_s >= onset_s; });
  const auto theta = static_cast<int>(first_after - run.epochs.begin()) - fit.first_onset_epoch;
  if (!fit.identifiable || theta < 0 || theta >= static_cast<int>(fit.statistic_by_onset.size())) {
    return std::nullopt;
  }
  return static_cast<size_t>(theta);
}

}  // namespace

std::optional<double> StatisticWithOnsetAt(const OnsetFit& fit, const EpochRun& run,
                                           double onset_s) {
  const auto j = TriedOnsetAt(fit, run, onset_s);
  if (!j.has_value()) return std::nullopt;
  return fit.statistic_by_onset[*j];
}

std::optional<EstimateAtOnset> EstimateNearOnset(const OnsetFit& fit, const EpochRun& run, double onset_s,
                                                 double tolerance_s) {
  std::optional<EstimateAtOnset> nearest;
  for (size_t k = 0; k < fit.estimate_by_epoch.size() && k < run.epochs.size(); ++k) {
    const double start_s = run.epochs[k].start_s;
    if (!(fit.std_error_by_epoch[k] > 0.0) || std::abs(start_s - onset_s) > tolerance_s) continue;
    if (!nearest.has_value() || std::abs(start_s - onset_s) < std::abs(nearest->onset_s - onset_s))
      nearest = EstimateAtOnset{start_s, fit.estimate_by_epoch[k], fit.std_error_by_epoch[k]};
  }
  return nearest;
}

double OnsetPValue(double statistic, double path_length) {
  return std::min(1.0, stats::ChiSquareSurvival(statistic, 1) + path_length * std::exp(-0.5 * statistic) / std::numbers::pi);
}

std::vector<EffectTerm> AbsentFaultTerms(const ErrorModel& model) {
  std::vector<EffectTerm> out;
  for (const EffectTerm& term : AllCatalogueTerms()) {
    if (term.family->kind == EffectKind::kFault && model.FindEffect(term) < 0) out.push_back(term);
  }
  return out;
}

std::vector<OnsetFit> ScanOnsets(const ForwardPass& fw, const StateLayout& layout, const EpochRun& run,
                                 const std::vector<EffectTerm>& terms, const OnsetScanOptions& options) {
  std::vector<OnsetFit> out;
  const int K = fw.epochs();
  if (terms.empty() || K < 2 || run.size() != K) return out;
  const double begin_s = run.epochs.front().start_s;
  const double end_s = run.epochs.back().time_s;
  int first = 0, last = K - 1;
  while (first < K && run.epochs[static_cast<size_t>(first)].start_s < begin_s + options.min_side_s) ++first;
  while (last >= 0 && run.epochs[static_cast<size_t>(last)].start_s > end_s - options.min_side_s) --last;
  const double centre_s = 0.5 * (begin_s + end_s);
  const OnsetSums sums = BackwardSweep(fw, layout, run, centre_s);
  for (const EffectTerm& term : terms) out.push_back(FitTerm(term, sums, run, first, last, centre_s, options));
  NameAmbiguousFaults(sums, run, centre_s, options, out);
  SetPeakAttitudeErrors(fw, layout, run, options.family_wise_alpha, out);
  return out;
}

}  // namespace insdiag::engine
