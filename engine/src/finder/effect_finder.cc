#include "insdiag/engine/finder/effect_finder.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <set>

#include "absl/strings/str_format.h"
#include "insdiag/engine/filter/linear_range.h"
#include "insdiag/engine/nav/rotation.h"
#include "insdiag/engine/nav/wgs84.h"
#include "insdiag/engine/stats/distributions.h"

namespace insdiag::engine {
namespace {

// A term's columns in the scan.
struct TermColumns {
  EffectTerm term;
  std::vector<Eigen::Index> columns;
};

std::vector<TermColumns> GroupByTerm(const std::vector<CandidateColumn>& cols) {
  std::vector<TermColumns> out;
  for (size_t i = 0; i < cols.size(); ++i) {
    if (out.empty() || !(out.back().term == cols[i].term)) out.push_back({cols[i].term, {}});
    out.back().columns.push_back(static_cast<Eigen::Index>(i));
  }
  return out;
}

Eigen::VectorXd Select(const Eigen::VectorXd& v, const std::vector<Eigen::Index>& idx) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(idx.size()));
  for (size_t i = 0; i < idx.size(); ++i) out[static_cast<Eigen::Index>(i)] = v[idx[i]];
  return out;
}

Eigen::MatrixXd Select(const Eigen::MatrixXd& m, const std::vector<Eigen::Index>& idx) {
  const auto n = static_cast<Eigen::Index>(idx.size());
  Eigen::MatrixXd out(n, n);
  for (Eigen::Index a = 0; a < n; ++a) {
    for (Eigen::Index b = 0; b < n; ++b) out(a, b) = m(idx[static_cast<size_t>(a)], idx[static_cast<size_t>(b)]);
  }
  return out;
}

// Eigenvalues below this share of the largest count as zero information.
constexpr double kRankTolerance = 1e-10;

// The score test of columns whose one-step estimate β̂ = 𝓘⁺s carries,
// besides its noise (covariance 𝓘⁺), the first-order model's error: up to
// ψ/2 of the estimate (linear_range.h), taken as an independent error
// e_j = relative_error_j |β̂_j| of each column. In the numerically non-zero
// eigen-directions V of 𝓘 (eigenvalues Λ): b = Vᵀβ̂, C = Λ⁻¹ + Vᵀ diag(e²) V,
// T = bᵀ C⁻¹ b, which is LM = sᵀ 𝓘⁺ s where e = 0. `covariance`, where
// given: V C Vᵀ, the estimate's covariance with both errors.
double StatisticWithLinearisationError(const Eigen::VectorXd& s, const Eigen::MatrixXd& I,
                                       const Eigen::VectorXd& relative_error, int* rank,
                                       Eigen::MatrixXd* covariance = nullptr) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(I);
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  const double top = lambda.size() > 0 ? lambda.maxCoeff() : 0.0;
  std::vector<Eigen::Index> kept;
  for (Eigen::Index i = 0; i < lambda.size(); ++i) {
    if (top > 0.0 && lambda[i] > kRankTolerance * top) kept.push_back(i);
  }
  *rank = static_cast<int>(kept.size());
  const auto r = static_cast<Eigen::Index>(kept.size());
  Eigen::MatrixXd V(I.rows(), r);
  Eigen::VectorXd inverse_lambda(r);
  for (Eigen::Index k = 0; k < r; ++k) {
    V.col(k) = eig.eigenvectors().col(kept[static_cast<size_t>(k)]);
    inverse_lambda[k] = 1.0 / lambda[kept[static_cast<size_t>(k)]];
  }
  const Eigen::VectorXd b = inverse_lambda.asDiagonal() * (V.transpose() * s);
  const Eigen::VectorXd error = relative_error.cwiseProduct((V * b).cwiseAbs());
  const Eigen::MatrixXd C = Eigen::MatrixXd(inverse_lambda.asDiagonal()) +
                            V.transpose() * error.cwiseAbs2().asDiagonal() * V;
  if (covariance != nullptr) *covariance = V * C * V.transpose();
  if (r == 0) return 0.0;
  return b.dot(C.ldlt().solve(b));
}

