// insdiag tokens [list]
// insdiag tokens create --name NAME --role viewer|operator|engineer|admin [--expires-days D]
// insdiag tokens revoke tokens/{token}
// insdiag tokens audit [--resource NAME] [--of tokens/{token}]
// Bearer tokens (ADMIN) and the audit trail of writes (ENGINEER and above).
// `create` prints the new secret once: it cannot be read back later.
// All take [--json] [--server ADDR] [--token TOKEN].
#include <absl/strings/ascii.h>
#include <absl/strings/str_cat.h>
#include <absl/time/clock.h>
#include <absl/time/time.h>

#include <ostream>

#include "insdiag/api/limits.h"
#include "insdiag/client/unary.h"
#include "insdiag/v1/access.grpc.pb.h"
#include "server_output.h"
#include "verb.h"

namespace insdiag::cli {
namespace {

class TokensVerb final : public Verb {
 public:
  std::string Name() const override { return "tokens"; }
  std::string Summary() const override { return "Create, list and revoke bearer tokens; read the audit trail"; }

  void DeclareOptions(OptionSink& options) override {
    options.Positionals("ACTION", &arguments_, "list (default) | create | revoke tokens/{token} | audit");
    options.Option("--name", &name_, "create: who or what will hold the token, e.g. \"bench-3 uploader\"");
    options.Option("--role", &role_, "create: viewer | operator | engineer | admin");
    options.Option("--expires-days", &expires_days_, "create: the token stops working after this many days");
    options.Option("--resource", &resource_, "audit: only events on this resource, e.g. runs/…");
    options.Option("--of", &of_token_, "audit: only events by this token (tokens/{token})");
    options.Option("--page-size", &page_size_, "list, audit: entries per page (default 50, at most 1000)");
    options.Option("--page-token", &page_token_, "list, audit: the next page");
    options.Flag("--json", &json_, "Print the response as JSON");
    server_.Declare(options);
  }

  int Run(std::ostream& out, std::ostream& err) override {
    const std::string action = arguments_.empty() ? "list" : arguments_.front();
    const size_t expected = action == "revoke" ? 2 : 1;
    if (arguments_.size() > expected || (action != "list" && action != "create" && action != "revoke" && action != "audit")) {
      return UsageError(err, Name(), "expected: list | create | revoke tokens/{token} | audit");
    }
    if (action == "revoke" && arguments_.size() != 2) return UsageError(err, Name(), "revoke: name the token (tokens/{token})");
    stub_ = v1::AccessService::NewStub(server_.Connect());
    if (action == "create") return Create(out, err);
    if (action == "revoke") return Revoke(arguments_[1], out, err);
    if (action == "audit") return Audit(out, err);
    return List(out, err);
  }

 private:
  int Create(std::ostream& out, std::ostream& err) {
    if (name_.empty()) return UsageError(err, Name(), "create: --name is required");
    v1::CreateTokenRequest request;
    v1::Token* token = request.mutable_token();
    token->set_display_name(name_);
    v1::Role role = v1::ROLE_UNSPECIFIED;
    if (!v1::Role_Parse(absl::AsciiStrToUpper(role_), &role) || role == v1::ROLE_UNSPECIFIED) {
      return UsageError(err, Name(), "create: --role is one of viewer, operator, engineer, admin");
    }
    token->set_role(role);
    if (!expires_days_.empty()) {
      double days = 0;
      if (auto s = ParseDouble(expires_days_, "--expires-days", &days);
          !s.ok() || !(days > 0) || days > api::kMaxTokenLifetimeDays) {
        return UsageError(err, Name(),
                          absl::StrCat("create: --expires-days must be a number of days above 0 and at most ",
                                       api::kMaxTokenLifetimeDays, " (ten years)"));
      }
      const absl::Time expiry = absl::Now() + absl::Hours(24.0 * days);
      token->mutable_expire_time()->set_seconds(absl::ToUnixSeconds(expiry));
    }
    auto created = client::CallUnary<v1::CreatedToken>(
        [&](grpc::ClientContext* c, v1::CreatedToken* r) { return stub_->CreateToken(c, request, r); });
    if (!created.ok()) return RequestFailed(err, Name(), "create token", created.status());
    if (json_) return PrintJson(*created, out, err);
    out << created->token().name() << "\n" << created->secret() << "\n";
    err << "insdiag tokens: the secret (second line) is shown only now; give it as --token or $INSDIAG_TOKEN\n";
    return kExitOk;
  }

