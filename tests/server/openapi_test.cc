// GET /v1/openapi.json through a real server: every REST route of the
// services' http rules is in the document, and every operation of the
// document is served (an anonymous request reaches the token check, not the
// gateway's "no method answers").
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <google/api/annotations.pb.h>
#include <google/protobuf/descriptor.h>
#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>

#include <regex>
#include <string>
#include <vector>

#include "insdiag/server/openapi.h"
#include "server_fixture.h"

namespace insdiag::testing {
namespace {

using ::testing::HasSubstr;

const std::vector<std::string> kServices = {"insdiag.v1.RunService", "insdiag.v1.AnalysisService",
                                            "insdiag.v1.KnowledgeService", "insdiag.v1.FleetService",
                                            "insdiag.v1.AccessService"};

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

TEST_F(OpenApiTest, EveryRestRouteIsInTheDocument) {
  const google::protobuf::Struct document = Document();
  ASSERT_TRUE(document.fields().contains("paths"));
  const auto& paths = document.fields().at("paths").struct_value().fields();
  EXPECT_EQ(document.fields().at("openapi").string_value(), "3.0.3");
  int routes = 0;
  const auto* pool = google::protobuf::DescriptorPool::generated_pool();
  for (const std::string& name : kServices) {
    const auto* service = pool->FindServiceByName(name);
    ASSERT_NE(service, nullptr) << name;
    for (int m = 0; m < service->method_count(); ++m) {
      const auto* method = service->method(m);
      ASSERT_TRUE(method->options().HasExtension(google::api::http)) << method->full_name() << " has no REST form";
      const auto& rule = method->options().GetExtension(google::api::http);
      std::string verb, path;
      switch (rule.pattern_case()) {
        case google::api::HttpRule::kGet: verb = "get", path = rule.get(); break;
        case google::api::HttpRule::kPost: verb = "post", path = rule.post(); break;
        case google::api::HttpRule::kDelete: verb = "delete", path = rule.delete_(); break;
        case google::api::HttpRule::kPatch: verb = "patch", path = rule.patch(); break;
        case google::api::HttpRule::kPut: verb = "put", path = rule.put(); break;
        default: continue;
      }
      ++routes;
      const std::string openapi_path = server::OpenApiPath(path);
      ASSERT_TRUE(paths.contains(openapi_path)) << method->full_name() << ": " << openapi_path << " missing";
      EXPECT_TRUE(paths.at(openapi_path).struct_value().fields().contains(verb))
          << method->full_name() << ": " << verb << " " << openapi_path << " missing";
    }
  }
  EXPECT_GE(routes, 35);
  EXPECT_TRUE(paths.contains("/v1/runs/{runsId}:download"));
  EXPECT_TRUE(paths.contains("/metrics"));
}

TEST_F(OpenApiTest, EveryOperationOfTheDocumentIsServed) {
  const google::protobuf::Struct document = Document();
  ASSERT_TRUE(document.fields().contains("paths"));
  httplib::Client anonymous("127.0.0.1", server_->http_port());
  int operations = 0;
  for (const auto& [path, methods] : document.fields().at("paths").struct_value().fields()) {
    const std::string concrete = std::regex_replace(path, std::regex(R"(\{[^}]*\})"), "x");
    for (const auto& [verb, operation] : methods.struct_value().fields()) {
      ++operations;
      auto send = [&]() -> httplib::Result {
        if (verb == "delete") return anonymous.Delete(concrete.c_str());
        if (verb == "post") return anonymous.Post(concrete.c_str(), "{}", "application/json");
        if (verb == "patch") return anonymous.Patch(concrete.c_str(), "{}", "application/json");
        if (verb == "put") return anonymous.Put(concrete.c_str(), "{}", "application/json");
        return anonymous.Get(concrete.c_str());
      };
      auto answer = send();
      ASSERT_TRUE(answer) << verb << " " << concrete;
      EXPECT_THAT(answer->body, ::testing::Not(HasSubstr("no method answers"))) << verb << " " << concrete;
      const bool open = path == "/healthz";
      EXPECT_EQ(answer->status, open ? 200 : 401) << verb << " " << concrete << ": " << answer->body.substr(0, 200);
    }
  }
  EXPECT_GE(operations, 39);
}

}  // namespace
}  // namespace insdiag::testing
