// The plan of the fleet, drawn before anything is written: every unit's
// commissioning, usage and withdrawal, its production batch, its parts'
// lives (competing risks among a role's failure modes), its removals without
// fault and its tests; and what the plan makes true of the fleet.
#include <absl/strings/str_cat.h>
#include <absl/time/civil_time.h>
#include <absl/time/time.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "generator.h"

namespace insdiag::kb::generator {
namespace {

// The UTC calendar month of a time, and the time its month starts.
absl::CivilMonth MonthOf(std::int64_t micros) {
  return absl::ToCivilMonth(absl::FromUnixMicros(micros), absl::UTCTimeZone());
}
std::int64_t MicrosOfMonthStart(absl::CivilMonth month) {
  return absl::ToUnixMicros(absl::FromCivil(month, absl::UTCTimeZone()));
}

std::string BatchName(absl::CivilMonth month, int batch_months) {
  if (batch_months == 3) return absl::StrCat(month.year(), "Q", (month.month() - 1) / 3 + 1);
  return absl::StrCat(month.year(), "-", month.month() < 10 ? "0" : "", month.month());
}

// The shifts of one failure's signature at its full size.
std::vector<Shift> DrawShifts(const ModeModel& mode, Rng& rng) {
  std::vector<Shift> shifts;
  const auto sign = [&](Direction d) {
    if (d == Direction::kUp) return 1.0;
    if (d == Direction::kDown) return -1.0;
    return rng.Uniform() < 0.5 ? 1.0 : -1.0;
  };
  for (const auto& t : mode.terms) {
    const Signature& s = t.term;
    if (s.common && t.members.size() > 1) {
      const double value = sign(s.direction) * (s.change + s.spread * rng.Normal());
      for (int member : t.members) shifts.push_back({t.kind, member, value});
      continue;
    }
    const double q = s.fraction > 0 ? std::min(s.fraction, 1.0) : 1.0;
    for (int member : t.members) {
      if (rng.Uniform() >= q) continue;
      shifts.push_back({t.kind, member, sign(s.direction) * (s.change + s.spread * rng.Normal())});
    }
  }
  return shifts;
}

// The unit's serial, commissioning, usage and (when it comes before the
// present) withdrawal.
void PlanService(const Model& m, int i, int count, Rng& rng, UnitPlan& u) {
  const v1::FleetProfile& p = m.profile;
  const double hours_per_us = 1.0 / kMicrosPerYear;  // × hours per year
  const int width = std::max<int>(5, static_cast<int>(std::to_string(count).size()));
  const std::string number = std::to_string(i + 1);
  u.serial = absl::StrCat(m.serial_prefix, "-", std::string(static_cast<std::size_t>(width) - number.size(), '0'),
                          number);
  const double position = (static_cast<double>(i) + rng.Uniform()) / static_cast<double>(count);
  u.commission_us = m.start_us + static_cast<std::int64_t>(position * static_cast<double>(m.end_us - m.start_us));
  u.hours_per_us = m.hours_per_year * std::exp(p.operating_hours_log_sd() * rng.Normal()) * hours_per_us;
  u.end_us = m.end_us;
  if (p.retirement_per_year() > 0) {
    const double retire_us = rng.Exponential(p.retirement_per_year()) * kMicrosPerYear;
    if (retire_us < static_cast<double>(m.end_us - u.commission_us)) {
      u.end_us = u.commission_us + static_cast<std::int64_t>(retire_us);
      u.retired = true;
    }
  }
  u.end_hours = u.HoursAt(u.end_us);
}

// The production batch of a unit commissioned at `commission_us` (the
// commissioning period), drawn from its own stream the first time it is seen.
int BatchOf(const Model& m, std::int64_t commission_us, std::map<std::string, int>& batch_index, Plan& plan) {
  const v1::FleetProfile& p = m.profile;
  const double batch_sd = std::sqrt(p.batch_variance_share());
  const absl::CivilMonth month = MonthOf(commission_us);
  const int month_index = static_cast<int>(month.year()) * 12 + month.month() - 1;
  const int first = month_index - month_index % p.batch_months();
  const std::string name = BatchName(absl::CivilMonth(first / 12, first % 12 + 1), p.batch_months());
  auto [it, added] = batch_index.emplace(name, static_cast<int>(plan.batches.size()));
  if (added) {
    Rng batch_rng(m.seed, kBatchStream, static_cast<std::uint64_t>(first));
    Batch b;
    b.name = name;
    for (const auto& t : m.identified) {
      b.offset.push_back(batch_sd * t.healthy_sd * batch_rng.Normal());
      const double z = batch_rng.Normal();
      b.ageing.push_back(t.ageing < 0 ? 0.0
                                      : p.ageing(t.ageing).log_ratio_per_year() +
                                            p.ageing(t.ageing).batch_sd_per_year() * z);
    }
    plan.batches.push_back(std::move(b));
  }
  return it->second;
}

// Parts and their lives, role by role (competing risks among the role's modes).
void PlanParts(const Model& m, Rng& rng, UnitPlan& u) {
  for (std::size_t role = 0; role < m.roles.size(); ++role) {
    double installed_hours = 0;
    std::int64_t installed_us = u.commission_us;
    while (true) {
      Part part;
      part.role = static_cast<int>(role);
      part.installed_hours = installed_hours;
      part.installed_us = installed_us;
      double life = INFINITY;
      int mode = -1;
      for (int candidate : m.modes_of_role[role]) {
        const ModeModel& mm = m.mode_models[static_cast<std::size_t>(candidate)];
        const double t = rng.Weibull(mm.shape, mm.scale_hours);
        if (t < life) {
          life = t;
          mode = candidate;
        }
      }
      const int part_index = static_cast<int>(u.parts.size());
      if (mode >= 0) {
        Failure f;
        f.part = part_index;
        f.mode = mode;
        f.hours = installed_hours + life;
        f.realised = f.hours < u.end_hours;
        f.time_us = f.realised ? u.TimeAt(f.hours)
                               : u.commission_us + static_cast<std::int64_t>(std::min(f.hours / u.hours_per_us, 1e17));
        f.shifts = DrawShifts(m.mode_models[static_cast<std::size_t>(mode)], rng);
        part.failure = static_cast<int>(u.failures.size());
        u.failures.push_back(std::move(f));
      }
      const Failure* failure = part.failure >= 0 ? &u.failures[static_cast<std::size_t>(part.failure)] : nullptr;
      if (failure != nullptr && failure->realised) {
        part.removed_us = failure->time_us;
        part.removed_hours = failure->hours;
        u.parts.push_back(part);
        installed_hours = failure->hours;
        installed_us = failure->time_us;
        continue;
      }
      if (u.retired) {
        part.removed_us = u.end_us;
        part.removed_hours = u.end_hours;
        part.withdrawn = true;
      }
      u.parts.push_back(part);
      break;
    }
  }
}

// Removals on suspicion: a Poisson process in operating hours.
void PlanNoFaultFound(const Model& m, Rng& rng, UnitPlan& u) {
  const v1::FleetProfile& p = m.profile;
  double total_weight = 0;
  for (double w : m.role_weight) total_weight += w;
  if (p.no_fault_found_per_million_hours() > 0 && total_weight > 0) {
    double h = rng.Exponential(p.no_fault_found_per_million_hours() * 1e-6);
    while (h < u.end_hours) {
      double pick = rng.Uniform() * total_weight;
      int role = 0;
      while (role + 1 < static_cast<int>(m.role_weight.size()) && pick >= m.role_weight[static_cast<std::size_t>(role)]) {
        pick -= m.role_weight[static_cast<std::size_t>(role)];
        ++role;
      }
      u.no_fault_found.push_back({role, u.TimeAt(h), h, -1});
      h += rng.Exponential(p.no_fault_found_per_million_hours() * 1e-6);
    }
  }
}

// One unit's tests in time order: periodic, one per failure and per
// no-fault-found removal, each followed by its retest; each event knows the
// test that found it.
void ScheduleTests(const Model& m, std::size_t i, std::int64_t interval_us, UnitPlan& u) {
  const double jitter = std::clamp(m.profile.test_interval_jitter(), 0.0, 0.9);
  Rng rng(m.seed, kScheduleStream, i);
  for (std::int64_t t = u.commission_us; t < u.end_us;) {
    u.tests.push_back({t, u.HoursAt(t), TestKind::kPeriodic, -1, 0, -1});
    t += static_cast<std::int64_t>(static_cast<double>(interval_us) * (1.0 + jitter * (2.0 * rng.Uniform() - 1.0)));
  }
  const auto retest = [&](std::int64_t t) {
    const std::int64_t after = t + RecordDelay(m);
    if (after < u.end_us) u.tests.push_back({after, u.HoursAt(after), TestKind::kRetest, -1, 0, -1});
  };
  for (std::size_t f = 0; f < u.failures.size(); ++f) {
    if (u.failures[f].realised) {
      u.tests.push_back({u.failures[f].time_us, u.failures[f].hours, TestKind::kFailure, static_cast<int>(f), 0, -1});
      retest(u.failures[f].time_us);
    }
  }
  for (std::size_t n = 0; n < u.no_fault_found.size(); ++n) {
    const auto& e = u.no_fault_found[n];
    u.tests.push_back({e.time_us, e.hours, TestKind::kNoFaultFound, static_cast<int>(n), 0, -1});
    retest(e.time_us);
  }
  std::stable_sort(u.tests.begin(), u.tests.end(), [](const Test& a, const Test& b) { return a.time_us < b.time_us; });
  for (std::size_t t = 0; t < u.tests.size(); ++t) {
    const Test& test = u.tests[t];
    if (test.kind == TestKind::kFailure) u.failures[static_cast<std::size_t>(test.event)].test = static_cast<int>(t);
    if (test.kind == TestKind::kNoFaultFound) {
      u.no_fault_found[static_cast<std::size_t>(test.event)].test = static_cast<int>(t);
    }
  }
}

// The fleet's tests in time order (ties by unit, then test), each numbered
// by its position.
void OrderTests(Plan& plan) {
  std::size_t total = 0;
  for (const auto& u : plan.units) total += u.tests.size();
  plan.order.clear();
  plan.order.reserve(total);
  for (std::size_t i = 0; i < plan.units.size(); ++i) {
    for (std::size_t t = 0; t < plan.units[i].tests.size(); ++t) plan.order.emplace_back(static_cast<int>(i), static_cast<int>(t));
  }
  std::sort(plan.order.begin(), plan.order.end(), [&](const auto& a, const auto& b) {
    const std::int64_t ta = plan.units[static_cast<std::size_t>(a.first)].tests[static_cast<std::size_t>(a.second)].time_us;
    const std::int64_t tb = plan.units[static_cast<std::size_t>(b.first)].tests[static_cast<std::size_t>(b.second)].time_us;
    return ta != tb ? ta < tb : a < b;
  });
  for (std::size_t g = 0; g < plan.order.size(); ++g) {
    plan.units[static_cast<std::size_t>(plan.order[g].first)].tests[static_cast<std::size_t>(plan.order[g].second)].global =
        static_cast<std::int64_t>(g);
  }
}

}  // namespace

void PlanUnits(const Model& m, int count, Plan& plan) {
  const v1::FleetProfile& p = m.profile;
  std::map<std::string, int> batch_index;
  const double unit_sd = std::sqrt(1.0 - p.batch_variance_share() - p.measurement_variance_share());
  plan.units.resize(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    // One stream per unit, drawn in this order: service, offsets, parts,
    // removals without fault.
    Rng rng(m.seed, kUnitStream, static_cast<std::uint64_t>(i));
    UnitPlan& u = plan.units[static_cast<std::size_t>(i)];
    PlanService(m, i, count, rng, u);
    u.batch = BatchOf(m, u.commission_us, batch_index, plan);
    for (const auto& t : m.identified) u.offset.push_back(unit_sd * t.healthy_sd * rng.Normal());
    PlanParts(m, rng, u);
    PlanNoFaultFound(m, rng, u);
    plan.parts += static_cast<std::int64_t>(u.parts.size());
  }
}

std::int64_t RecordDelay(const Model& m) {
  return static_cast<std::int64_t>(m.profile.record_delay_days() * static_cast<double>(kMicrosPerDay));
}

void PlanTests(const Model& m, Plan& plan, std::int64_t interval_us) {
  plan.interval_us = interval_us;
  for (std::size_t i = 0; i < plan.units.size(); ++i) ScheduleTests(m, i, interval_us, plan.units[i]);
  OrderTests(plan);
}

bool Diagnosed(const UnitPlan& u, std::size_t test) {
  const TestKind kind = u.tests[test].kind;
  return test + 1 == u.tests.size() || kind == TestKind::kFailure || kind == TestKind::kNoFaultFound;
}

// Whether the unit's latest analysis shows its coming failure `f`: the
// unit is in service, `f` lies within the precursor window after that
// analysis with at least half its signature grown, and its mode moves
// something the analyses measure (a jump or a drifting bias has no
// precursor term in them).
bool LatestAnalysisShows(const Model& m, const UnitPlan& u, const Failure& f) {
  if (u.retired || u.tests.empty() || f.shifts.empty()) return false;
  const std::int64_t ahead_us = f.time_us - u.tests.back().time_us;
  return ahead_us < m.precursor_us && PrecursorShare(m, ahead_us) >= 0.5;
}

void FillTruth(const Model& m, const Plan& plan, GeneratedFleet& out) {
  FleetTruth& truth = out.truth;
  truth.test_interval_days = static_cast<double>(plan.interval_us) / static_cast<double>(kMicrosPerDay);
  for (const auto& u : plan.units) {
    const std::string& batch = plan.batches[static_cast<std::size_t>(u.batch)].name;
    truth.batch_of_unit[u.serial] = batch;
    truth.analyses_of_unit[u.serial] = static_cast<std::int64_t>(u.tests.size());
    truth.fleet_operating_hours += u.end_hours;
    for (const auto& f : u.failures) {
      if (f.realised) {
        const auto month = MicrosOfMonthStart(MonthOf(f.time_us));
        ++truth.failures[{m.mode_models[static_cast<std::size_t>(f.mode)].id, batch, month}];
      } else if (LatestAnalysisShows(m, u, f)) {
        truth.units_about_to_fail.insert(u.serial);
      }
    }
    for (const auto& t : u.tests) {
      ++truth.analyses[{batch, MicrosOfMonthStart(MonthOf(t.time_us))}];
    }
    for (const auto& part : u.parts) ++truth.parts_by_role[m.roles[static_cast<std::size_t>(part.role)]];
  }
  for (const auto& b : plan.batches) {
    for (std::size_t i = 0; i < m.identified.size(); ++i) {
      truth.ageing_per_year[{b.name, m.identified[i].name}] = b.ageing[i];
    }
  }
}

}  // namespace insdiag::kb::generator
