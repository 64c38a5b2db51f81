#include "insdiag/server/access_guard.h"

#include <absl/strings/ascii.h>
#include <absl/strings/match.h>
#include <absl/strings/str_cat.h>
#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>

#include <random>

#include "access_codec.h"
#include "insdiag/server/server_log.h"

namespace insdiag::server {
namespace {

using google::protobuf::FieldDescriptor;
using google::protobuf::Message;

absl::string_view Metadata(const grpc::ServerContext& context, absl::string_view key) {
  const auto& metadata = context.client_metadata();
  const auto found = metadata.find(grpc::string_ref(key.data(), key.size()));
  if (found == metadata.end()) return {};
  return absl::string_view(found->second.data(), found->second.size());
}

// The string field `field` of `message`, or "".
std::string StringField(const Message& message, const char* field) {
  const FieldDescriptor* f = message.GetDescriptor()->FindFieldByName(field);
  if (f == nullptr || f->is_repeated() || f->cpp_type() != FieldDescriptor::CPPTYPE_STRING) return "";
  return message.GetReflection()->GetString(message, f);
}

std::string ResourceOf(const Message* request, const Message* response) {
  if (request != nullptr) {
    if (std::string name = StringField(*request, "name"); !name.empty()) return name;
  }
  if (response != nullptr) {
    if (std::string name = StringField(*response, "name"); !name.empty()) return name;
    const auto* type = response->GetDescriptor();
    for (int i = 0; i < type->field_count(); ++i) {
      const FieldDescriptor* f = type->field(i);
      if (f->cpp_type() != FieldDescriptor::CPPTYPE_MESSAGE || f->is_repeated()) continue;
      if (std::string name = StringField(response->GetReflection()->GetMessage(*response, f), "name"); !name.empty()) {
        return name;
      }
      break;
    }
  }
  return request != nullptr ? StringField(*request, "parent") : "";
}

}  // namespace

AccessGuard::AccessGuard(kb::AccessStore& store) : store_(store) {
  std::random_device entropy;
  for (int i = 0; i < 4; ++i) absl::StrAppend(&gateway_key_, absl::Hex(entropy(), absl::kZeroPad8));
}

absl::Status AccessGuard::CheckEveryMethodHasARule(const std::vector<std::string>& services) {
  const auto* pool = google::protobuf::DescriptorPool::generated_pool();
  for (const std::string& name : services) {
    const auto* service = pool->FindServiceByName(name);
    if (service == nullptr) return absl::InternalError(absl::StrCat("unknown service ", name));
    for (int m = 0; m < service->method_count(); ++m) {
      const auto& options = service->method(m)->options();
      if (!options.HasExtension(v1::access) || options.GetExtension(v1::access).role() == v1::ROLE_UNSPECIFIED) {
        return absl::InternalError(
            absl::StrCat(service->method(m)->full_name(), " has no access rule (option (insdiag.v1.access))"));
      }
    }
  }
  return absl::OkStatus();
}

const v1::AccessRule* AccessGuard::RuleOf(absl::string_view method) const {
  const auto* descriptor = google::protobuf::DescriptorPool::generated_pool()->FindMethodByName(std::string(method));
  if (descriptor == nullptr || !descriptor->options().HasExtension(v1::access)) return nullptr;
  return &descriptor->options().GetExtension(v1::access);
}

std::string AccessGuard::PeerOf(const grpc::ServerContext& context) const {
  if (Metadata(context, kGatewayKeyMetadata) == gateway_key_) {
    if (absl::string_view forwarded = Metadata(context, kPeerMetadata); !forwarded.empty()) return std::string(forwarded);
  }
  return context.peer();
}

absl::StatusOr<kb::Caller> AccessGuard::Admit(const grpc::ServerContext& context, absl::string_view method) {
  const v1::AccessRule* rule = RuleOf(method);
  // Fail closed: CheckEveryMethodHasARule keeps this from happening.
  if (rule == nullptr || rule->role() == v1::ROLE_UNSPECIFIED) {
    return absl::PermissionDeniedError(absl::StrCat(method, " has no access rule"));
  }
  const kb::Role least_role = RoleOf(rule->role());
  const absl::StatusOr<kb::Caller> who = Authenticate(Metadata(context, "authorization"));
  absl::Status admitted = who.status();
  if (who.ok() && who->role < least_role) {
    admitted = absl::PermissionDeniedError(absl::StrCat(method, " needs the role ", kb::RoleName(least_role),
                                                        " or above; ", who->token, " (", who->display_name,
                                                        ") has ", kb::RoleName(who->role)));
  }
  if (admitted.ok()) return who;
  if (rule->writes()) {
    const kb::AuditedCall refused{.caller = who.ok() ? std::optional(*who) : std::nullopt,
                                  .method = std::string(method), .resource = "", .peer = PeerOf(context),
                                  .outcome = admitted};
    if (auto recorded = store_.RecordAuditEvent(refused); !recorded.ok()) {
      Log(LogLevel::kError, absl::StrCat("audit event of a refused ", method, " not recorded: ", recorded.message()));
    }
  }
  return admitted;
}

absl::StatusOr<kb::Caller> AccessGuard::Authenticate(absl::string_view authorization) {
  if (authorization.empty()) {
    return absl::UnauthenticatedError(
        "no bearer token: send 'authorization: Bearer <token>' (the CLI takes --token or $INSDIAG_TOKEN)");
  }
  constexpr absl::string_view kScheme = "bearer ";
  if (authorization.size() <= kScheme.size() || !absl::EqualsIgnoreCase(authorization.substr(0, kScheme.size()), kScheme)) {
    return absl::UnauthenticatedError("the authorization is not 'Bearer <token>'");
  }
  return store_.Authenticate(std::string(absl::StripAsciiWhitespace(authorization.substr(kScheme.size()))));
}

void AccessGuard::Audit(const grpc::ServerContext& context, absl::string_view method, const kb::Caller& caller,
                        const Message* request, const Message* response, const absl::Status& outcome) {
  const v1::AccessRule* rule = RuleOf(method);
  if (rule == nullptr || !rule->writes()) return;
  const kb::AuditedCall call{.caller = caller, .method = std::string(method), .resource = ResourceOf(request, response),
                             .peer = PeerOf(context), .outcome = outcome};
  if (auto recorded = store_.RecordAuditEvent(call); !recorded.ok()) {
    Log(LogLevel::kError,
        absl::StrCat("audit event of ", method, " on ", call.resource, " not recorded: ", recorded.message()));
  }
}

}  // namespace insdiag::server
