#include "lightstage/station/station_server.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"

#include <httplib.h>

#include <fmt/format.h>

#include <fstream>
#include <map>
#include <optional>
#include <thread>

namespace lightstage::station {

namespace fs = std::filesystem;

namespace {

void answer_json(httplib::Response& response, int status, const nlohmann::json& body) {
  response.status = status;
  response.set_header("Cache-Control", "no-store");
  response.set_content(body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace),
                       "application/json");
}

void answer_error(httplib::Response& response, int status, const std::string& message) {
  answer_json(response, status, {{"error", message}, {"status", status}});
}

std::string client_of(const httplib::Request& request) {
  std::string client = request.get_header_value("X-Lightstage-Client");
  if (client.size() > 128) client.resize(128);
  return client;
}

nlohmann::json parse_body(const httplib::Request& request) {
  if (request.body.empty()) return nlohmann::json::object();
  try {
    return nlohmann::json::parse(request.body);
  } catch (const nlohmann::json::parse_error& e) {
    throw Refused(400, fmt::format("the body is not JSON: {}", e.what()));
  }
}

const char* content_type(const fs::path& file) {
  static const std::map<std::string, const char*> types = {{".html", "text/html; charset=utf-8"},
                                                           {".json", "application/json"},
                                                           {".js", "text/javascript; charset=utf-8"},
                                                           {".png", "image/png"},
                                                           {".jpg", "image/jpeg"},
                                                           {".jpeg", "image/jpeg"},
                                                           {".dzi", "application/xml"},
                                                           {".xml", "application/xml"},
                                                           {".svg", "image/svg+xml"},
                                                           {".txt", "text/plain; charset=utf-8"},
                                                           {".lp", "text/plain; charset=utf-8"},
                                                           {".log", "text/plain; charset=utf-8"},
                                                           {".csv", "text/csv"}};
  const auto found = types.find(file.extension().string());
  return found == types.end() ? "application/octet-stream" : found->second;
}

// The file under `root` that `relative` names, or nothing when it leaves root,
// names a hidden file or folder (a solve's spill, a partial write) or is not a file.
std::optional<fs::path> contained_file(const fs::path& root, const std::string& relative) {
  for (const auto& part : fs::path(relative)) {
    const std::string name = part.string();
    if (name.empty() || name.front() == '.' || part.is_absolute()) return std::nullopt;
  }
  std::error_code error;
  const fs::path base = fs::canonical(root, error);
  if (error) return std::nullopt;
  const fs::path file = fs::weakly_canonical(base / relative, error);
  if (error) return std::nullopt;
  const auto [end, _] = std::mismatch(base.begin(), base.end(), file.begin(), file.end());
  if (end != base.end() || !fs::is_regular_file(file)) return std::nullopt;
  // What a link inside the folder leads to is held to the same rule.
  for (const auto& part : file.lexically_relative(base)) {
    const std::string name = part.string();
    if (!name.empty() && name.front() == '.') return std::nullopt;
  }
  return file;
}

// The host a request was sent to, without its port ("[::1]:8080" -> "::1").
std::string host_name(const std::string& host_header) {
  if (!host_header.empty() && host_header.front() == '[') {
    const auto close = host_header.find(']');
    return close == std::string::npos ? host_header : host_header.substr(1, close - 1);
  }
  return host_header.substr(0, host_header.find(':'));
}

}  // namespace

StationServer::StationServer(Station& station, ServerOptions options)
    : station_(station),
      options_(std::move(options)),
      access_({options_.token, options_.lease}),
      audit_(station.data() / "audit.log"),
      server_(std::make_unique<httplib::Server>()) {
  if (!is_loopback_address(options_.host) && options_.token.empty())
    throw InputError(fmt::format(
        "--listen {}: any address but loopback needs a token (give --token, or let the station make one)",
        options_.host));
  server_->set_payload_max_length(options_.max_body_bytes);
  routes();
  watcher_ = std::thread([this] { watch_leases(); });
}

StationServer::~StationServer() {
  stop();
  {
    const std::lock_guard lock(watch_mutex_);
    stopping_ = true;
  }
  watch_changed_.notify_all();
  if (watcher_.joinable()) watcher_.join();
}

