#include "insdiag/api/json.h"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>

#include <string>

#include "json_shape.h"

namespace insdiag::api {

absl::StatusOr<std::string> ToJson(const google::protobuf::Message& message, bool pretty) {
  google::protobuf::util::JsonPrintOptions options;
  options.always_print_primitive_fields = true;
  options.add_whitespace = pretty;
  std::string out;
  const auto status = google::protobuf::util::MessageToJsonString(message, &out, options);
  if (!status.ok()) return absl::InternalError(std::string(status.message()));
  return out;
}

absl::Status FromJson(std::string_view json, google::protobuf::Message* message) {
  message->Clear();
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  const auto status = google::protobuf::util::JsonStringToMessage(json, message, options);
  if (!status.ok()) {
    return absl::InvalidArgumentError("request body is not a valid " + message->GetTypeName() +
                                      " in JSON: " + std::string(status.message()));
  }
  // Parsed as protobuf takes it; now as it was written, every value of the
  // type its field takes (json_shape.h). The body is a JSON object: it parsed.
  google::protobuf::Struct written;
  if (google::protobuf::util::JsonStringToMessage(json, &written, options).ok()) {
    if (absl::Status shape = internal::CheckJsonShape(written, *message->GetDescriptor(), ""); !shape.ok()) {
      message->Clear();
      return absl::InvalidArgumentError("request body is not a valid " + message->GetTypeName() +
                                        " in JSON: " + std::string(shape.message()));
    }
  }
  return absl::OkStatus();
}

}  // namespace insdiag::api
