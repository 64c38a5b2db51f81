// The model of a fleet built from the data files: the unit type's nominal
// values and tolerances, its failure modes, the diagnosis settings and the
// fleet profile, with the options' overrides.
#include <absl/strings/match.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_split.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "generator.h"
#include "insdiag/api/resource_names.h"
#include "insdiag/engine/model/parameter_key.h"
#include "insdiag/engine/status_macros.h"
#include "insdiag/kb/diagnosis.h"
#include "insdiag/kb/catalogue_data.h"

namespace insdiag::kb::generator {
namespace {

bool GlobMatches(const std::string& pattern, const std::string& name) {
  const std::vector<std::string> p = absl::StrSplit(pattern, '.');
  const std::vector<std::string> n = absl::StrSplit(name, '.');
  if (p.size() != n.size()) return false;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p[i] != "*" && p[i] != n[i]) return false;
  }
  return true;
}

std::string FamilyOf(const std::string& name) {
  const std::optional<engine::ParameterKey> key = engine::ParseParameterKey(name);
  return key ? key->family : name;
}

std::string ModeId(const FailureMode& mode) { return api::IdOrSelf(mode.name, api::kFailureModes); }

// The unit type, its failure modes and diagnosis settings, and the fleet
// profile (the options' or the built-in one).
absl::Status LoadData(const FleetGeneratorOptions& options, Model& m) {
  INSDIAG_ASSIGN_OR_RETURN(UnitTypeCatalogue catalogue, BuiltinUnitTypeCatalogue(options.unit_type));
  m.unit_type = std::move(catalogue.unit_type);
  m.unit_type_id = api::IdOrSelf(m.unit_type.name, api::kUnitTypes);
  m.settings = catalogue.settings;
  m.modes = std::move(catalogue.failure_modes);
  if (options.profile) {
    m.profile = *options.profile;
  } else {
    auto profile = BuiltinFleetProfile(m.unit_type_id);
    if (!profile.ok()) return profile.status();
    m.profile = *profile;
  }
  return absl::OkStatus();
}

absl::Status ValidateProfile(const v1::FleetProfile& p, const std::string& unit_type_id) {
  if (p.history_years() <= 0 || p.batch_months() <= 0 || p.operating_hours_per_year() <= 0 ||
      p.test_interval_days() <= 0 || p.precursor_days() <= 0 || p.sample_rate_hz() <= 0 ||
      p.batch_variance_share() < 0 || p.measurement_variance_share() < 0 ||
      p.batch_variance_share() + p.measurement_variance_share() >= 1 || p.effect_std_error_tolerances() <= 0 ||
      p.operable_tolerances() < 1) {
    return absl::InvalidArgumentError(absl::StrCat("fleet profile of ", unit_type_id,
                                                   ": history, batches, usage, test interval, precursor window, "
                                                   "sample rate and effect error must be positive, the variance "
                                                   "shares below 1 together, operable tolerances at least 1"));
  }
  return absl::OkStatus();
}

// The measured terms: the identified parameters (nominal value > 0), the
// effects with a tolerance, and the effects without one that a signature
// scores (standard scores).
void AddTerms(Model& m) {
  const v1::FleetProfile& p = m.profile;
  for (const NominalParameter& n : m.unit_type.nominal) {
    if (n.value > 0) {
      // The engine identifies Gauss–Markov drifts by correlation processing,
      // noise densities by Allan variance.
      const char* method = absl::StrContains(n.name, "_gm.") ? "ACF" : "ALLAN";
      const double healthy_sd = m.settings.healthy_log_ratio_fraction * std::log1p(n.tolerance / n.value);
      IdentifiedTerm t{n.name, n.unit, method, n.value, n.tolerance, healthy_sd, -1, 0};
      for (int a = 0; a < p.ageing_size(); ++a) {
        if (GlobMatches(p.ageing(a).parameter(), n.name)) t.ageing = a;
      }
      m.identified.push_back(std::move(t));
    } else {
      m.effects.push_back({n.name, FamilyOf(n.name), n.unit, n.tolerance, 0.0});
    }
  }
  // Effects without a tolerance that a signature scores (standard scores).
  for (const auto& mode : m.modes) {
    for (const Signature& s : mode.signature) {
      if (s.scale != Scale::kZ || absl::EndsWith(s.parameter, ".*")) continue;
      const bool known = std::any_of(m.effects.begin(), m.effects.end(),
                                     [&](const EffectTerm& e) { return e.name == s.parameter; });
      const auto se = p.effect_std_errors().find(FamilyOf(s.parameter));
      if (known || se == p.effect_std_errors().end()) continue;
      m.effects.push_back({s.parameter, FamilyOf(s.parameter), "", 0.0, se->second});
    }
  }
}

