// One route of the REST face (rest_gateway.h), as the gateway serves it.
#pragma once

#include <string>

namespace insdiag::server {

struct RestRoute {
  std::string http_method;    // GET, POST, DELETE, …
  std::string path_template;  // a google.api.http template, "/v1/{name=runs/*}:watch"
  std::string method;  // the gRPC method it calls, "insdiag.v1.AnalysisService.WatchAnalysis";
                       // empty for the gateway's own routes (/healthz, /metrics, …)
};

}  // namespace insdiag::server
