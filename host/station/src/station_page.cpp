// The page, its stylesheet and its script, embedded at build time
// (host/station/web: Preact and htm from npm, bundled by esbuild).
#include "lightstage/station/station_server.hpp"

#include "lightstage/station/station_page_files.hpp"

#include <httplib.h>

namespace lightstage::station {
namespace {

// Only what the station serves itself runs or loads: no inline script, no other origin.
constexpr const char* kPolicy =
    "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data:; connect-src 'self'; "
    "base-uri 'none'; form-action 'none'; frame-ancestors 'none'";

void serve(httplib::Server& server, const char* path, const char* body, const char* type) {
  server.Get(path, [body, type](const httplib::Request&, httplib::Response& response) {
    response.set_header("Content-Security-Policy", kPolicy);
    response.set_header("X-Content-Type-Options", "nosniff");
    response.set_header("Cache-Control", "no-cache");
    response.set_content(body, type);
  });
}

}  // namespace

void StationServer::page_routes() {
  serve(*server_, "/", page::kIndexHtml, "text/html; charset=utf-8");
  serve(*server_, "/station.css", page::kStationCss, "text/css; charset=utf-8");
  serve(*server_, "/station.js", page::kStationJs, "text/javascript; charset=utf-8");
  // Browsers ask for it unbidden: no icon, and no 404 in the console.
  server_->Get("/favicon.ico",
               [](const httplib::Request&, httplib::Response& response) { response.status = 204; });
}

}  // namespace lightstage::station
