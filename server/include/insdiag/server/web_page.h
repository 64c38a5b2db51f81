// The page (clients/web) on insdiagd's HTTP port, beside the REST gateway:
// GET / and its assets are files of one directory, which the build fills
// (clients/web/CMakeLists.txt). The page calls the REST API only.
#pragma once

#include <filesystem>

namespace httplib {
class Server;
}  // namespace httplib

namespace insdiag::server {

// Serves the files of `dir` (`/` is dir/index.html) ahead of the REST routes,
// with `Cache-Control: no-cache` so a rebuilt page is seen on reload. Without
// dir/index.html, GET / answers 503 with how to build the page, and false is
// returned. Call before RestGateway::Register.
bool ServeWebPage(httplib::Server& http, const std::filesystem::path& dir);

}  // namespace insdiag::server
