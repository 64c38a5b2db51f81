// The unit types' failure modes as the experts write them
// (data/failure-modes/*.json, built in; their format is
// insdiag.v1.FailureModeCatalogue), and their templates expanded per axis
// into the failure modes the knowledge base is seeded with. In kb's terms:
// insdiag/kb/catalogue_data.h.
#pragma once

#include <absl/status/statusor.h>

#include <string>
#include <vector>

#include "insdiag/v1/knowledge.pb.h"

namespace insdiag::kb {

const std::vector<v1::FailureModeCatalogue>& BuiltinFailureModeCatalogues();
// The catalogue of one unit type (display or resource name), one of
// BuiltinFailureModeCatalogues(); NOT_FOUND when none.
absl::StatusOr<const v1::FailureModeCatalogue*> BuiltinFailureModeCatalogue(
    const std::string& unit_type);

// The catalogue's templates expanded per axis into failure modes
// (failureModes/{id}), signatures at the expert's values. INVALID_ARGUMENT
// naming the mode and field for a malformed template.
absl::StatusOr<std::vector<v1::FailureMode>> ExpandCatalogue(const v1::FailureModeCatalogue& catalogue);

}  // namespace insdiag::kb
