#include "insdiag/server/openapi.h"

#include <absl/strings/ascii.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_split.h>
#include <google/protobuf/descriptor.h>
#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>

#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>


namespace insdiag::server {
namespace {

using google::protobuf::Descriptor;
using google::protobuf::FieldDescriptor;
using google::protobuf::Struct;
using google::protobuf::Value;

Value Text(const std::string& s) {
  Value v;
  v.set_string_value(s);
  return v;
}

Value Flag(bool b) {
  Value v;
  v.set_bool_value(b);
  return v;
}

Value Object(Struct s) {
  Value v;
  *v.mutable_struct_value() = std::move(s);
  return v;
}

Value List(std::vector<Value> items) {
  Value v;
  for (auto& item : items) *v.mutable_list_value()->add_values() = std::move(item);
  return v;
}

Struct Fields(std::initializer_list<std::pair<std::string, Value>> fields) {
  Struct s;
  for (const auto& [k, v] : fields) (*s.mutable_fields())[k] = v;
  return s;
}

Value Ref(const std::string& schema) { return Object(Fields({{"$ref", Text("#/components/schemas/" + schema)}})); }

// The JSON-mapping schema of protobuf messages, collected as they are met.
class Schemas {
 public:
  Value Of(const Descriptor* type) {
    const std::string name = type->full_name();
    if (name == "google.protobuf.Timestamp") return Object(Fields({{"type", Text("string")}, {"format", Text("date-time")}}));
    if (name == "google.protobuf.Duration") return Object(Fields({{"type", Text("string")}, {"example", Text("1.5s")}}));
    if (name == "google.protobuf.Struct") return Object(Fields({{"type", Text("object")}}));
    if (name == "google.protobuf.Value") return Object(Fields({}));
    if (!seen_.contains(name)) {
      seen_.insert(name);
      Struct properties;
      for (int i = 0; i < type->field_count(); ++i) {
        const FieldDescriptor* f = type->field(i);
        (*properties.mutable_fields())[f->json_name()] = FieldSchema(f);
      }
      Struct schema = Fields({{"type", Text("object")}});
      (*schema.mutable_fields())["properties"] = Object(std::move(properties));
      (*components_.mutable_fields())[name] = Object(std::move(schema));
    }
    return Ref(name);
  }

  Value FieldSchema(const FieldDescriptor* f) {
    if (f->is_map()) {
      const FieldDescriptor* value = f->message_type()->map_value();
      return Object(Fields({{"type", Text("object")}, {"additionalProperties", ScalarOrMessage(value)}}));
    }
    Value item = ScalarOrMessage(f);
    if (!f->is_repeated()) return item;
    return Object(Fields({{"type", Text("array")}, {"items", item}}));
  }

  Value ScalarOrMessage(const FieldDescriptor* f) {
    switch (f->cpp_type()) {
      case FieldDescriptor::CPPTYPE_MESSAGE: return Of(f->message_type());
      case FieldDescriptor::CPPTYPE_ENUM: {
        std::vector<Value> names;
        for (int i = 0; i < f->enum_type()->value_count(); ++i) names.push_back(Text(f->enum_type()->value(i)->name()));
        return Object(Fields({{"type", Text("string")}, {"enum", List(std::move(names))}}));
      }
      case FieldDescriptor::CPPTYPE_BOOL: return Object(Fields({{"type", Text("boolean")}}));
      case FieldDescriptor::CPPTYPE_DOUBLE:
      case FieldDescriptor::CPPTYPE_FLOAT: return Object(Fields({{"type", Text("number")}}));
      case FieldDescriptor::CPPTYPE_INT32:
      case FieldDescriptor::CPPTYPE_UINT32: return Object(Fields({{"type", Text("integer")}, {"format", Text("int32")}}));
      // The JSON mapping writes 64-bit integers as strings.
      case FieldDescriptor::CPPTYPE_INT64:
      case FieldDescriptor::CPPTYPE_UINT64: return Object(Fields({{"type", Text("string")}, {"format", Text("int64")}}));
      case FieldDescriptor::CPPTYPE_STRING:
        return f->type() == FieldDescriptor::TYPE_BYTES ? Object(Fields({{"type", Text("string")}, {"format", Text("byte")}}))
                                                        : Object(Fields({{"type", Text("string")}}));
    }
    return Object(Fields({}));
  }

  Struct Take() { return std::move(components_); }

