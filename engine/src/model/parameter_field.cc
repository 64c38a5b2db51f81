#include "insdiag/engine/model/parameter_field.h"

#include <array>
#include <utility>

namespace insdiag::engine {
namespace {

constexpr std::array<std::pair<ParameterField, std::string_view>, 10> kSuffixes = {{
    {ParameterField::kPriorSigma, "prior_sigma"},
    {ParameterField::kOnset, "onset"},
    {ParameterField::kDensity, "density"},
    {ParameterField::kSigma, "sigma"},
    {ParameterField::kTau, "tau"},
    {ParameterField::kPeriod, "period"},
    {ParameterField::kDecayRate, "alpha"},
    {ParameterField::kFrequency, "beta"},
    {ParameterField::kShortestTau, "tau_min"},
    {ParameterField::kLongestTau, "tau_max"},
}};

}  // namespace

std::string_view FieldSuffix(ParameterField field) {
  for (const auto& [f, suffix] : kSuffixes) {
    if (f == field) return suffix;
  }
  return "";
}

std::string ParameterName(std::string_view quantity, ParameterField field) {
  std::string name(quantity);
  if (field != ParameterField::kValue) {
    name += '.';
    name += FieldSuffix(field);
  }
  return name;
}

SplitParameter SplitParameterName(std::string_view name) {
  const size_t dot = name.rfind('.');
  if (dot != std::string_view::npos && dot > 0) {
    const std::string_view tail = name.substr(dot + 1);
    for (const auto& [field, suffix] : kSuffixes) {
      if (tail == suffix) return {name.substr(0, dot), field};
    }
  }
  return {name, ParameterField::kValue};
}

}  // namespace insdiag::engine
