// The JSON shape check behind api::FromJson: protobuf 3.21's JSON parser
// takes "yes" for true and a single value for a list, so a request of the
// wrong type would be stored as something its sender did not mean. Each
// value is checked against its field's type before the message is parsed.
#pragma once

#include <absl/status/status.h>
#include <google/protobuf/descriptor.h>
#include <google/protobuf/struct.pb.h>

#include <string>

namespace insdiag::api::internal {

// INVALID_ARGUMENT naming the field path ("analysis.model.effects") when a
// value of `object` has a JSON type its field does not take: a bool field
// takes true or false; a string or bytes field, a string; a number field, a
// number or a string (proto3's JSON mapping writes 64-bit integers as
// strings); an enum, a string or a number; a list, an array; a map or a
// message, an object; null is any field's default. A string holds no U+0000. Well-known types take
// their JSON forms (Timestamp and Duration: strings; Struct, Value: anything).
absl::Status CheckJsonShape(const google::protobuf::Struct& object, const google::protobuf::Descriptor& type,
                            const std::string& path);

}  // namespace insdiag::api::internal
