// The REST face's request parsing: a path template (as in a google.api.http
// rule), a path matched against it, query parameters and a JSON body turned
// into a request message. Input lines: template, path, query string, then
// the body. Refused or accepted, never a crash.
#include <absl/strings/str_split.h>

#include <cstdint>
#include <string>
#include <vector>

#include "insdiag/server/path_template.h"
#include "insdiag/v1/access.pb.h"
#include "insdiag/v1/analyses.pb.h"
#include "insdiag/v1/runs.pb.h"
#include "rest_request.h"

// Last: httplib.h pulls in <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> lines = absl::StrSplit(input, absl::MaxSplits('\n', 3));
  lines.resize(4);
  auto path_template = insdiag::server::PathTemplate::Parse(lines[0]);
  std::map<std::string, std::string> bindings;
  if (path_template.ok()) {
    if (auto matched = path_template->Match(lines[1])) bindings = *matched;
  }
  httplib::Request http;
  http.body = lines[3];
  for (absl::string_view pair : absl::StrSplit(lines[2], '&', absl::SkipEmpty())) {
    std::pair<std::string, std::string> kv = absl::StrSplit(pair, absl::MaxSplits('=', 1));
    http.params.emplace(kv.first, kv.second);
  }
  // Three shapes of request: a nested message body, the whole body, a list's scalars.
  insdiag::v1::CreateAnalysisRequest create;
  (void)insdiag::server::BuildRequest("analysis", bindings, http, create);
  insdiag::v1::CreateTokenRequest token;
  (void)insdiag::server::BuildRequest("*", bindings, http, token);
  insdiag::v1::ListRunsRequest list;
  (void)insdiag::server::BuildRequest("", bindings, http, list);
  return 0;
}
