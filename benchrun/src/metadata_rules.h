// Metadata rules the CSV reader needs while it reads, before the metadata is
// complete; BenchRunValidator applies the same functions to finished metadata.
#pragma once

#include <string>
#include <string_view>

namespace insdiag::benchrun::internal {

// A metadata key as the spec allows it: lower-case ASCII letters, digits and
// '_', starting with a letter.
bool IsMetadataKey(std::string_view key);

// Why the value of a reference key the format gives a grammar
// (reference_attitude_readout, reference_level_sigma_rad,
// reference_heading_sigma_rad) is not one; empty when it is, or when `key`
// is none of them.
std::string CheckReferenceKey(std::string_view key, std::string_view value);

// Why `format` is not the one this library reads; empty when it is.
std::string CheckFormat(std::string_view format);

}  // namespace insdiag::benchrun::internal
