#include "insdiag/engine/bench_run.h"

#include <absl/strings/numbers.h>

#include <algorithm>
#include <cmath>

#include "insdiag/engine/stats/robust.h"

namespace insdiag::engine {

std::optional<std::string> BenchRunMetadata::Extra(const std::string& key) const {
  for (const auto& [k, v] : extra) {
    if (k == key) return v;
  }
  return std::nullopt;
}

std::optional<bool> BenchRunMetadata::DeclaredAttitudeReadout() const {
  const auto readout = Extra(std::string(kReferenceAttitudeReadoutKey));
  if (!readout.has_value()) return std::nullopt;
  return *readout == kAttitudeReadByEncoders;
}

void BenchRunMetadata::DeclareAttitudeReadout(bool encoders_read) {
  const std::string value(encoders_read ? kAttitudeReadByEncoders : kAttitudeNotRead);
  for (auto& [k, v] : extra) {
    if (k == kReferenceAttitudeReadoutKey) {
      v = value;
      return;
    }
  }
  extra.emplace_back(std::string(kReferenceAttitudeReadoutKey), value);
}

StatedAttitudeAccuracy BenchRunMetadata::AttitudeAccuracy() const {
  StatedAttitudeAccuracy stated;
  const auto positive = [](const std::string& text) -> std::optional<double> {
    double value = 0.0;
    if (!absl::SimpleAtod(text, &value) || !std::isfinite(value) || value <= 0.0) return std::nullopt;
    return value;
  };
  if (const auto level = Extra(std::string(kReferenceLevelSigmaKey))) stated.level_sigma_rad = positive(*level);
  if (const auto heading = Extra(std::string(kReferenceHeadingSigmaKey))) {
    stated.heading_surveyed = *heading != kHeadingNotSurveyed;
    if (stated.heading_surveyed) stated.heading_sigma_rad = positive(*heading);
  }
  return stated;
}

bool BenchRun::ReferenceAttitudeIsRead() const {
  if (const auto declared = metadata.DeclaredAttitudeReadout(); declared.has_value()) return *declared;
  size_t segment_first = 0;
  for (size_t k = 1; k < samples.size(); ++k) {
    if (StartsSegment(k)) {
      segment_first = k;
    } else if (samples[k].ref_rpy_rad != samples[segment_first].ref_rpy_rad) {
      return true;
    }
  }
  return false;
}

double MedianSampleIntervalS(std::span<const ImuSample> samples) {
  if (samples.size() < 2) return 0.0;
  // The median is robust to the occasional late sample a logger produces.
  std::vector<double> dt;
  dt.reserve(samples.size() - 1);
  for (size_t k = 1; k < samples.size(); ++k) dt.push_back(samples[k].t_s - samples[k - 1].t_s);
  return stats::MedianInPlace(dt);
}

double BenchRun::NominalIntervalS() const { return MedianSampleIntervalS(samples); }

bool BenchRun::StartsSegment(size_t k) const {
  return std::binary_search(metadata.segment_starts.begin(), metadata.segment_starts.end(), k);
}

double BenchRun::DurationS() const {
  if (samples.empty()) return 0.0;
  // The first sample covers (t0 − Δt, t0]: a run of N samples lasts N·Δt.
  return samples.back().t_s - samples.front().t_s + NominalIntervalS();
}

}  // namespace insdiag::engine
