// The largest drift each sensor axis's raw samples allow.
//
// Why. The innovations see a drift only through what it does to the
// navigation solution. A drift the table's motion leaves all but
// unobservable (a level unit's heading gyro on a still table) has a nearly
// flat likelihood, and EM carries it wherever it absorbs a misfit elsewhere:
// through Earth rate, a z gyro drift of σ 0.018 rad/s and τ 44,000 s (370
// times the unit's σ) took in a y gyro ramp, and the ramp was named as an x
// step. The raw samples see every drift directly. A first-order Gauss–Markov
// drift (σ, τ) adds σ² g(T/τ) to its channel's Allan variance at cluster
// time T (g(u) = (2u − 3 + 4e^{−u} − e^{−2u})/u², IEEE Std 952-1997 Annex C;
// allan.h's Markov term), and every other noise only adds to it. A drift
// whose σ² g(T/τ) stands above the channel's measured Allan variance's upper
// confidence bound at some T is refuted by the samples, whatever the
// innovations prefer. So is a bias random walk of density K, whose Allan
// variance is K²T/3 (the same annex), and a second-order pair: its
// autocovariance σ₂² e^{−α|t|} cos βt is σ₂² Re e^{−λ|t|} with λ = α − iβ, a
// Gauss–Markov process's of complex rate, and the same integrals give its
// Allan variance σ₂² Re g(λT).
//
// What. Per drift axis, the points (T, upper bound of σ²(T)) of its
// channel's curve over the static segments (after their jumps and ramps are
// taken out: those are faults, not drift). Each bound is σ̂² ν/χ²_ν(α′), ν the
// point's equivalent degrees of freedom were its noise a rate random walk
// (NIST SP 1065 Table 5; the smallest of the model's noises, so the bound
// holds whatever the noise), α′ the family-wise α shared by Bonferroni over
// all six curves' points. A run
// without static segments has no points, and allows every drift.
#pragma once

#include <array>
#include <limits>
#include <vector>

#include "insdiag/engine/ident/allan.h"
#include "insdiag/engine/model/drift_axis.h"
#include "insdiag/engine/model/error_model.h"

namespace insdiag::engine::ident {

class DriftCeilings {
 public:
  struct Point {
    double cluster_time_s = 0.0;
    double allan_variance_bound = 0.0;  // [(rad/s)² | (m/s²)²]
  };
  // How far a drift stands above its axis's ceiling: the largest ratio of its
  // Allan variance to the bound over the points, and where. A ratio of at
  // most 1 is allowed.
  struct Excess {
    double ratio = 0.0;
    double cluster_time_s = 0.0;
  };

  DriftCeilings() = default;
  // From the run's Allan analysis, at `family_wise_alpha`.
  static DriftCeilings FromAllan(const AllanResult& allan, double family_wise_alpha);

  // Of the random terms `terms` on the axis's channel (a drift, with a
  // bias random walk as its rate random walk), or of a drift alone.
  Excess ExcessOf(DriftAxis drift, const AllanNoiseTerms& terms) const;
  Excess ExcessOf(DriftAxis drift, const GaussMarkov& value) const;
  // Of the terms with a second-order pair (σ₂, α, β) beside them.
  struct SecondOrderPair {
    double sigma = 0.0;
    double decay_rate_per_s = 0.0;
    double frequency_rad_s = 0.0;
  };
  Excess ExcessOf(DriftAxis drift, const AllanNoiseTerms& terms, const SecondOrderPair& pair) const;
  bool Allows(DriftAxis drift, const GaussMarkov& value) const;
  // The largest σ the samples allow a drift of correlation time `tau_s`
  // (infinite where the axis has no point).
  double LargestSigma(DriftAxis drift, double tau_s) const;
  // `value` where allowed, else its σ lowered to the ceiling at its τ.
  GaussMarkov Within(DriftAxis drift, const GaussMarkov& value) const;

  const std::vector<Point>& PointsOf(DriftAxis drift) const {
    return points_[static_cast<size_t>(drift.Index())];
  }
  void Add(DriftAxis drift, Point point) {
    points_[static_cast<size_t>(drift.Index())].push_back(point);
  }

 private:
  std::array<std::vector<Point>, DriftAxis::kCount> points_;
};

}  // namespace insdiag::engine::ident