// The filter's peak attitude error under the estimate β̂ of a term's columns:
// |A_ψ β̂| bounded by Σ |β̂_k| max|A_ψ,k| (exact for one column).
double ImpliedPeakAttitudeError(const Eigen::VectorXd& beta, const Eigen::VectorXd& peak_sensitivity,
                                const std::vector<Eigen::Index>& columns) {
  double rad = 0.0;
  for (size_t k = 0; k < columns.size(); ++k) {
    rad += std::abs(beta[static_cast<Eigen::Index>(k)]) * peak_sensitivity[columns[k]];
  }
  return rad;
}


}  // namespace

RunExcitation MeasureExcitation(const BenchRun& run) {
  RunExcitation e;
  if (run.samples.size() < 2) return e;
  const double g = wgs84::NormalGravityMps2(run.metadata.site.latitude_rad, run.metadata.site.height_m);
  const Eigen::Vector3d gravity_ned(0.0, 0.0, g);
  std::array<double, 3> force_min{}, force_max{};
  force_min.fill(std::numeric_limits<double>::infinity());
  force_max.fill(-std::numeric_limits<double>::infinity());
  std::array<bool, 36> yaw_bins{};
  double t_min = run.samples.front().temp_degc, t_max = t_min;
  // Every tenth sample is plenty to see what the table and the oven did.
  constexpr size_t kStride = 10;
  Eigen::Matrix3d C_previous = nav::EulerToDcm(run.samples.front().ref_rpy_rad);
  for (size_t k = 0; k < run.samples.size(); k += kStride) {
    const ImuSample& s = run.samples[k];
    const Eigen::Matrix3d C_b_n = nav::EulerToDcm(s.ref_rpy_rad);
    // The table's rotation of the body w.r.t. the local level frame, in body
    // axes: the sensors' readings would count a turn-on bias or the noise of
    // a unit at rest as turning.
    const Eigen::Vector3d turn = nav::QuaternionToRotationVector(Eigen::Quaterniond(C_previous.transpose() * C_b_n));
    e.turned_rad += turn.cwiseAbs();
    C_previous = C_b_n;
    // The specific force the table's attitude gives a perfect unit: f = −C_n^b g^n.
    const Eigen::Vector3d force = -C_b_n.transpose() * gravity_ned;
    for (int i = 0; i < 3; ++i) {
      force_min[static_cast<size_t>(i)] = std::min(force_min[static_cast<size_t>(i)], force[i]);
      force_max[static_cast<size_t>(i)] = std::max(force_max[static_cast<size_t>(i)], force[i]);
    }
    const double yaw = std::remainder(s.ref_rpy_rad.z(), 2.0 * std::numbers::pi) + std::numbers::pi;
    yaw_bins[std::min<size_t>(35, static_cast<size_t>(yaw / (2.0 * std::numbers::pi) * 36.0))] = true;
    t_min = std::min(t_min, s.temp_degc);
    t_max = std::max(t_max, s.temp_degc);
  }
  for (int i = 0; i < 3; ++i) e.force_range_mps2[i] = force_max[static_cast<size_t>(i)] - force_min[static_cast<size_t>(i)];
  e.temperature_range_degc = run.has_temperature ? t_max - t_min : 0.0;
  e.yaw_span_rad = 2.0 * std::numbers::pi * static_cast<double>(std::count(yaw_bins.begin(), yaw_bins.end(), true)) / 36.0;
  return e;
}

