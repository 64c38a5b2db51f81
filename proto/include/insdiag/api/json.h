// The one JSON printer and parser of insdiag messages (protobuf's JSON
// mapping, lowerCamelCase names). Printing always includes fields at their
// default value, so zeros and empty lists are present for scripts that read
// the output. Used by the REST face and the CLI.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>
#include <google/protobuf/message.h>

#include <string>
#include <string_view>

#include "insdiag/api/json_string.h"  // JsonString, for JSON written outside a message

namespace insdiag::api {

// Compact single-line JSON unless `pretty`.
absl::StatusOr<std::string> ToJson(const google::protobuf::Message& message, bool pretty = false);

// Parses JSON into `message` (cleared first); unknown fields are refused.
// INVALID_ARGUMENT naming what did not parse.
absl::Status FromJson(std::string_view json, google::protobuf::Message* message);

}  // namespace insdiag::api
