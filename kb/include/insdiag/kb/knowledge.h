// The knowledge base's own terms for what the diagnosis reads and makes: a
// unit type's nominal values, its failure modes and their signatures, the
// diagnosis's constants, and the diagnosis itself (docs/DIAGNOSIS.md); and
// the fleet's units and their modules. Plain values: the diagnosis's math
// (kb/diagnosis.h) works on these, and the API's messages are mapped to and
// from them at kb's edge
// (kb/messages/include/insdiag/kb/knowledge_messages.h; units and modules
// in server/src/knowledge_codec.h).
#pragma once

#include <absl/time/time.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace insdiag::kb {

// The scale an evidence term and a signature term are measured on.
//   kLogRatio   ln(identified / nominal), for positive quantities (σ, τ, ARW, VRW)
//   kTolerance  (identified − nominal) / tolerance, for the rest
//   kZ          estimate / standard error, for effects without a tolerance
enum class Scale { kLogRatio, kTolerance, kZ };

// The scale's name as the catalogue and the database write it
// ("log_ratio"), and the scale of such a name (nullopt for another).
const char* ScaleName(Scale scale);
std::optional<Scale> ScaleNamed(std::string_view name);

// A nominal value of a unit type's parameter, with its tolerance:
// |identified − value| ≤ tolerance is in specification.
struct NominalParameter {
  std::string name;  // "gyro_bias_gm.x.sigma"
  double value = 0.0;
  double tolerance = 0.0;
  std::string unit;
};

struct UnitType {
  std::string name;  // unitTypes/{unit_type}
  std::string display_name;
  std::vector<NominalParameter> nominal;
  std::string description;
};

// A unit of the fleet, registered by its first run.
struct Unit {
  std::string name;       // units/{serial}
  std::string unit_type;  // unitTypes/{unit_type}; empty when the unit's runs never named one
  double operating_hours = 0.0;
  absl::Time create_time;
  std::string batch;  // production batch, e.g. "2023Q2"
  std::optional<absl::Time> commission_time;
  bool retired = false;  // withdrawn from service (its modules are censored there)
};

// A replaceable part of a unit in one role, from installation to removal.
struct Module {
  std::string name;  // units/{unit}/modules/{role}
  std::string role;  // gyro.x … acc.z, interface_card, control_card, coupler, power_supply
  std::string part_serial;
  absl::Time installed_time;
  double installed_hours = 0.0;  // the unit's operating hours at installation
  std::optional<absl::Time> removed_time;  // none: still installed
  double removed_hours = 0.0;
  std::string removal_reason;
  bool current = false;  // the part in the role now
};

// Which way a failure moves a signature term.
enum class Direction { kUp, kDown, kEither };

// The direction's name as the catalogue and the database write it ("UP"),
// and the direction of such a name (nullopt for another).
const char* DirectionName(Direction direction);
std::optional<Direction> DirectionNamed(std::string_view name);

// How a failure shows in the evidence: which term moves, which way and how
// far (change and spread in `scale` units, across failed units).
struct Signature {
  // A term ("gyro_bias_gm.x.sigma") or a family over all axes ("gyro_scale_factor.*").
  std::string parameter;
  Direction direction = Direction::kEither;
  double change = 0.0;
  double spread = 0.0;
  Scale scale = Scale::kTolerance;
  bool common = false;     // a family whose axes move together (one shared shift)
  double fraction = 1.0;   // a family's share of terms expected to move
  // The expert's values, before confirmed cases refined change and spread.
  double expert_change = 0.0;
  double expert_spread = 0.0;
  int confirmed_cases = 0;
};

struct FailureMode {
  std::string name;  // failureModes/{failure_mode}
  std::string module_role;
  std::string description;
  std::vector<Signature> signature;
  std::string display_name;
  std::string unit_type;  // unitTypes/{unit_type}
  double expert_rate_per_million_hours = 0.0;  // floors the prior
  double rate_per_million_hours = 0.0;         // the prior's rate now, blended with the fleet's failures
  std::int64_t confirmed_failures = 0;
  double weibull_shape = 0.0;                  // the life the fleet generator draws from
  double weibull_scale_hours = 0.0;
};

// The diagnosis's constants for one unit type (the fields are explained in
// proto/insdiag/v1/knowledge.proto, DiagnosisSettings, and docs/DIAGNOSIS.md).
struct DiagnosisSettings {
  double healthy_tolerance_sd = 0.0;
  double healthy_log_ratio_fraction = 0.0;
  double healthy_z_sd = 0.0;
  double contamination = 0.0;
  double broad_log_ratio = 0.0;
  double broad_tolerance = 0.0;
  double broad_z = 0.0;
  double unknown_prior = 0.0;
  double minimum_exposure_hours = 0.0;
  double expert_pseudo_hours = 0.0;
  double expert_signature_weight = 0.0;
  double significance_level = 0.0;
  double incidental_contamination = 0.0;
  double trend_z_change = 0.0;
  double trend_z_spread = 0.0;
  int present_score_octaves = 0;
};

// A unit type's diagnosis constants, as its failure-mode catalogue gives them.
struct UnitTypeDiagnosisSettings {
  std::string unit_type;  // unitTypes/{unit_type} or its display name
  DiagnosisSettings settings;
};

// One observed quantity of a diagnosis's evidence, as the diagnosis keeps it.
struct EvidenceItem {
  std::string name;
  Scale scale = Scale::kTolerance;
  double value = 0.0;           // the observed change, in scale units
  double measurement_sd = 0.0;
  double healthy_sd = 0.0;
  bool significant = false;
};

// A module (or `healthy`, `unknown`) with its probability summed over its modes.
struct Candidate {
  std::string module;
  std::string failure_mode;  // the module's most probable mode
  double probability = 0.0;
  std::vector<std::string> evidence;  // human-readable lines
};

// One hypothesis: a failure mode, `healthy` or `unknown`.
struct Hypothesis {
  std::string failure_mode;
  std::string module;
  double prior = 0.0;
  double log_likelihood = 0.0;
  double probability = 0.0;
};

// A diagnosis as the math makes it; the store names it and keeps it.
struct Diagnosis {
  std::string analysis;  // analyses/{analysis}
  std::string unit;      // units/{serial}
  std::vector<Candidate> candidates;    // most probable first
  std::vector<Hypothesis> hypotheses;   // most probable first
  std::vector<std::string> notes;
  std::vector<EvidenceItem> evidence;
};

}  // namespace insdiag::kb