bool Excites(const RunExcitation& e, const EffectTerm& term, const ExcitationThresholds& t, double g,
             std::string* why) {
  const char axes[] = "xyz";
  auto need_turn = [&](int axis) {
    if (e.turned_rad[axis] >= t.turned_rad) return true;
    *why = std::string("the run does not turn the unit about its ") + axes[axis] + " axis";
    return false;
  };
  auto need_force = [&](int axis) {
    if (e.force_range_mps2[axis] >= t.force_range_g * g) return true;
    *why = std::string("the run's tilts do not change the specific force along ") + axes[axis];
    return false;
  };
  switch (term.family->regressor) {
    case Regressor::kOne:
    case Regressor::kStep:
    case Regressor::kRamp:
    case Regressor::kNone:
      return true;
    case Regressor::kOwnInput:
      return term.family->sensor == Sensor::kGyro ? need_turn(term.axis) : need_force(term.axis);
    case Regressor::kCrossInput:
      return term.family->sensor == Sensor::kGyro ? need_turn(term.source_axis) : need_force(term.source_axis);
    case Regressor::kSpecificForce:
      return need_force(term.source_axis);
    case Regressor::kTemperature:
      if (e.temperature_range_degc >= t.temperature_range_degc) return true;
      *why = "the run's temperature does not change (or the run has no temp column)";
      return false;
    case Regressor::kYawSinCos:
      if (e.yaw_span_rad >= t.yaw_span_rad) return true;
      *why = "the run does not turn the table through half a turn of yaw";
      return false;
  }
  return false;
}

std::vector<std::string> SegmentMotion(const BenchRun& run, const ForwardPass& fw, int segment_epochs) {
  std::vector<std::string> labels;
  const int K = fw.epochs();
  for (int first = 0; first < K; first += segment_epochs) {
    const int last = std::min(K, first + segment_epochs) - 1;
    const size_t s0 = first == 0 ? 0 : static_cast<size_t>(fw.epoch_sample[static_cast<size_t>(first - 1)]);
    const size_t s1 = static_cast<size_t>(fw.epoch_sample[static_cast<size_t>(last)]);
    double turned = 0.0;
    Eigen::Matrix3d previous = nav::EulerToDcm(run.samples[s0].ref_rpy_rad);
    for (size_t k = s0 + 1; k <= s1; ++k) {
      const Eigen::Matrix3d C = nav::EulerToDcm(run.samples[k].ref_rpy_rad);
      turned += Eigen::AngleAxisd(previous.transpose() * C).angle();
      previous = C;
    }
    constexpr double kStillRad = 0.5 * std::numbers::pi / 180.0;
    constexpr double kTurningRad = 0.5 * std::numbers::pi;
    labels.push_back(turned < kStillRad ? "still" : turned > kTurningRad ? "turning" : "tilting");
  }
  return labels;
}

