// The v1 API's resource names: a collection and an id, "runs/{run}",
// "analyses/{analysis}", "units/{unit}", "unitTypes/{unitType}", … (AIP-122).
// One place builds and reads them for the server and the stores, with one refusal for a name that is not
// one: "analysis.run: 'x' is not a run name (runs/{run})".
#pragma once

#include <absl/status/statusor.h>

#include <string>
#include <string_view>

namespace insdiag::api {

struct Collection {
  std::string_view segment;  // "runs"
  std::string_view noun;     // "a run": what a refusal says the name is not
  std::string_view id;       // "run": the id's placeholder in the pattern
};

inline constexpr Collection kRuns{"runs", "a run", "run"};
inline constexpr Collection kAnalyses{"analyses", "an analysis", "analysis"};
inline constexpr Collection kUnits{"units", "a unit", "unit"};
inline constexpr Collection kUnitTypes{"unitTypes", "a unit type", "unitType"};
inline constexpr Collection kDiagnoses{"diagnoses", "a diagnosis", "diagnosis"};
inline constexpr Collection kFailureRecords{"failureRecords", "a failure record", "failureRecord"};
inline constexpr Collection kFailureModes{"failureModes", "a failure mode", "failureMode"};
inline constexpr Collection kTokens{"tokens", "a token", "token"};

// "runs/abc".
std::string ResourceName(const Collection& collection, std::string_view id);

// The id of `name` in `collection`: a non-empty id without '/'. `field`
// names the request field in the refusal ("name", "analysis.run").
absl::StatusOr<std::string> ResourceId(std::string_view name, const Collection& collection,
                                       std::string_view field = "name");

// A unit's module: "units/{unit}/modules/{module}", the module named by its
// role in the unit ("gyro.x").
struct ModuleOfUnit {
  std::string unit;
  std::string role;
};
std::string ModuleName(std::string_view unit_id, std::string_view role);
// Both ids non-empty and without '/'; the refusal names `field`.
absl::StatusOr<ModuleOfUnit> ParseModuleName(std::string_view name,
                                             std::string_view field = "module");

// The id when `name` is in `collection`, else `name` itself: for inputs that
// accept a bare id too (a unit type given as "INS-2000").
std::string IdOrSelf(std::string_view name, const Collection& collection);

}  // namespace insdiag::api