int StationServer::bind() {
  if (options_.port == 0) {
    port_ = server_->bind_to_any_port(options_.host);
  } else {
    port_ = server_->bind_to_port(options_.host, options_.port) ? options_.port : -1;
  }
  if (port_ <= 0)
    throw Error(fmt::format("cannot listen on {}:{} (in use, or not an address of this machine)",
                            options_.host, options_.port));
  return port_;
}

void StationServer::run() {
  running_ = true;
  if (!stop_asked_) server_->listen_after_bind();
  running_ = false;
}

// httplib's stop() does nothing until the server listens: a stop asked for
// before that (a signal right at start) waits for it, or keeps run() from listening.
void StationServer::stop() {
  stop_asked_ = true;
  while (running_ && !server_->is_running()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  server_->stop();
}

std::string StationServer::url() const {
  const std::string host =
      options_.host.find(':') != std::string::npos ? "[" + options_.host + "]" : options_.host;
  std::string url = fmt::format("http://{}:{}/", host, port_);
  if (!options_.token.empty()) url += "?token=" + options_.token;
  return url;
}

// An operator who lit LEDs by hand and went away (a closed tab, a lost
// network) leaves them lit no longer than the lease.
// Tried again every tick until the dome is dark; the log says the first try and how it ended.
void StationServer::watch_leases() {
  std::unique_lock lock(watch_mutex_);
  bool darkening = false;
  std::string last_outcome;
  while (!watch_changed_.wait_for(lock, std::chrono::milliseconds(250), [this] { return stopping_; })) {
    if (access_.lapsed(Clock::now())) darkening = true;
    if (!darkening) continue;
    if (!station_.lit_by_hand()) {
      darkening = false;
      last_outcome.clear();
      continue;
    }
    AuditEntry entry{"", "station", "", "dark", {{"why", "the operator's lease lapsed"}}, "ok"};
    try {
      station_.dark();
    } catch (const std::exception& e) {
      entry.outcome = fmt::format("failed (tried again): {}", e.what());
    }
    if (entry.outcome != last_outcome) {
      audit_.record(entry);
      if (entry.outcome != "ok")
        logger("station")->warn("could not darken the LEDs of an operator who went away: {}", entry.outcome);
    }
    last_outcome = entry.outcome;
  }
}

// The page's origin: on loopback, a request must name a loopback host, so a
// page elsewhere cannot reach the station through a name that resolves to
// 127.0.0.1 (DNS rebinding); off loopback the token guards it. Actions must
// carry the client id, a header no cross-site form can set.
std::optional<std::string> StationServer::refusal(const httplib::Request& request) const {
  if (is_loopback_address(options_.host)) {
    if (!request.has_header("Host")) return "the request names no Host";
    const std::string host = host_name(request.get_header_value("Host"));
    if (!is_loopback_address(host) && host != options_.host)
      return fmt::format("this station answers on loopback only, not to the host '{}'", host);
  }
  if (request.method == "POST" && client_of(request).empty())
    return "actions need the page's client id (header X-Lightstage-Client)";
  return std::nullopt;
}

void StationServer::check_token(const httplib::Request& request) const {
  std::string presented = request.get_param_value("token");
  const std::string header = request.get_header_value("Authorization");
  if (header.rfind("Bearer ", 0) == 0) presented = header.substr(7);
  access_.check_token(presented);
}

void StationServer::guarded(const httplib::Request& request, httplib::Response& response,
                            const std::function<void()>& answer) {
  try {
    if (const auto refused = refusal(request)) throw Refused(403, *refused);
    check_token(request);
    access_.touch(client_of(request), Clock::now());
    answer();
  } catch (const Refused& e) {
    answer_error(response, e.status(), e.what());
  } catch (const InputError& e) {
    answer_error(response, 400, e.what());
  }
}

void StationServer::read(const std::string& pattern, std::function<nlohmann::json()> answer) {
  server_->Get(pattern, [this, answer](const httplib::Request& request, httplib::Response& response) {
    guarded(request, response, [&] { answer_json(response, 200, answer()); });
  });
}

void StationServer::action(const std::string& pattern, const std::string& name, bool needs_control,
                           Action act) {
  server_->Post(pattern, [this, name, needs_control, act](const httplib::Request& request,
                                                          httplib::Response& response) {
    const std::string client = client_of(request);
    AuditEntry entry{client, "", request.remote_addr, name, nlohmann::json::object(), "ok"};
    // Checked here, with the body read, not before routing: a body left unread
    // on a kept-alive connection would be taken for the next request.
    const auto refused = refusal(request);
    if (refused) {
      answer_error(response, 403, *refused);
      return;  // not an operator's action: not recorded
    }
    try {
      check_token(request);
      const nlohmann::json body = parse_body(request);
      entry.details = body;
      const std::string target = request.matches.size() > 1 ? request.matches[1].str() : std::string();
      if (!target.empty()) entry.details = {{"target", target}, {"body", body}};
      if (needs_control) access_.require_operator(client, Clock::now());
      answer_json(response, 200, act({body, client, target}));
    } catch (const Refused& e) {
      entry.outcome = fmt::format("refused: {}", e.what());
      answer_error(response, e.status(), e.what());
    } catch (const InputError& e) {
      entry.outcome = fmt::format("refused: {}", e.what());
      answer_error(response, 400, e.what());
    } catch (const std::exception& e) {
      entry.outcome = fmt::format("failed: {}", e.what());
      answer_error(response, 500, e.what());
    }
    // Requests without the token are not the station's operators: they are
    // refused, not recorded (the log cannot be filled by whoever reaches the port).
    if (response.status == 401) return;
    entry.name = access_.name_of(client);
    audit_.record(entry);
  });
}

void StationServer::routes() {
  server_->set_exception_handler(
      [](const httplib::Request&, httplib::Response& response, std::exception_ptr thrown) {
        std::string message = "internal error";
        try {
          std::rethrow_exception(thrown);
        } catch (const std::exception& e) {
          message = e.what();
        } catch (...) {
        }
        answer_error(response, 500, message);
      });
  // httplib's own refusals (no route, body too large, bad request line) as JSON too.
  server_->set_error_handler([](const httplib::Request& request, httplib::Response& response) {
    if (!response.body.empty()) return;
    std::string message = fmt::format("{} {}: no such resource", request.method, request.path);
    if (response.status == 413) message = "the request body is too large";
    if (response.status == 400) message = "malformed request";
    answer_error(response, response.status, message);
  });

  page_routes();
  read("/api/status", [this] { return station_.status(); });
  server_->Get("/api/access", [this](const httplib::Request& request, httplib::Response& response) {
    guarded(request, response,
            [&] { answer_json(response, 200, access_.to_json(client_of(request), Clock::now())); });
  });
  read("/api/rig", [this] { return station_.rig_json(); });
  read("/api/data", [this] { return station_.data_json(); });
  read("/api/methods", [this] { return nlohmann::json(station_.methods()); });
  read("/api/job", [this] { return station_.job_json(); });

  action("/api/control", "control.take", false, [this](const Call& call) {
    std::string name = call.body.is_object() && call.body.contains("name") && call.body["name"].is_string()
                           ? call.body["name"].get<std::string>()
                           : std::string();
    if (name.size() > 64) name.resize(64);
    access_.take(call.client, name, Clock::now());
    return access_.to_json(call.client, Clock::now());
  });
  action("/api/control/release", "control.release", false, [this](const Call& call) {
    access_.release(call.client);
    if (station_.lit_by_hand()) station_.dark();  // what this operator lit goes dark with them
    return access_.to_json(call.client, Clock::now());
  });
  action("/api/leds", "leds.set", true, [this](const Call& call) {
    station_.set_leds(leds_request(call.body));
    return station_.status()["dome"];
  });
  action("/api/dark", "dark", false, [this](const Call&) {
    station_.dark();
    return station_.status()["dome"];
  });
  action("/api/place", "place", true, [this](const Call& call) {
    if (!call.body.contains("object") || !call.body["object"].is_string())
      throw Refused(400, "place: the field 'object' is needed (\"object\", \"chrome-1\", ...)");
    station_.place(call.body["object"].get<std::string>());
    return station_.status();
  });
  action("/api/preview", "preview", true, [this](const Call& call) {
    Preview preview = station_.preview(preview_request(call.body));
    const std::lock_guard lock(preview_mutex_);
    preview_png_ = std::move(preview.png);
    return preview.stats;
  });
  server_->Get("/api/preview.png", [this](const httplib::Request& request, httplib::Response& response) {
    guarded(request, response, [&] {
      const std::lock_guard lock(preview_mutex_);
      if (preview_png_.empty()) throw Refused(404, "no preview taken yet");
      response.set_header("Cache-Control", "no-store");
      response.set_content(preview_png_, "image/png");
    });
  });
  action("/api/test-sequence", "test-sequence", true,
         [this](const Call& call) { return station_.start_test_sequence(test_sequence_request(call.body)); });
  action("/api/capture", "capture.start", true,
         [this](const Call& call) { return station_.start_capture(capture_request(call.body)); });
  action("/api/capture/resume", "capture.resume", true, [this](const Call& call) {
    if (!call.body.contains("name") || !call.body["name"].is_string())
      throw Refused(400, "resume: the field 'name' (the stack to complete) is needed");
    return station_.resume_capture(call.body["name"].get<std::string>());
  });
  server_->Get(R"(/api/stacks/([^/]+)/sphere)",
               [this](const httplib::Request& request, httplib::Response& response) {
                 guarded(request, response,
                         [&] { answer_json(response, 200, station_.sphere(request.matches[1].str())); });
               });
  server_->Get(R"(/api/stacks/([^/]+)/sphere\.png)",
               [this](const httplib::Request& request, httplib::Response& response) {
                 guarded(request, response, [&] {
                   response.set_header("Cache-Control", "no-store");
                   response.set_content(station_.sphere_png(request.matches[1].str()), "image/png");
                 });
               });
  action(R"(/api/stacks/([^/]+)/sphere)", "sphere.draw", true,
         [this](const Call& call) { return station_.set_sphere(call.target, sphere_request(call.body)); });
  action(R"(/api/stacks/([^/]+)/sphere/forget)", "sphere.forget", true,
         [this](const Call& call) { return station_.forget_sphere(call.target); });
  action("/api/calibrate", "calibration.start", true,
         [this](const Call& call) { return station_.start_calibration(calibration_request(call.body)); });
  action("/api/solve", "solve.start", true,
         [this](const Call& call) { return station_.start_solve(solve_request(call.body)); });
  action("/api/export", "export.start", true, [this](const Call& call) {
    const nlohmann::json& body = call.body;
    if (!body.is_object() || !body.contains("result") || !body["result"].is_string() ||
        !body.contains("format") || !body["format"].is_string())
      throw Refused(400, "export: the fields 'result' and 'format' (ptm or hsh) are needed");
    return station_.start_export(body["result"].get<std::string>(), body["format"].get<std::string>());
  });
  action("/api/job/stop", "job.stop", true, [this](const Call&) {
    station_.stop_job();
    return station_.job_json();
  });
  action("/api/job/abort", "job.abort", true, [this](const Call&) {
    station_.stop_job(true);
    return station_.job_json();
  });

  server_->Get(R"(/files/((stacks|calibrations|results|surfaces|exports)/(.+)))",
               [this](const httplib::Request& request, httplib::Response& response) {
                 guarded(request, response, [&] {
                   const auto file =
                       contained_file(station_.data() / request.matches[2].str(), request.matches[3].str());
                   if (!file) throw Refused(404, fmt::format("no file {}", request.matches[1].str()));
                   const auto size = static_cast<std::size_t>(fs::file_size(*file));
                   auto in = std::make_shared<std::ifstream>(*file, std::ios::binary);
                   response.set_content_provider(
                       size, content_type(*file),
                       [in](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
                         std::vector<char> chunk(std::min<std::size_t>(length, 1 << 20));
                         in->seekg(static_cast<std::streamoff>(offset));
                         in->read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
                         if (in->gcount() <= 0) return false;
                         return sink.write(chunk.data(), static_cast<std::size_t>(in->gcount()));
                       });
                 });
               });
}

}  // namespace lightstage::station
