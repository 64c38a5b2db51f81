#include "insdiag/server/path_template.h"

#include <gtest/gtest.h>

namespace insdiag::server {
namespace {

using Bindings = std::map<std::string, std::string>;

PathTemplate Parsed(const std::string& text) {
  auto parsed = PathTemplate::Parse(text);
  EXPECT_TRUE(parsed.ok()) << parsed.status();
  return *parsed;
}

TEST(PathTemplate, LiteralPathMatchesOnlyItself) {
  const auto runs = Parsed("/v1/runs");
  EXPECT_EQ(runs.Match("/v1/runs"), Bindings{});
  EXPECT_FALSE(runs.Match("/v1/runs/x"));
  EXPECT_FALSE(runs.Match("/v1/run"));
}

TEST(PathTemplate, VariableBindsTheResourceName) {
  const auto get = Parsed("/v1/{name=runs/*}");
  EXPECT_EQ(get.Match("/v1/runs/4f3a"), (Bindings{{"name", "runs/4f3a"}}));
  EXPECT_FALSE(get.Match("/v1/runs"));
  EXPECT_FALSE(get.Match("/v1/runs/a/b"));
  EXPECT_FALSE(get.Match("/v1/units/a"));
  // A custom verb belongs to another route, not to the run's id.
  EXPECT_FALSE(get.Match("/v1/runs/4f3a:download"));
}

TEST(PathTemplate, VariableInsideThePathAndCustomVerb) {
  EXPECT_EQ(Parsed("/v1/{parent=units/*}/modules").Match("/v1/units/S-1/modules"),
            (Bindings{{"parent", "units/S-1"}}));
  const auto watch = Parsed("/v1/{name=analyses/*}:watch");
  EXPECT_TRUE(watch.has_verb());
  EXPECT_EQ(watch.Match("/v1/analyses/a1:watch"), (Bindings{{"name", "analyses/a1"}}));
  EXPECT_FALSE(watch.Match("/v1/analyses/a1"));
  EXPECT_EQ(Parsed("/v1/runs:upload").Match("/v1/runs:upload"), Bindings{});
}

TEST(PathTemplate, ShortVariableAndDoubleWildcard) {
  EXPECT_EQ(Parsed("/v1/things/{id}").Match("/v1/things/7"), (Bindings{{"id", "7"}}));
  EXPECT_EQ(Parsed("/v1/{path=files/**}").Match("/v1/files/a/b/c"), (Bindings{{"path", "files/a/b/c"}}));
}

TEST(PathTemplate, MalformedTemplatesAreRefused) {
  for (const char* bad : {"v1/runs", "/v1/{name=runs/*", "/v1/{=runs/*}", "/v1/**/x", "/v1//runs"}) {
    EXPECT_FALSE(PathTemplate::Parse(bad).ok()) << bad;
  }
}

}  // namespace
}  // namespace insdiag::server