  int Revoke(const std::string& name, std::ostream& out, std::ostream& err) {
    v1::RevokeTokenRequest request;
    request.set_name(ResourceName("tokens", name));
    auto token = client::CallUnary<v1::Token>(
        [&](grpc::ClientContext* c, v1::Token* r) { return stub_->RevokeToken(c, request, r); });
    if (!token.ok()) return RequestFailed(err, Name(), "revoke " + request.name(), token.status());
    if (json_) return PrintJson(*token, out, err);
    out << token->name() << " revoked " << DateTime(token->revoke_time()) << "\n";
    return kExitOk;
  }

  int List(std::ostream& out, std::ostream& err) {
    v1::ListTokensRequest request;
    int page_size = 0;
    if (auto s = ParseInt(page_size_, "--page-size", &page_size); !s.ok()) return UsageError(err, Name(), std::string(s.message()));
    request.set_page_size(page_size);
    request.set_page_token(page_token_);
    auto response = client::CallUnary<v1::ListTokensResponse>(
        [&](grpc::ClientContext* c, v1::ListTokensResponse* r) { return stub_->ListTokens(c, request, r); });
    if (!response.ok()) return RequestFailed(err, Name(), "list tokens", response.status());
    if (json_) return PrintJson(*response, out, err);
    Table table({"token", "name", "role", "created", "expires", "revoked"});
    for (const auto& t : response->tokens()) {
      table.Add({t.name(), t.display_name(), absl::AsciiStrToLower(v1::Role_Name(t.role())), DateTime(t.create_time()),
                 t.has_expire_time() ? DateTime(t.expire_time()) : "never",
                 t.has_revoke_time() ? DateTime(t.revoke_time()) : ""});
    }
    table.Print(out);
    if (!response->next_page_token().empty()) out << "next page: --page-token " << response->next_page_token() << "\n";
    return kExitOk;
  }

  int Audit(std::ostream& out, std::ostream& err) {
    v1::ListAuditEventsRequest request;
    int page_size = 0;
    if (auto s = ParseInt(page_size_, "--page-size", &page_size); !s.ok()) return UsageError(err, Name(), std::string(s.message()));
    request.set_page_size(page_size);
    request.set_page_token(page_token_);
    request.set_resource(resource_);
    request.set_token(ResourceName("tokens", of_token_));
    auto response = client::CallUnary<v1::ListAuditEventsResponse>(
        [&](grpc::ClientContext* c, v1::ListAuditEventsResponse* r) { return stub_->ListAuditEvents(c, request, r); });
    if (!response.ok()) return RequestFailed(err, Name(), "list audit events", response.status());
    if (json_) return PrintJson(*response, out, err);
    Table table({"time", "who", "role", "method", "resource", "from", "outcome"});
    for (const auto& e : response->audit_events()) {
      table.Add({DateTime(e.event_time()), e.display_name().empty() ? "(no valid token)" : e.display_name(),
                 absl::AsciiStrToLower(v1::Role_Name(e.role())), e.method(), e.resource(), e.peer(), e.code()});
    }
    table.Print(out);
    if (!response->next_page_token().empty()) out << "next page: --page-token " << response->next_page_token() << "\n";
    return kExitOk;
  }

  std::vector<std::string> arguments_;
  std::string name_, role_, expires_days_, resource_, of_token_, page_size_, page_token_;
  bool json_ = false;
  ServerFlags server_;
  std::unique_ptr<v1::AccessService::Stub> stub_;
};

}  // namespace

std::unique_ptr<Verb> MakeVerb_tokens() { return std::make_unique<TokensVerb>(); }

}  // namespace insdiag::cli
