#include "insdiag/server/web_page.h"

#include <absl/strings/str_cat.h>

#include <system_error>

#include <httplib.h>

namespace insdiag::server {

bool ServeWebPage(httplib::Server& http, const std::filesystem::path& dir) {
  std::error_code error;
  if (!dir.empty() && std::filesystem::is_regular_file(dir / "index.html", error)) {
    // Module scripts are refused by browsers under any type but JavaScript's.
    http.set_file_extension_and_mimetype_mapping("js", "text/javascript");
    http.set_file_extension_and_mimetype_mapping("mjs", "text/javascript");
    return http.set_mount_point("/", dir.string(), {{"Cache-Control", "no-cache"}});
  }
  const std::string note = absl::StrCat(
      "<!doctype html><meta charset=utf-8><title>insdiag</title>"
      "<p>insdiagd serves no page: ",
      dir.empty() ? std::string("no page directory was given") : absl::StrCat(dir.string(), "/index.html is missing"),
      ".</p><p>Build it with <code>scripts/install-deps.sh &amp;&amp; scripts/build.sh</code> (the page's "
      "charting library comes from clients/web/node_modules), or point <code>insdiagd --web-dir</code> at a "
      "built page. The REST API answers under <a href=\"/v1/runs\">/v1/</a>.</p>\n");
  http.Get("/", [note](const httplib::Request&, httplib::Response& response) {
    response.status = 503;
    response.set_content(note, "text/html; charset=utf-8");
  });
  return false;
}

}  // namespace insdiag::server
