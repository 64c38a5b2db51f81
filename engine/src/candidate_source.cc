#include "insdiag/engine/candidate_source.h"

#include <array>
#include <utility>

namespace insdiag::engine {
namespace {

constexpr std::array<std::pair<CandidateSource, std::string_view>, 5> kSourceNames = {{
    {CandidateSource::kScore, "SCORE"},
    {CandidateSource::kStructure, "STRUCTURE"},
    {CandidateSource::kLikelihood, "LIKELIHOOD"},
    {CandidateSource::kGlr, "GLR"},
    {CandidateSource::kRaw, "RAW"},
}};

}  // namespace

std::string_view CandidateSourceName(CandidateSource source) {
  for (const auto& [s, name] : kSourceNames) {
    if (s == source) return name;
  }
  return "";
}

std::optional<CandidateSource> CandidateSourceNamed(std::string_view name) {
  for (const auto& [s, n] : kSourceNames) {
    if (n == name) return s;
  }
  return std::nullopt;
}

}  // namespace insdiag::engine