// The measured terms a signature term moves: identified parameters for a
// log ratio, effects of the matching scale otherwise.
SignatureTargets TargetsOf(const Model& m, const Signature& s) {
  SignatureTargets targets;
  targets.term = s;
  if (s.scale == Scale::kLogRatio) {
    targets.kind = TermKind::kIdentified;
    for (std::size_t i = 0; i < m.identified.size(); ++i) {
      if (SignatureCovers(s.parameter, m.identified[i].name)) targets.members.push_back(static_cast<int>(i));
    }
  } else {
    targets.kind = TermKind::kEffect;
    for (std::size_t i = 0; i < m.effects.size(); ++i) {
      const bool scale_fits = (s.scale == Scale::kZ) == m.effects[i].scored();
      if (scale_fits && SignatureCovers(s.parameter, m.effects[i].name)) {
        targets.members.push_back(static_cast<int>(i));
      }
    }
  }
  return targets;
}

// Every failure mode's role, Weibull life, expert rate and measurable
// signature terms; a note for each term nothing measures.
absl::Status AddModeModels(Model& m) {
  for (const auto& mode : m.modes) {
    ModeModel mm;
    mm.id = ModeId(mode);
    const auto role = std::find(m.roles.begin(), m.roles.end(), mode.module_role);
    if (role == m.roles.end()) {
      return absl::FailedPreconditionError(absl::StrCat(mode.name, ": module role '", mode.module_role,
                                                        "' is not in the knowledge base's module_roles"));
    }
    mm.role = static_cast<int>(role - m.roles.begin());
    mm.shape = mode.weibull_shape;
    mm.scale_hours = mode.weibull_scale_hours;
    mm.expert_rate = mode.expert_rate_per_million_hours * 1e-6;
    for (const Signature& s : mode.signature) {
      SignatureTargets targets = TargetsOf(m, s);
      if (targets.members.empty()) {
        m.notes.push_back(absl::StrCat(mode.name, ": signature term ", s.parameter, " (", ScaleName(s.scale),
                                       ") has no measurable counterpart in ", m.unit_type.name,
                                       " and the fleet profile: its failures show no precursor there"));
        continue;
      }
      mm.terms.push_back(std::move(targets));
    }
    m.modes_of_role[static_cast<std::size_t>(mm.role)].push_back(static_cast<int>(m.mode_models.size()));
    m.role_weight[static_cast<std::size_t>(mm.role)] += mm.expert_rate;
    m.mode_models.push_back(std::move(mm));
  }
  return absl::OkStatus();
}

// The seed and what derives from it (serials, the ids' salt), the history's
// span and the fleet's usage.
void SetHistory(const FleetGeneratorOptions& options, Model& m) {
  const v1::FleetProfile& p = m.profile;
  m.seed = options.seed;
  m.run_format = options.run_format;
  m.serial_prefix = options.serial_prefix.empty() ? absl::StrCat("G", options.seed) : options.serial_prefix;
  {
    std::uint64_t state = options.seed ^ static_cast<std::uint64_t>(AdvisoryLockKey(m.serial_prefix));
    m.salt = static_cast<std::uint32_t>(SplitMix(state) >> 32);
  }
  m.end_us = options.end_time_micros;
  if (m.end_us == 0) {
    const auto now = std::chrono::duration_cast<std::chrono::microseconds>(
                         std::chrono::system_clock::now().time_since_epoch())
                         .count();
    m.end_us = now - now % kMicrosPerDay;
  }
  const double years = options.history_years > 0 ? options.history_years : p.history_years();
  m.start_us = m.end_us - static_cast<std::int64_t>(years * kMicrosPerYear);
  m.hours_per_year = options.operating_hours_per_year > 0 ? options.operating_hours_per_year
                                                          : p.operating_hours_per_year();
  m.precursor_us = static_cast<std::int64_t>(p.precursor_days() * static_cast<double>(kMicrosPerDay));
}

}  // namespace

absl::StatusOr<Model> BuildModel(const FleetGeneratorOptions& options, std::vector<std::string> roles) {
  Model m;
  INSDIAG_RETURN_IF_ERROR(LoadData(options, m));
  INSDIAG_RETURN_IF_ERROR(ValidateProfile(m.profile, m.unit_type_id));
  m.roles = std::move(roles);
  m.modes_of_role.assign(m.roles.size(), {});
  m.role_weight.assign(m.roles.size(), 0.0);
  AddTerms(m);
  INSDIAG_RETURN_IF_ERROR(AddModeModels(m));
  SetHistory(options, m);
  return m;
}

}  // namespace insdiag::kb::generator
