// The diagnosis's one-dimensional densities in log form (docs/DIAGNOSIS.md).
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "insdiag/kb/diagnosis.h"

namespace insdiag::kb::internal {

inline double LogNormalPdf(double x, double mean, double variance) {
  const double d = x - mean;
  return -0.5 * (std::log(2.0 * std::numbers::pi * variance) + d * d / variance);
}

inline double LogCauchyPdf(double x, double scale) {
  return -std::log(std::numbers::pi * scale * (1.0 + (x / scale) * (x / scale)));
}

// log(e^a + e^b) without overflow.
inline double LogAddExp(double a, double b) {
  if (a == -INFINITY) return b;
  if (b == -INFINITY) return a;
  const double m = std::max(a, b);
  return m + std::log(std::exp(a - m) + std::exp(b - m));
}

// A healthy unit's variance of a term: its scatter and its measurement's,
// s_h² + s_m².
inline double HealthyVariance(const EvidenceTerm& t) {
  return t.healthy_sd * t.healthy_sd + t.measurement_sd * t.measurement_sd;
}

// The signs of the change a signature term's direction allows.
inline std::vector<double> SignsOf(Direction d) {
  if (d == Direction::kUp) return {1.0};
  if (d == Direction::kDown) return {-1.0};
  return {1.0, -1.0};
}

// The broad density's scale b of a term's scale: where evidence that is off
// for a reason no hypothesis names may lie.
inline double BroadScale(Scale scale, const DiagnosisSettings& s) {
  switch (scale) {
    case Scale::kLogRatio: return s.broad_log_ratio;
    case Scale::kTolerance: return s.broad_tolerance;
    case Scale::kZ: return s.broad_z;
  }
  return s.broad_z;
}

// The broad density of a term: Cauchy(x; 0, √(b² + s_m²)).
inline double LogBroad(const EvidenceTerm& t, const DiagnosisSettings& s) {
  const double b = BroadScale(t.scale, s);
  return LogCauchyPdf(t.x, std::sqrt(b * b + t.measurement_sd * t.measurement_sd));
}

}  // namespace insdiag::kb::internal