namespace {

// One term's score test, before the ranking.
struct ScoredTerm {
  EffectCandidate candidate;
  Eigen::VectorXd beta;
  const TermColumns* columns = nullptr;
  // Not a finding, and left out of its family's joint test: its estimate is
  // far outside the linear range, or the raw samples refute it.
  bool left_out = false;
};

// What the run and the scan need to score a term.
struct ScanContext {
  const ScoreTestObserver& scan;
  const RunExcitation& excitation;
  double gravity_mps2;
  double log_updates;
  const FinderOptions& options;
  std::span<const RawSampleConstant> raw_constants;
};

// The term's one-step estimate and statistic, or why the run cannot test it;
// and whether its estimate is within the first-order model's range
// (docs/IDENTIFICATION.md, "The scan's linear range").
ScoredTerm ScoreTerm(const TermColumns& t, const ScanContext& context) {
  ScoredTerm sc;
  sc.columns = &t;
  EffectCandidate& c = sc.candidate;
  c.name = t.term.Name();
  c.family = std::string(t.term.family->name);
  c.source = "SCORE";
  c.unit = std::string(t.term.family->unit);
  c.dof = static_cast<int>(t.columns.size());
  std::string why;
  const Eigen::VectorXd st = Select(context.scan.score(), t.columns);
  const Eigen::MatrixXd It = Select(context.scan.information(), t.columns);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(It);
  const bool full_rank =
      eig.eigenvalues().minCoeff() > kRankTolerance * std::max(eig.eigenvalues().maxCoeff(), 0.0) &&
      eig.eigenvalues().minCoeff() > 0.0;
  c.identifiable =
      Excites(context.excitation, t.term, context.options.excitation, context.gravity_mps2, &why) &&
      full_rank;
  if (!c.identifiable) {
    if (why.empty()) why = "its signature vanishes in this run";
    c.std_error = std::numeric_limits<double>::infinity();
    c.p_value = c.p_value_holm = 1.0;
    c.note = "not identifiable with this profile: " + why;
    return sc;
  }
  const Eigen::MatrixXd noise_cov = It.inverse();
  sc.beta = noise_cov * st;
  const double attitude_error_rad =
      ImpliedPeakAttitudeError(sc.beta, context.scan.peak_attitude_sensitivity(), t.columns);
  // 2Δℓ is the linear model's; whether the term is a finding counts the
  // first-order model's error of β̂ beside its noise (linear_range.h).
  c.statistic = st.dot(sc.beta);
  Eigen::MatrixXd cov;
  int rank = 0;
  const double tested = StatisticWithLinearisationError(
      st, It, Eigen::VectorXd::Constant(c.dof, 0.5 * attitude_error_rad), &rank, &cov);
  c.p_value = stats::ChiSquareSurvival(tested, c.dof);
  double noise_std_error = 0.0;
  if (c.dof == 1) {
    c.estimate = sc.beta[0];
    c.std_error = std::sqrt(cov(0, 0));
    noise_std_error = std::sqrt(noise_cov(0, 0));
  } else {
    // Yaw harmonic magnitude √(a² + b²), delta method.
    const double mag = sc.beta.norm();
    c.estimate = mag;
    const Eigen::VectorXd grad = mag > 0.0 ? Eigen::VectorXd(sc.beta / mag)
                                           : Eigen::VectorXd::Ones(c.dof) / std::sqrt(c.dof);
    c.std_error = std::sqrt(grad.dot(cov * grad));
    noise_std_error = std::sqrt(grad.dot(noise_cov * grad));
  }
  c.predicted_delta_aic = -c.statistic + 2.0 * c.dof;
  c.predicted_delta_bic = -c.statistic + c.dof * context.log_updates;
  const double relative_std_error = noise_std_error / std::abs(c.estimate);
  const LinearRange range = LinearRangeOf(attitude_error_rad, relative_std_error);
  if (range == LinearRange::kFarOutside) {
    c.identifiable = false;
    sc.left_out = true;
  }
  if (range != LinearRange::kWithin)
    c.note = LinearRangeNote(range, attitude_error_rad, relative_std_error);
  if (std::string refuted;
      RefutedByRawSamples(t.term, c.estimate, c.std_error, context.raw_constants,
                          context.options.family_wise_alpha, &refuted)) {
    c.identifiable = false;
    sc.left_out = true;
    c.note = c.note.empty() ? refuted : c.note + "; " + refuted;
  }
  return sc;
}

// Holm over the identifiable terms, and the signatures too alike to tell
// apart in this run.
void AdjustAndNameLookAlikes(std::vector<ScoredTerm>& scored, const Eigen::MatrixXd& I,
                             double ambiguity_threshold) {
  std::vector<size_t> tested;
  std::vector<double> p;
  for (size_t i = 0; i < scored.size(); ++i) {
    if (!scored[i].candidate.identifiable) continue;
    tested.push_back(i);
    p.push_back(scored[i].candidate.p_value);
  }
  std::vector<double> adjusted(p.size());
  stats::HolmAdjust(p, adjusted);
  for (size_t j = 0; j < tested.size(); ++j) scored[tested[j]].candidate.p_value_holm = adjusted[j];
  for (size_t a = 0; a < tested.size(); ++a) {
    for (size_t b = 0; b < tested.size(); ++b) {
      if (a == b) continue;
      const TermColumns& ta = *scored[tested[a]].columns;
      const TermColumns& tb = *scored[tested[b]].columns;
      double best = 0.0;
      for (Eigen::Index i : ta.columns) {
        for (Eigen::Index j : tb.columns) best = std::max(best, std::abs(I(i, j)) / std::sqrt(I(i, i) * I(j, j)));
      }
      if (best >= ambiguity_threshold)
        scored[tested[a]].candidate.correlated_with.push_back(tb.term.Name());
    }
  }
}

// Where a candidate shows: its share of the score per channel and segment,
// the largest first.
std::vector<SegmentContribution> WhereItShows(const ScoredTerm& sc, const ScoreTestObserver& scan,
                                              const ForwardPass& fw,
                                              const std::vector<std::string>& motion,
                                              int segments_per_candidate) {
  const int E = scan.segment_epochs();
  const double interval = fw.epochs() > 1 ? (fw.epoch_time_s.back() - fw.epoch_time_s.front()) / (fw.epochs() - 1) : 1.0;
  std::vector<SegmentContribution> pieces;
  for (int c = 0; c < kChannelCount; ++c) {
    const Eigen::MatrixXd& by_segment = scan.score_by_segment()[static_cast<size_t>(c)];
    for (Eigen::Index segment = 0; segment < by_segment.cols(); ++segment) {
      double contribution = 0.0;
      for (size_t k = 0; k < sc.columns->columns.size(); ++k) {
        contribution +=
            by_segment(sc.columns->columns[k], segment) * sc.beta[static_cast<Eigen::Index>(k)];
      }
      const double share = contribution / sc.candidate.statistic;
      if (share <= 0.0) continue;
      const int first = static_cast<int>(segment) * E;
      const int last = std::min(fw.epochs(), first + E) - 1;
      pieces.push_back(
          {std::string(kChannelNames[static_cast<size_t>(c)]),
           fw.epoch_time_s[static_cast<size_t>(first)] - interval,
           fw.epoch_time_s[static_cast<size_t>(last)],
           static_cast<size_t>(segment) < motion.size() ? motion[static_cast<size_t>(segment)] : "",
           share});
    }
  }
  std::sort(pieces.begin(), pieces.end(),
            [](const auto& a, const auto& b) { return a.share > b.share; });
  if (static_cast<int>(pieces.size()) > segments_per_candidate)
    pieces.resize(static_cast<size_t>(segments_per_candidate));
  return pieces;
}

// Families: the joint test of their terms that the run excites and that are
// within the linear range, Holm-adjusted, most significant first.
// Each column's relative first-order error ψ/2 under the family's joint
// estimate, ψ that of the column's term (its own columns of the estimate).
Eigen::VectorXd FamilyLinearisationErrors(const Eigen::VectorXd& score,
                                          const Eigen::MatrixXd& information,
                                          const std::vector<const TermColumns*>& members,
                                          const ScanContext& context) {
  Eigen::VectorXd relative_error = Eigen::VectorXd::Zero(score.size());
  Eigen::MatrixXd pseudo_inverse;
  int rank = 0;
  StatisticWithLinearisationError(score, information, relative_error, &rank, &pseudo_inverse);
  const Eigen::VectorXd beta = pseudo_inverse * score;
  Eigen::Index offset = 0;
  for (const TermColumns* t : members) {
    const auto n = static_cast<Eigen::Index>(t->columns.size());
    const double attitude_error_rad = ImpliedPeakAttitudeError(
        beta.segment(offset, n), context.scan.peak_attitude_sensitivity(), t->columns);
    relative_error.segment(offset, n).setConstant(0.5 * attitude_error_rad);
    offset += n;
  }
  return relative_error;
}

std::vector<EffectCandidate> FamilyCandidates(const std::vector<TermColumns>& terms,
                                              const std::set<std::string>& left_out,
                                              const ScanContext& context) {
  std::map<std::string, std::vector<Eigen::Index>> family_columns;
  std::map<std::string, std::vector<const TermColumns*>> family_terms;
  std::vector<std::string> family_order;
  for (const TermColumns& t : terms) {
    std::string why;
    if (!Excites(context.excitation, t.term, context.options.excitation, context.gravity_mps2,
                 &why) ||
        left_out.count(t.term.Name())) {
      continue;
    }
    const std::string name(t.term.family->name);
    if (!family_columns.count(name)) family_order.push_back(name);
    auto& cols = family_columns[name];
    cols.insert(cols.end(), t.columns.begin(), t.columns.end());
    family_terms[name].push_back(&t);
  }
  std::vector<EffectCandidate> families;
  std::vector<double> family_p;
  for (const std::string& name : family_order) {
    const auto& cols = family_columns[name];
    EffectCandidate c;
    c.name = name;
    c.family = name;
    c.source = "SCORE";
    const Eigen::VectorXd score = Select(context.scan.score(), cols);
    const Eigen::MatrixXd information = Select(context.scan.information(), cols);
    const Eigen::VectorXd relative_error =
        FamilyLinearisationErrors(score, information, family_terms[name], context);
    c.statistic = StatisticWithLinearisationError(score, information,
                                                  Eigen::VectorXd::Zero(score.size()), &c.dof);
    const double tested =
        StatisticWithLinearisationError(score, information, relative_error, &c.dof);
    c.identifiable = c.dof > 0;
    c.p_value = c.dof > 0 ? stats::ChiSquareSurvival(tested, c.dof) : 1.0;
    c.predicted_delta_aic = -c.statistic + 2.0 * c.dof;
    c.predicted_delta_bic = -c.statistic + c.dof * context.log_updates;
    c.unit = std::string(FindEffectFamily(name)->unit);
    family_p.push_back(c.p_value);
    families.push_back(std::move(c));
  }
  std::vector<double> family_adjusted(family_p.size());
  stats::HolmAdjust(family_p, family_adjusted);
  for (size_t i = 0; i < families.size(); ++i) families[i].p_value_holm = family_adjusted[i];
  std::stable_sort(families.begin(), families.end(),
                   [](const EffectCandidate& a, const EffectCandidate& b) {
                     if (a.p_value_holm != b.p_value_holm) return a.p_value_holm < b.p_value_holm;
                     return a.statistic > b.statistic;
                   });
  return families;
}

}  // namespace

