// Ranking the missing effects from one score-test pass (score_test.h).
//
// Per term (one or two parameters p): LM = s_tᵀ 𝓘_t⁻¹ s_t ~ χ²(p) without the
// effect; β̂ = 𝓘_t⁻¹ s_t, Cov β̂ = 𝓘_t⁻¹ from the noise (a yaw harmonic's
// magnitude √(a²+b²) by the delta method). Per family: the joint test of its terms, LM =
// s_Fᵀ 𝓘_F⁺ s_F ~ χ²(rank 𝓘_F). p-values are adjusted over all candidates by
// Holm's step-down method (family-wise error). Adding an effect changes AIC by
// −LM + 2p and BIC by −LM + p ln N (LM is the likelihood ratio, score_test.h).
// Two candidates whose innovation signatures are nearly parallel in the
// S⁻¹ metric, |𝓘_ij|/√(𝓘_ii 𝓘_jj) above a threshold, cannot be told apart by
// this run and are named together.
//
// A term is identifiable only when the run excites it — rotation about the
// axes it needs, tilts that change the specific force it needs, temperature
// change — and its information is non-singular; otherwise it is reported as
// not identifiable with this profile, never as absent.
//
// Nor is a term whose one-step estimate is far outside the filter's linear
// range (linear_range.h): under the estimate the filter's attitude error
// peaks at ψ = |β̂| · max|A_ψ| (score_test.h), and beyond ψ = 1 rad the
// estimate is an artefact, reported so and not ranked. Within it the test
// counts the first-order error ψ/2 · |β̂| beside the noise: Cov β̂ =
// 𝓘_t⁻¹ + diag((ψ/2 · β̂)²) for the p-value and the SE, while LM, ΔAIC and
// ΔBIC stay the linear model's.
//
// Nor is a constant bias whose estimate the still segments' raw samples
// refute (raw_sample_evidence.h): they measure it with no navigation model.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/filter/forward_filter.h"
#include "insdiag/engine/finder/raw_sample_evidence.h"
#include "insdiag/engine/finder/score_test.h"
#include "insdiag/engine/report.h"

namespace insdiag::engine {

// What the table did to the unit, for the excitation checks: read from the
// reference attitude, the table's motion, not from the sensors, whose
// turn-on biases and noise would pass for motion on a unit at rest.
struct RunExcitation {
  Eigen::Vector3d turned_rad = Eigen::Vector3d::Zero();  // Σ|rotation w.r.t. the local level frame| per body axis
  Eigen::Vector3d force_range_mps2 = Eigen::Vector3d::Zero();  // max − min of gravity's component f_i over the run
  double temperature_range_degc = 0.0;
  double yaw_span_rad = 0.0;  // range of the reference yaw covered (≤ 2π)
};

struct ExcitationThresholds {
  double turned_rad = 2.0 * 3.141592653589793;  // one full turn's worth about the axis
  double force_range_g = 0.5;                   // half a g of change in that axis' specific force
  double temperature_range_degc = 1.0;
  double yaw_span_rad = 3.141592653589793;      // half a turn of table yaw
};

RunExcitation MeasureExcitation(const BenchRun& run);
bool Excites(const RunExcitation& e, const EffectTerm& term, const ExcitationThresholds& t, double gravity_mps2,
             std::string* why);

struct FinderOptions {
  double family_wise_alpha = 0.01;
  double ambiguity_threshold = 0.9;  // |cos| of two signatures named together
  int top_candidates_with_segments = 10;
  int segments_per_candidate = 5;
  ExcitationThresholds excitation;
};

struct RankedEffects {
  std::vector<EffectCandidate> terms;     // most significant first
  std::vector<EffectCandidate> families;  // most significant first
};

// `motion`: the table's motion label per score segment ("still", "turning",
// "tilting"). `raw_constants`: the still segments' constant biases that
// measure what this model's candidates would (raw_sample_evidence.h); a
// constant-bias term they refute is not ranked.
RankedEffects RankMissingEffects(const ScoreTestObserver& scan, const ForwardPass& forward,
                                 const BenchRun& run, const std::vector<std::string>& motion,
                                 const FinderOptions& options,
                                 std::span<const RawSampleConstant> raw_constants = {});

// Labels the run's score segments of `segment_epochs` epochs by the table's motion.
std::vector<std::string> SegmentMotion(const BenchRun& run, const ForwardPass& forward, int segment_epochs);

}  // namespace insdiag::engine
