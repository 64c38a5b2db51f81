// GET /v1/openapi.json through a real server, against the route table the
// gateway serves from: every route is in the document, and every operation
// of the document is served (an anonymous request reaches the token check,
// not the gateway's "no method answers").
#include "insdiag/server/openapi.h"

#include <absl/strings/ascii.h>
#include <gmock/gmock.h>
#include <google/api/annotations.pb.h>
#include <google/protobuf/descriptor.h>
#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include <regex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "insdiag/server/path_template.h"
#include "server_fixture.h"

namespace insdiag::testing {
namespace {

using ::testing::HasSubstr;

class OpenApiTest : public ServerTest {
 protected:
  google::protobuf::Struct Document() {
    httplib::Client viewer("127.0.0.1", server_->http_port());
    viewer.set_bearer_token_auth(MakeToken(pool(), v1::VIEWER).c_str());
    auto answer = viewer.Get("/v1/openapi.json");
    EXPECT_TRUE(answer);
    google::protobuf::Struct document;
    if (!answer) return document;
    EXPECT_EQ(answer->status, 200);
    EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(answer->body, &document).ok()) << answer->body.substr(0, 200);
    return document;
  }
};

TEST(OpenApiPathTest, WritesEachWildcardAsAParameterNamedAfterItsCollection) {
  EXPECT_EQ(server::OpenApiPath("/v1/{name=runs/*}"), "/v1/runs/{runsId}");
  EXPECT_EQ(server::OpenApiPath("/v1/{name=analyses/*}:watch"), "/v1/analyses/{analysesId}:watch");
  EXPECT_EQ(server::OpenApiPath("/v1/{unit_type=unitTypes/*}/parameterTrend"),
            "/v1/unitTypes/{unitTypesId}/parameterTrend");
  EXPECT_EQ(server::OpenApiPath("/v1/runs"), "/v1/runs");
}

TEST_F(OpenApiTest, AnswersOnlyAValidToken) {
  httplib::Client anonymous("127.0.0.1", server_->http_port());
  auto refused = anonymous.Get("/v1/openapi.json");
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 401);
}

// The gateway's own route table against the document, both ways: every
// route it serves is an operation of the document, every operation is a
// route it serves, and a request to each operation's path reaches it (the
// token check, not the gateway's "no method answers").
TEST_F(OpenApiTest, EveryRouteTheGatewayServesIsInTheDocumentAndEveryOperationIsServed) {
  const google::protobuf::Struct document = Document();
  ASSERT_TRUE(document.fields().contains("paths"));
  EXPECT_EQ(document.fields().at("openapi").string_value(), "3.0.3");
  std::set<std::pair<std::string, std::string>> operations;  // (verb, OpenAPI path)
  for (const auto& [path, methods] : document.fields().at("paths").struct_value().fields()) {
    for (const auto& [verb, operation] : methods.struct_value().fields())
      operations.emplace(verb, path);
  }
  const std::vector<server::RestRoute> routes = server_->rest_routes();
  std::set<std::pair<std::string, std::string>> served;
  std::set<std::string> methods_served;
  for (const auto& route : routes) {
    const std::string verb = absl::AsciiStrToLower(route.http_method);
    const std::string path = server::OpenApiPath(route.path_template);
    EXPECT_TRUE(served.emplace(verb, path).second) << "served twice: " << verb << " " << path;
    EXPECT_TRUE(operations.contains({verb, path}))
        << route.method << ": " << verb << " " << path << " is not in the document";
    if (!route.method.empty()) methods_served.insert(route.method);
  }
  for (const auto& [verb, path] : operations) {
    EXPECT_TRUE(served.contains({verb, path}))
        << verb << " " << path << " is in the document but not served";
  }
  EXPECT_EQ(served.size(), operations.size());

  // Every http rule of every served service is a route, LiveRunService's too.
  int rules = 0;
  for (const std::string& name : server::InsdiagServer::ServiceNames()) {
    const auto* service =
        google::protobuf::DescriptorPool::generated_pool()->FindServiceByName(name);
    ASSERT_NE(service, nullptr) << name;
    for (int m = 0; m < service->method_count(); ++m) {
      if (!service->method(m)->options().HasExtension(google::api::http)) continue;
      ++rules;
      EXPECT_TRUE(methods_served.contains(service->method(m)->full_name()))
          << service->method(m)->full_name();
    }
  }
  EXPECT_EQ(rules, 43);
  EXPECT_TRUE(methods_served.contains("insdiag.v1.LiveRunService.WatchLiveRun"));
  EXPECT_TRUE(served.contains({"get", "/v1/runs/{runsId}:download"}));
  EXPECT_TRUE(served.contains({"get", "/metrics"}));

  // Each operation answered at its path: the route the gateway matches
  // first (its own order) is the operation's, and it reaches the token check.
  httplib::Client anonymous("127.0.0.1", server_->http_port());
  for (const auto& [verb, path] : operations) {
    const std::string concrete = std::regex_replace(path, std::regex(R"(\{[^}]*\})"), "x");
    const server::RestRoute* first = nullptr;
    for (const auto& route : routes) {
      auto parsed = server::PathTemplate::Parse(route.path_template);
      ASSERT_TRUE(parsed.ok()) << route.path_template;
      if (absl::AsciiStrToLower(route.http_method) == verb && parsed->Match(concrete)) {
        first = &route;
        break;
      }
    }
    ASSERT_NE(first, nullptr) << verb << " " << concrete << " matches no route";
    EXPECT_EQ(server::OpenApiPath(first->path_template), path)
        << verb << " " << concrete << " reaches another route";
    auto send = [&]() -> httplib::Result {
      if (verb == "delete") return anonymous.Delete(concrete.c_str());
      if (verb == "post") return anonymous.Post(concrete.c_str(), "{}", "application/json");
      return anonymous.Get(concrete.c_str());
    };
    auto answer = send();
    ASSERT_TRUE(answer) << verb << " " << concrete;
    EXPECT_THAT(answer->body, ::testing::Not(HasSubstr("no method answers")))
        << verb << " " << concrete;
    const bool open = path == "/healthz";
    EXPECT_EQ(answer->status, open ? 200 : 401)
        << verb << " " << concrete << ": " << answer->body.substr(0, 200);
  }
  EXPECT_EQ(operations.size(), 47u);
}

}  // namespace
}  // namespace insdiag::testing
