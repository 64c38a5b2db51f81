// What the analysis's stages after condensing share (engine/src/analysis.cc):
// the run as screened, its update epochs, what a perfect unit would have
// measured on it, the spikes repaired, the options and the a-priori model the
// identification starts from.
#pragma once

#include <array>
#include <string_view>
#include <vector>

#include "insdiag/engine/analysis.h"
#include "insdiag/engine/bench_run.h"
#include "insdiag/engine/filter/epoch_run.h"
#include "insdiag/engine/finder/fault_findings.h"
#include "insdiag/engine/ident/drift_likelihood.h"
#include "insdiag/engine/model/error_model.h"
#include "insdiag/engine/monitor/monitoring.h"
#include "insdiag/engine/monitor/sample_screening.h"

namespace insdiag::engine::pipeline {

// Where the a-priori model came from.
enum class APrioriSource {
  // The run's complete datasheet: the unit's own specification.
  kDatasheet,
  // The unit type's nominal model: a class prior drift identification
  // searches decades from.
  kNominal,
  // The run's own Allan fit: its drift τ is a bound or a guess of the static
  // segments, a placeholder the whole run re-tunes.
  kAllanFit,
};

// The a-priori model and where it came from.
struct APriori {
  ErrorModel model;
  APrioriSource source = APrioriSource::kNominal;
  bool FromDatasheet() const { return source == APrioriSource::kDatasheet; }
  bool FromAllanFit() const { return source == APrioriSource::kAllanFit; }
  // Where drift identification starts (a datasheet's drifts need no grid).
  ident::DriftStartOptions drift_starts;
  // Per sensor axis (DriftAxis::Index order), the remainder of the counter
  // its samples are read from, q/√12 (count_quantum.h); 0 where they are not
  // counts. The quantisation term never falls below it: it is read from the
  // samples, not a term the innovations are asked to support.
  std::array<double, DriftAxis::kCount> counted_quantisation{};
};

struct RunContext {
  const BenchRun& run;
  const EpochRun& epochs;
  // ReferenceMeasurements(run): the table's motion alone fixes it, so the
  // screening and every report share one computation.
  const std::vector<std::array<double, 6>>& reference_measurements;
  const SampleScreening& samples;
  const AnalysisOptions& options;
  const APriori& a_priori;
  // What the static segments' raw samples show, needing no navigation model
  // (finder/raw_sample_evidence.h): the jumps and ramps the Allan analysis
  // found, and each sensor axis' constant bias.
  const RawSampleEvidence& raw_samples;
  // The drifts those raw samples allow (ident/drift_ceiling.h): an estimate
  // of the innovations' likelihood beyond them is not the drift's.
  const ident::DriftCeilings& drift_ceilings;
};

inline void Progress(const AnalysisOptions& o, double fraction, std::string_view stage) {
  if (o.progress) o.progress(fraction, stage);
}

}  // namespace insdiag::engine::pipeline