RankedEffects RankMissingEffects(const ScoreTestObserver& scan, const ForwardPass& fw,
                                 const BenchRun& run, const std::vector<std::string>& motion,
                                 const FinderOptions& options,
                                 std::span<const RawSampleConstant> raw_constants) {
  const RunExcitation excitation = MeasureExcitation(run);
  const ScanContext context{
      scan,
      excitation,
      wgs84::NormalGravityMps2(run.metadata.site.latitude_rad, run.metadata.site.height_m),
      std::log(static_cast<double>(std::max(1, fw.scalar_updates))),
      options,
      raw_constants};
  const std::vector<TermColumns> terms = GroupByTerm(scan.columns());
  std::vector<ScoredTerm> scored;
  std::set<std::string> left_out;
  for (const TermColumns& t : terms) {
    scored.push_back(ScoreTerm(t, context));
    if (scored.back().left_out) left_out.insert(scored.back().candidate.name);
  }
  AdjustAndNameLookAlikes(scored, scan.information(), options.ambiguity_threshold);
  std::stable_sort(scored.begin(), scored.end(), [](const ScoredTerm& a, const ScoredTerm& b) {
    if (a.candidate.identifiable != b.candidate.identifiable) return a.candidate.identifiable;
    if (a.candidate.p_value_holm != b.candidate.p_value_holm)
      return a.candidate.p_value_holm < b.candidate.p_value_holm;
    return a.candidate.statistic > b.candidate.statistic;
  });
  for (int rank = 0;
       rank < options.top_candidates_with_segments && rank < static_cast<int>(scored.size());
       ++rank) {
    ScoredTerm& sc = scored[static_cast<size_t>(rank)];
    if (!sc.candidate.identifiable || sc.candidate.statistic <= 0.0) continue;
    sc.candidate.where = WhereItShows(sc, scan, fw, motion, options.segments_per_candidate);
  }
  RankedEffects out;
  for (ScoredTerm& sc : scored) out.terms.push_back(std::move(sc.candidate));
  out.families = FamilyCandidates(terms, left_out, context);
  return out;
}

}  // namespace insdiag::engine
