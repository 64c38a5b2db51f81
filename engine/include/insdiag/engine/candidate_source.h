// Which test put a missing-effect candidate in the report: its `source`,
// named as reports and the API name it ("SCORE", "GLR", …). The engine's
// report carries the name; what reads a report back (the diagnosis, the
// report codec) compares the parsed value, never the text.
#pragma once

#include <optional>
#include <string_view>

namespace insdiag::engine {

enum class CandidateSource {
  kScore,       // "SCORE": the one-pass score (Lagrange-multiplier) test (finder/score_test.h)
  kStructure,   // "STRUCTURE": a correlation-function family of the smoothed drift
                // (ident/correlation.h)
  kLikelihood,  // "LIKELIHOOD": a walk or second-order pair by the innovations' likelihood
  kGlr,         // "GLR": a step or ramp by the generalised likelihood ratio over onsets
                // (finder/onset_scan.h)
  kRaw,  // "RAW": a jump or ramp the still segments' raw samples show (finder/fault_findings.h)
};

std::string_view CandidateSourceName(CandidateSource source);
// The source a name CandidateSourceName gives; nullopt for any other text.
std::optional<CandidateSource> CandidateSourceNamed(std::string_view name);

// A random structure's test (a walk or second-order pair): its size is a variance.
inline bool IsStructureSource(CandidateSource s) {
  return s == CandidateSource::kStructure || s == CandidateSource::kLikelihood;
}
// A fault's test (a step or ramp at an unknown onset).
inline bool IsFaultTestSource(CandidateSource s) {
  return s == CandidateSource::kGlr || s == CandidateSource::kRaw;
}

}  // namespace insdiag::engine
