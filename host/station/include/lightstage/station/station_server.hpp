#pragma once
// The station over HTTP (cpp-httplib): a JSON API under /api, the data
// folder's files under /files, read-only. Every answer to a bad request is a
// JSON error {"error": message, "status": code}; nothing a client sends
// crashes the server (bodies over the limit: 413, malformed JSON: 400,
// unknown routes: 404, any exception: 500 with its message).
//
// Access (operator_access.hpp): the token, when one is set, on every /api and
// /files request (header "Authorization: Bearer T", or ?token=T for links);
// the client id in "X-Lightstage-Client". Reads are open to every client with
// the token; actions need control, but for POST /api/dark, which anyone may
// send (darkening the dome is always safe). Every action goes to the audit log
// (but for requests without the token).
//
// Origin: on a loopback address the Host a request names must be loopback
// too (no DNS rebinding), and every POST must carry the client id header (no
// cross-site form posts); both refused with 403.

#include "lightstage/station/audit_log.hpp"
#include "lightstage/station/operator_access.hpp"
#include "lightstage/station/station.hpp"

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

namespace httplib {
class Server;
struct Request;
struct Response;
}  // namespace httplib

namespace lightstage::station {

struct ServerOptions {
  std::string host = "127.0.0.1";
  int port = 8080;                        // 0 = any free port (bind() says which)
  std::string token;                      // empty = none (refused for a non-loopback host)
  std::size_t max_body_bytes = 64 << 10;  // larger request bodies: 413
  std::chrono::milliseconds lease{std::chrono::seconds(15)};
};

class StationServer {
 public:
  // Throws InputError when a non-loopback host comes without a token.
  StationServer(Station& station, ServerOptions options);
  ~StationServer();
  StationServer(const StationServer&) = delete;
  StationServer& operator=(const StationServer&) = delete;

  // Binds the address; returns the port. Throws Error naming the address when it cannot.
  int bind();
  // Serves until stop() (from another thread or a signal handler's thread).
  void run();
  void stop();
  std::string url() const;  // http://HOST:PORT/ (with ?token=T when one is set)

 private:
  void routes();
  void watch_leases();
  void page_routes();  // the page and its script (station_page.cpp)
  // What an action is given: the request's JSON body, the client, and the
  // name the path names (a stack), if any.
  struct Call {
    const nlohmann::json& body;
    const std::string& client;
    std::string target;
  };
  // Runs an action: token, control, audit, JSON answer or JSON error.
  using Action = std::function<nlohmann::json(const Call& call)>;
  void action(const std::string& pattern, const std::string& name, bool needs_control, Action act);
  void read(const std::string& pattern, std::function<nlohmann::json()> answer);
  // Answers a GET: the token checked, the client's lease renewed, refusals as JSON errors.
  void guarded(const httplib::Request& request, httplib::Response& response,
               const std::function<void()>& answer);
  void check_token(const httplib::Request& request) const;
  // Why a request is refused before any route sees it (its Host, its client id), if it is.
  std::optional<std::string> refusal(const httplib::Request& request) const;

  Station& station_;
  ServerOptions options_;
  OperatorAccess access_;
  AuditLog audit_;
  std::unique_ptr<httplib::Server> server_;
  int port_ = 0;
  std::atomic<bool> running_{false}, stop_asked_{false};
  std::mutex preview_mutex_;
  std::string preview_png_;  // the last live-view frame

  std::mutex watch_mutex_;
  std::condition_variable watch_changed_;
  bool stopping_ = false;
  std::thread watcher_;
};

}  // namespace lightstage::station