 private:
  std::set<std::string> seen_;
  Struct components_;
};

// The path variables of a rule ("name" of "{name=runs/*}") and the OpenAPI
// parameters that stand for them.
struct PathVariables {
  std::set<std::string> fields;
  std::vector<std::string> parameters;
};

PathVariables VariablesOf(const std::string& rule_path) {
  PathVariables out;
  for (size_t open = rule_path.find('{'); open != std::string::npos; open = rule_path.find('{', open + 1)) {
    const size_t close = rule_path.find('}', open);
    const std::string inside = rule_path.substr(open + 1, close - open - 1);
    out.fields.insert(inside.substr(0, inside.find('=')));
  }
  const std::string path = OpenApiPath(rule_path);
  for (size_t open = path.find('{'); open != std::string::npos; open = path.find('{', open + 1)) {
    out.parameters.push_back(path.substr(open + 1, path.find('}', open) - open - 1));
  }
  return out;
}

Value Parameter(const std::string& name, const char* in, bool required, Value schema, const std::string& what = "") {
  Struct p = Fields({{"name", Text(name)}, {"in", Text(in)}, {"required", Flag(required)}, {"schema", std::move(schema)}});
  if (!what.empty()) (*p.mutable_fields())["description"] = Text(what);
  return Object(std::move(p));
}

Value ErrorResponse() {
  return Object(Fields({{"description", Text("an error (AIP-193): code, message, status and details")},
                        {"content", Object(Fields({{"application/json",
                                                    Object(Fields({{"schema", Ref("insdiag.Error")}}))}}))}}));
}

Value Answer(const std::string& description, const std::string& content_type, Value schema) {
  return Object(Fields({{"description", Text(description)},
                        {"content", Object(Fields({{content_type, Object(Fields({{"schema", std::move(schema)}}))}}))}}));
}

Value OperationOf(const OpenApiOperation& op, Schemas& schemas) {
  const auto* method = op.method;
  const Descriptor* input = method->input_type();
  const PathVariables vars = VariablesOf(op.path);
  std::vector<Value> parameters;
  for (const std::string& p : vars.parameters) parameters.push_back(Parameter(p, "path", true, Object(Fields({{"type", Text("string")}}))));
  Struct operation = Fields({{"operationId", Text(absl::StrCat(method->service()->name(), "_", method->name()))},
                             {"summary", Text(method->full_name())}});
  const FieldDescriptor* body_field = op.body.empty() || op.body == "*" ? nullptr : input->FindFieldByName(op.body);
  if (op.body != "*") {
    for (int i = 0; i < input->field_count(); ++i) {
      const FieldDescriptor* f = input->field(i);
      if (vars.fields.contains(f->name()) || f == body_field || f->cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE) continue;
      parameters.push_back(Parameter(f->json_name(), "query", false, schemas.FieldSchema(f)));
    }
  }
  if (method->client_streaming()) {
    // A streamed upload: a bench-run file, or one request message a line.
    (*operation.mutable_fields())["requestBody"] = Object(Fields(
        {{"required", Flag(true)},
         {"content", Object(Fields({{"text/csv", Object(Fields({{"schema", Object(Fields({{"type", Text("string")}}))}}))},
                                    {"application/x-ndjson", Object(Fields({{"schema", schemas.Of(input)}}))}}))}}));
  } else if (!op.body.empty()) {
    Value schema = body_field != nullptr ? schemas.FieldSchema(body_field) : schemas.Of(input);
    (*operation.mutable_fields())["requestBody"] =
        Object(Fields({{"required", Flag(true)},
                       {"content", Object(Fields({{"application/json", Object(Fields({{"schema", schema}}))}}))}}));
  }
  if (!parameters.empty()) (*operation.mutable_fields())["parameters"] = List(std::move(parameters));
  const bool streams = method->server_streaming();
  Struct responses;
  if (method->output_type()->full_name() == "google.api.HttpBody") {
    // The body is the document itself; its Content-Type says which kind.
    (*responses.mutable_fields())["200"] =
        Answer("the document, under its own media type", "*/*",
               Object(Fields({{"type", Text("string")}, {"format", Text("binary")}})));
  } else {
    (*responses.mutable_fields())["200"] =
        Answer(streams ? "one JSON object a line, as the responses arrive" : "the response",
               streams ? "application/x-ndjson" : "application/json", schemas.Of(method->output_type()));
  }
  (*responses.mutable_fields())["default"] = ErrorResponse();
  (*operation.mutable_fields())["responses"] = Object(std::move(responses));
  return Object(std::move(operation));
}

Value ExtraOperationOf(const OpenApiExtraRoute& route) {
  std::vector<Value> parameters;
  const std::string& path = route.path;
  for (size_t open = path.find('{'); open != std::string::npos; open = path.find('{', open + 1)) {
    parameters.push_back(Parameter(path.substr(open + 1, path.find('}', open) - open - 1), "path", true,
                                   Object(Fields({{"type", Text("string")}}))));
  }
  Struct operation = Fields({{"summary", Text(route.summary)}});
  if (!parameters.empty()) (*operation.mutable_fields())["parameters"] = List(std::move(parameters));
  Struct responses;
  (*responses.mutable_fields())["200"] =
      Answer(route.summary, route.content_type, Object(Fields({{"type", Text("string")}})));
  (*responses.mutable_fields())["default"] = ErrorResponse();
  (*operation.mutable_fields())["responses"] = Object(std::move(responses));
  if (!route.needs_token) (*operation.mutable_fields())["security"] = List({});
  return Object(std::move(operation));
}

}  // namespace

std::string OpenApiPath(const std::string& rule_path) {
  std::string out;
  size_t at = 0;
  while (at < rule_path.size()) {
    const size_t open = rule_path.find('{', at);
    if (open == std::string::npos) {
      out += rule_path.substr(at);
      break;
    }
    out += rule_path.substr(at, open - at);
    const size_t close = rule_path.find('}', open);
    const std::string inside = rule_path.substr(open + 1, close - open - 1);
    const size_t eq = inside.find('=');
    if (eq == std::string::npos) {
      out += "{" + inside + "}";
    } else {
      // Each wildcard of the pattern is a parameter named after the collection before it.
      std::vector<std::string> segments = absl::StrSplit(inside.substr(eq + 1), '/');
      std::string previous = inside.substr(0, eq);
      for (size_t i = 0; i < segments.size(); ++i) {
        if (i > 0) out += "/";
        if (segments[i] == "*" || segments[i] == "**") {
          out += "{" + previous + (segments[i] == "**" ? "Path" : "Id") + "}";
        } else {
          out += segments[i];
          previous = segments[i];
        }
      }
    }
    at = close + 1;
  }
  return out;
}

std::string OpenApiDocument(const std::vector<OpenApiOperation>& operations,
                            const std::vector<OpenApiExtraRoute>& extras) {
  Schemas schemas;
  std::map<std::string, Struct> paths;  // OpenAPI path → method → operation
  for (const OpenApiOperation& op : operations) {
    (*paths[OpenApiPath(op.path)].mutable_fields())[absl::AsciiStrToLower(op.http_method)] = OperationOf(op, schemas);
  }
  for (const OpenApiExtraRoute& route : extras) {
    (*paths[route.path].mutable_fields())[absl::AsciiStrToLower(route.http_method)] = ExtraOperationOf(route);
  }
  Struct path_object;
  for (auto& [path, methods] : paths) (*path_object.mutable_fields())[path] = Object(std::move(methods));

  Struct components_schemas = schemas.Take();
  (*components_schemas.mutable_fields())["insdiag.Error"] = Object(Fields(
      {{"type", Text("object")},
       {"properties", Object(Fields({{"error", Object(Fields({{"type", Text("object")},
                                                               {"properties", Object(Fields({
                                                                   {"code", Object(Fields({{"type", Text("integer")}}))},
                                                                   {"message", Object(Fields({{"type", Text("string")}}))},
                                                                   {"status", Object(Fields({{"type", Text("string")}}))},
                                                                   {"details", Object(Fields({{"type", Text("array")},
                                                                                              {"items", Object(Fields({{"type", Text("object")}}))}}))},
                                                               }))}}))}}))}}));
  Struct document = Fields({
      {"openapi", Text("3.0.3")},
      {"info", Object(Fields({{"title", Text("insdiag")},
                              {"version", Text("v1")},
                              {"description", Text("The REST face of insdiag's gRPC services (docs/API.md), generated "
                                                   "from their google.api.http rules.")}}))},
      {"paths", Object(std::move(path_object))},
      {"components", Object(Fields({{"schemas", Object(std::move(components_schemas))},
                                    {"securitySchemes", Object(Fields({{"bearer", Object(Fields({{"type", Text("http")},
                                                                                                {"scheme", Text("bearer")}}))}}))}}))},
      {"security", List({Object(Fields({{"bearer", List({})}}))})},
  });
  std::string json;
  google::protobuf::util::JsonPrintOptions print;
  print.add_whitespace = true;
  (void)google::protobuf::util::MessageToJsonString(document, &json, print);
  return json;
}

}  // namespace insdiag::server
