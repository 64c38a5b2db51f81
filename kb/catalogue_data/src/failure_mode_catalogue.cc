#include "insdiag/kb/failure_mode_catalogue.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_replace.h>

#include <set>
#include <string_view>

#include "failure_mode_data.h"
#include "insdiag/api/json.h"
#include "insdiag/api/resource_names.h"

namespace insdiag::kb {

const std::vector<v1::FailureModeCatalogue>& BuiltinFailureModeCatalogues() {
  // Parsed once: tests and the offline diagnosis read them again and again.
  static const std::vector<v1::FailureModeCatalogue> catalogues = [] {
    std::vector<v1::FailureModeCatalogue> out;
    for (const std::string_view json : kFailureModeJson) {
      v1::FailureModeCatalogue catalogue;
      // The files are part of the build and parsed by a unit test.
      if (api::FromJson(json, &catalogue).ok()) out.push_back(std::move(catalogue));
    }
    return out;
  }();
  return catalogues;
}

absl::StatusOr<const v1::FailureModeCatalogue*> BuiltinFailureModeCatalogue(
    const std::string& unit_type) {
  const std::string name = api::IdOrSelf(unit_type, api::kUnitTypes);
  for (const auto& catalogue : BuiltinFailureModeCatalogues()) {
    if (catalogue.unit_type() == name) return &catalogue;
  }
  return absl::NotFoundError(absl::StrCat("no failure modes for unit type '", unit_type, "'"));
}

absl::StatusOr<std::vector<v1::FailureMode>> ExpandCatalogue(const v1::FailureModeCatalogue& catalogue) {
  std::vector<v1::FailureMode> out;
  std::set<std::string> seen;
  for (const auto& tmpl : catalogue.modes()) {
    const auto bad = [&](const std::string& field, const std::string& why) {
      return absl::InvalidArgumentError(
          absl::StrCat("failure modes of ", catalogue.unit_type(), ": mode '", tmpl.id(), "': ", field, ": ", why));
    };
    if (tmpl.id().empty()) return bad("id", "is empty");
    if (tmpl.rate_per_million_hours() <= 0) return bad("ratePerMillionHours", "must be positive");
    if (tmpl.weibull_shape() <= 0 || tmpl.weibull_scale_hours() <= 0) return bad("weibull", "must be positive");
    if (tmpl.signature().empty()) return bad("signature", "is empty");
    std::vector<std::string> axes(tmpl.axes().begin(), tmpl.axes().end());
    if (axes.empty()) axes.push_back("");
    for (const std::string& axis : axes) {
      const auto fill = [&](const std::string& text) {
        return axis.empty() ? text : absl::StrReplaceAll(text, {{"{i}", axis}});
      };
      v1::FailureMode mode;
      mode.set_name(api::ResourceName(api::kFailureModes, fill(tmpl.id())));
      if (!seen.insert(mode.name()).second) return bad("id", "expands to a name used twice");
      mode.set_module_role(fill(tmpl.module_role()));
      mode.set_display_name(axis.empty() ? tmpl.display_name() : absl::StrCat(tmpl.display_name(), " (", axis, ")"));
      mode.set_description(tmpl.description());
      mode.set_unit_type(api::ResourceName(api::kUnitTypes, catalogue.unit_type()));
      mode.set_expert_rate_per_million_hours(tmpl.rate_per_million_hours());
      mode.set_rate_per_million_hours(tmpl.rate_per_million_hours());
      mode.set_weibull_shape(tmpl.weibull_shape());
      mode.set_weibull_scale_hours(tmpl.weibull_scale_hours());
      for (const auto& sig : tmpl.signature()) {
        if (sig.scale() != "log_ratio" && sig.scale() != "tolerance" && sig.scale() != "z") {
          return bad("signature.scale", absl::StrCat("'", sig.scale(), "' is not log_ratio, tolerance or z"));
        }
        if (sig.direction() == v1::Signature::DIRECTION_UNSPECIFIED) return bad("signature.direction", "is missing");
        if (sig.change() < 0 || sig.spread() <= 0) {
          return bad("signature", absl::StrCat(sig.parameter(), ": change must be ≥ 0 and spread > 0"));
        }
        v1::Signature* term = mode.add_signature();
        *term = sig;
        term->set_parameter(fill(sig.parameter()));
        term->set_expert_change(sig.change());
        term->set_expert_spread(sig.spread());
        if (term->fraction() <= 0.0) term->set_fraction(1.0);
      }
      out.push_back(std::move(mode));
    }
  }
  return out;
}

}  // namespace insdiag::kb
