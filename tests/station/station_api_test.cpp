// The station's HTTP API on the simulated dome (its programs as separate
// processes): status, a capture followed to its end, stopped and resumed,
// two operators, the token, bad requests, and LEDs left lit by a vanished operator.
#include "lightstage/station/station_server.hpp"

#include "lightstage/testing/paths.hpp"

#include <fmt/format.h>
#include <httplib.h>
#include <opencv2/imgcodecs.hpp>

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fstream>
#include <thread>
#include <utility>

namespace lightstage::station {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using std::chrono::milliseconds;
using std::chrono::seconds;

struct Answer {
  int status = 0;
  json body;
  std::string text;
  std::string content_type;
};

// The simulated dome (64x64 sphere, no noise), the station and its server on a free port.
class StationUnderTest {
 public:
  explicit StationUnderTest(ServerOptions server_options = {}, const std::string& data_name = "data",
                            int side = 64) {
    StationOptions options;
    options.rig = testing::source_dir() / "hw" / "rigs" / "sim-dome.yaml";
    options.data = testing::scratch_dir() / data_name;
    SimulatedBenchOptions bench;
    bench.scene = "sphere";
    bench.width = side;
    bench.height = side;
    bench.noise = "none";
    bench.programs = testing::bin_dir();
    options.simulated = bench;
    station_ = std::make_unique<Station>(options);
    server_options.port = 0;
    server_ = std::make_unique<StationServer>(*station_, server_options);
    port_ = server_->bind();
    thread_ = std::thread([this] { server_->run(); });
  }
  ~StationUnderTest() {
    server_->stop();
    thread_.join();
  }

  Answer get(const std::string& path, const std::string& client = "tab-a", const std::string& token = "") {
    httplib::Client http("127.0.0.1", port_);
    httplib::Headers headers = {{"X-Lightstage-Client", client}};
    if (!token.empty()) headers.emplace("Authorization", "Bearer " + token);
    return answer(http.Get(path, headers));
  }
  Answer post(const std::string& path, const std::string& body, const std::string& client = "tab-a",
              const std::string& token = "") {
    httplib::Client http("127.0.0.1", port_);
    httplib::Headers headers = {{"X-Lightstage-Client", client}};
    if (!token.empty()) headers.emplace("Authorization", "Bearer " + token);
    return answer(http.Post(path, headers, body, "application/json"));
  }
  Answer post(const std::string& path, const json& body, const std::string& client = "tab-a") {
    return post(path, body.dump(), client);
  }
  // Polls the job (as `client`, which keeps its lease) until it is no longer running.
  json wait_job(const std::string& client = "tab-a", seconds timeout = seconds(120)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    json job;
    do {
      job = get("/api/job", client).body;
      if (job.is_object() && job["state"] != "running") return job;
      std::this_thread::sleep_for(milliseconds(50));
    } while (std::chrono::steady_clock::now() < deadline);
    ADD_FAILURE() << "the job did not end: " << job.dump();
    return job;
  }
  // Polls the job until it has done at least `done` items (or ended); returns its last state.
  json wait_progress(int done, std::chrono::milliseconds poll = milliseconds(5)) {
    const auto deadline = std::chrono::steady_clock::now() + seconds(60);
    json job;
    do {
      job = get("/api/job").body;
      std::this_thread::sleep_for(poll);
    } while (job["state"] == "running" && job["done"].get<int>() < done &&
             std::chrono::steady_clock::now() < deadline);
    return job;
  }
  Station& station() { return *station_; }
  int port() const { return port_; }

 private:
  static Answer answer(const httplib::Result& result) {
    if (!result) return {-1, nullptr, "no answer", ""};
    return {result->status, json::parse(result->body, nullptr, false), result->body,
            result->get_header_value("Content-Type")};
  }

  std::unique_ptr<Station> station_;
  std::unique_ptr<StationServer> server_;
  int port_ = 0;
  std::thread thread_;
};

std::vector<json> audit_lines(const fs::path& data) {
  std::vector<json> lines;
  std::ifstream in(data / "audit.log");
  for (std::string line; std::getline(in, line);) lines.push_back(json::parse(line));
  return lines;
}

const json kCapture = {{"name", "sphere"}, {"exposure_us", 4000}, {"dark_frames", 2}};

TEST(StationApi, StatusIsJsonAndEveryClientMayRead) {
  StationUnderTest station;
  const Answer status = station.get("/api/status", "someone");
  ASSERT_EQ(status.status, 200) << status.text;
  EXPECT_TRUE(status.body["dome"]["connected"].get<bool>()) << status.text;
  EXPECT_EQ(status.body["dome"]["controller"]["state"], "IDLE");
  EXPECT_EQ(status.body["rig"]["leds"], 96);
  EXPECT_EQ(status.body["simulated"]["placed"], "object");
  EXPECT_TRUE(status.body["job"].is_null());
  EXPECT_EQ(station.get("/api/rig").body["leds"].size(), 96u);
  const json methods = station.get("/api/methods").body;
  EXPECT_NE(std::find(methods.begin(), methods.end(), "l2"), methods.end()) << methods.dump();
  EXPECT_EQ(station.get("/api/access", "someone").body["you"], "viewer");
}

TEST(StationApi, ACaptureIsFollowedToItsEndThenSolvedWithItsReport) {
  StationUnderTest station;
  ASSERT_EQ(station.post("/api/control", json{{"name", "Ann"}}).status, 200);
  const Answer started = station.post("/api/capture", kCapture);
  ASSERT_EQ(started.status, 200) << started.text;
  EXPECT_EQ(started.body["kind"], "capture");
  // Followed from a second client (read-only) while it runs: the count only rises.
  std::size_t last = 0;
  bool saw_running = false;
  json job;
  for (int i = 0; i < 4000; ++i) {
    job = station.get("/api/job", "tab-b").body;
    station.get("/api/access", "tab-a");  // the operator's page keeps polling too
    if (job["state"] != "running") break;
    saw_running = true;
    EXPECT_GE(job["done"].get<std::size_t>(), last);
    last = job["done"];
    std::this_thread::sleep_for(milliseconds(20));
  }
  EXPECT_TRUE(saw_running);
  ASSERT_EQ(job["state"], "done") << job.dump();
  EXPECT_EQ(job["done"], 96);
  EXPECT_EQ(job["total"], 96);
  EXPECT_EQ(job["result"]["frames"], 96);
  const json stack = station.get("/api/data").body["stacks"][0];
  EXPECT_EQ(stack["name"], "sphere");
  EXPECT_TRUE(stack["complete"].get<bool>());
  EXPECT_FALSE(stack["resumable"].get<bool>());
  // The same name again is refused: nothing is overwritten.
  const Answer again = station.post("/api/capture", kCapture);
  EXPECT_EQ(again.status, 409) << again.text;

  ASSERT_EQ(station.post("/api/solve", json{{"stack", "sphere"}, {"method", "l2"}}).status, 200);
  const json solved = station.wait_job();
  ASSERT_EQ(solved["state"], "done") << solved.dump();
  const Answer report = station.get("/files/results/sphere-l2/report.html");
  EXPECT_EQ(report.status, 200);
  EXPECT_NE(report.text.find("<html"), std::string::npos);
  EXPECT_EQ(station.get("/files/surfaces/sphere-l2/depth.pfm").status, 200);
  EXPECT_EQ(station.get("/files/results/../../audit.log").status, 404);
  EXPECT_EQ(station.get("/files/results/nothing.png").status, 404);

  // Every action in the audit log, with who asked.
  const auto lines = audit_lines(station.station().data());
  const auto capture =
      std::find_if(lines.begin(), lines.end(), [](const json& l) { return l["action"] == "capture.start"; });
  ASSERT_NE(capture, lines.end());
  EXPECT_EQ((*capture)["outcome"], "ok");
  EXPECT_EQ((*capture)["client"], "tab-a");
  EXPECT_EQ((*capture)["name"], "Ann");
  EXPECT_EQ((*capture)["details"]["name"], "sphere");
  const auto refused =
      std::find_if(capture + 1, lines.end(), [](const json& l) { return l["action"] == "capture.start"; });
  ASSERT_NE(refused, lines.end());
  EXPECT_NE((*refused)["outcome"].get<std::string>().find("refused: stacks/sphere exists"), std::string::npos)
      << refused->dump();
}

TEST(StationApi, AStoppedCaptureKeepsItsFramesAndResumesFromThePage) {
  StationUnderTest station;
  ASSERT_EQ(station.post("/api/control", json{{"name", "Ann"}}).status, 200);
  ASSERT_EQ(station.post("/api/capture", kCapture).status, 200);
  json job = station.wait_progress(20);
  ASSERT_EQ(station.post("/api/job/stop", json::object()).status, 200);
  job = station.wait_job();
  ASSERT_EQ(job["state"], "stopped") << job.dump();
  const json stack = station.get("/api/data").body["stacks"][0];
  EXPECT_GE(stack["frames"].get<int>(), 20);
  EXPECT_LT(stack["frames"].get<int>(), 96);
  EXPECT_FALSE(stack["complete"].get<bool>());
  EXPECT_TRUE(stack["resumable"].get<bool>());
  // Stopped between controller sequences: the dome is dark.
  EXPECT_TRUE(station.get("/api/status").body["dome"]["controller"]["leds_on"].empty());

  ASSERT_EQ(station.post("/api/capture/resume", json{{"name", "sphere"}}).status, 200);
  job = station.wait_job();
  ASSERT_EQ(job["state"], "done") << job.dump();
  EXPECT_EQ(job["result"]["frames"], 96);
  EXPECT_LT(job["result"]["taken_now"].get<int>(), 96);
  EXPECT_TRUE(station.get("/api/data").body["stacks"][0]["complete"].get<bool>());
  EXPECT_EQ(station.post("/api/capture/resume", json{{"name", "unknown"}}).status, 404);
}

TEST(StationApi, DarkPausesARunningCaptureAtOnceKeepingItsFrames) {
  StationUnderTest station;
  ASSERT_EQ(station.post("/api/control", json{{"name", "Ann"}}).status, 200);
  ASSERT_EQ(station.post("/api/capture", kCapture).status, 200);
  json job = station.wait_progress(10);
  ASSERT_EQ(job["state"], "running") << job.dump();
  ASSERT_EQ(station.post("/api/dark", json::object(), "tab-b").status, 200);
  job = station.wait_job();
  EXPECT_EQ(job["state"], "stopped") << job.dump();
  // Asked of the controller now that no job holds it (while one does, the status is its last answer).
  EXPECT_TRUE(station.get("/api/status").body["dome"]["controller"]["leds_on"].empty());
  const json stack = station.get("/api/data").body["stacks"][0];
  EXPECT_GE(stack["frames"].get<int>(), 10);
  EXPECT_LT(stack["frames"].get<int>(), 96);
  EXPECT_TRUE(stack["resumable"].get<bool>());
  EXPECT_TRUE(station.get("/api/status").body["dome"]["connected"].get<bool>()) << "darkening is no failure";
  ASSERT_EQ(station.post("/api/capture/resume", json{{"name", "sphere"}}).status, 200);
  job = station.wait_job();
  ASSERT_EQ(job["state"], "done") << job.dump();
  EXPECT_EQ(job["result"]["frames"], 96);
}

// A stop ends a solve mid-way (from its workers' progress) without taking
// the station down, and leaves no half result behind.
TEST(StationApi, AStoppedSolveLeavesNoHalfResult) {
  StationUnderTest station({}, "data", 160);
  ASSERT_EQ(station.post("/api/control", json{{"name", "Ann"}}).status, 200);
  ASSERT_EQ(
      station.post("/api/capture", json{{"name", "s"}, {"exposure_us", 4000}, {"dark_frames", 0}}).status,
      200);
  ASSERT_EQ(station.wait_job()["state"], "done");
  ASSERT_EQ(station.post("/api/solve", json{{"stack", "s"}, {"method", "biquadratic"}, {"name", "r"}}).status,
            200);
  json job = station.wait_progress(1, milliseconds(2));
  ASSERT_EQ(job["state"], "running") << "the solve ended before it could be stopped: " << job.dump();
  ASSERT_EQ(station.post("/api/job/stop", json::object()).status, 200);
  job = station.wait_job();
  EXPECT_EQ(job["state"], "stopped") << job.dump();
  EXPECT_FALSE(fs::exists(station.station().data() / "results" / "r"));
  EXPECT_FALSE(fs::exists(station.station().data() / "surfaces" / "r"));
  EXPECT_EQ(station.get("/api/status").status, 200);
  // The name is free again.
  ASSERT_EQ(station.post("/api/solve", json{{"stack", "s"}, {"method", "l2"}, {"name", "r"}}).status, 200);
  EXPECT_EQ(station.wait_job()["state"], "done");
}

TEST(StationApi, TwoOperatorsTheSecondReadOnlyUntilTheFirstReleases) {
  StationUnderTest station;
  ASSERT_EQ(station.post("/api/control", json{{"name", "Ann"}}, "tab-a").status, 200);
  const Answer taken = station.post("/api/control", json{{"name", "Bob"}}, "tab-b");
  EXPECT_EQ(taken.status, 409);
  EXPECT_NE(taken.body["error"].get<std::string>().find("Ann"), std::string::npos) << taken.text;
  EXPECT_EQ(station.post("/api/leds", json{{"leds", {{{"id", 1}}}}}, "tab-b").status, 403);
  EXPECT_EQ(station.post("/api/capture", kCapture, "tab-b").status, 403);
  EXPECT_EQ(station.get("/api/status", "tab-b").status, 200);
  EXPECT_EQ(station.get("/api/access", "tab-b").body["operator"], "Ann");
  // Darkening the dome is open to everyone.
  EXPECT_EQ(station.post("/api/dark", json::object(), "tab-b").status, 200);

  const Answer lit = station.post("/api/leds", json{{"leds", {{{"id", 1}}, {{"id", 7}}}}}, "tab-a");
  ASSERT_EQ(lit.status, 200) << lit.text;
  EXPECT_EQ(lit.body["controller"]["leds_on"].size(), 2u) << lit.text;
  EXPECT_EQ(station.post("/api/leds", json{{"leds", {{{"id", 999}}}}}, "tab-a").status, 400);
  // This rig's drivers cannot dim: the controller's refusal comes back as it said it.
  const Answer dimmed = station.post("/api/leds", json{{"leds", {{{"id", 7}, {"level", 0.5}}}}}, "tab-a");
  EXPECT_EQ(dimmed.status, 400);
  EXPECT_NE(dimmed.text.find("cannot dim"), std::string::npos) << dimmed.text;
  // Releasing darkens what that operator lit, and hands over.
  ASSERT_EQ(station.post("/api/control/release", json::object(), "tab-a").status, 200);
  EXPECT_TRUE(station.get("/api/status").body["dome"]["controller"]["leds_on"].empty());
  EXPECT_EQ(station.post("/api/control", json{{"name", "Bob"}}, "tab-b").status, 200);
  EXPECT_EQ(station.get("/api/access", "tab-a").body["you"], "viewer");
}

TEST(StationApi, WithATokenEveryRequestMustCarryIt) {
  ServerOptions options;
  options.token = "4f1c0a7e9b2d4c6f8a0b1c2d3e4f5a6b";
  StationUnderTest station(options);
  EXPECT_EQ(station.get("/api/status").status, 401);
  EXPECT_EQ(station.get("/api/status", "tab-a", "wrong").status, 401);
  EXPECT_EQ(station.post("/api/control", "{}", "tab-a", "").status, 401);
  EXPECT_EQ(station.get("/files/stacks/x").status, 401);
  EXPECT_EQ(station.get("/api/status", "tab-a", options.token).status, 200);
  EXPECT_EQ(station.get("/api/status?token=" + options.token).status, 200);
  EXPECT_EQ(station.post("/api/control", "{\"name\": \"Ann\"}", "tab-a", options.token).status, 200);
  // Whoever reaches the port without the token cannot fill the audit log.
  for (int i = 0; i < 20; ++i) EXPECT_EQ(station.post("/api/dark", "{}", "tab-x", "").status, 401);
  const auto lines = audit_lines(station.station().data());
  ASSERT_FALSE(lines.empty());
  for (const json& line : lines) EXPECT_EQ(line["outcome"], "ok") << line.dump();
}

TEST(StationApi, FilesStayInTheirFoldersAndActionsComeFromThePageOnLoopback) {
  StationUnderTest station;
  ASSERT_EQ(station.post("/api/control", json{{"name", "Ann"}}).status, 200);
  const fs::path result = station.station().data() / "results" / "r";
  fs::create_directories(result);
  std::ofstream(result / "notes.txt") << "kept\n";
  std::ofstream(result / ".bands-1.spill") << "not served\n";
  EXPECT_EQ(station.get("/files/results/r/notes.txt").text, "kept\n");
  // Deep Zoom descriptors, JPEG tiles and scripts get their types, for any viewer reading them from here.
  for (const auto& [name, type] : {std::pair{"normal.dzi", "application/xml"},
                                   {"normal_files/0/0_0.jpg", "image/jpeg"},
                                   {"zoom.js", "text/javascript; charset=utf-8"},
                                   {"report.html", "text/html; charset=utf-8"}}) {
    fs::create_directories((result / name).parent_path());
    std::ofstream(result / name) << "x";
    EXPECT_EQ(station.get(std::string("/files/results/r/") + name).content_type, type) << name;
  }
  for (const char* path :
       {"/files/stacks/../audit.log", "/files/stacks/%2e%2e/audit.log", "/files/results/r/../../audit.log",
        "/files/results/r/.bands-1.spill", "/files/results/../.station/dome/1-object/domed.log",
        "/files/results//etc/passwd"}) {
    const Answer a = station.get(path);
    EXPECT_EQ(a.status, 404) << path << ": " << a.text.substr(0, 200);
  }
  httplib::Client http("127.0.0.1", station.port());
  // A page elsewhere reaching 127.0.0.1 under its own name (DNS rebinding).
  auto rebound = http.Get("/api/status", {{"Host", "rebind.example.org:8080"}, {"X-Lightstage-Client", "x"}});
  ASSERT_TRUE(rebound);
  EXPECT_EQ(rebound->status, 403) << rebound->body;
  EXPECT_NE(rebound->body.find("rebind.example.org"), std::string::npos) << rebound->body;
  auto named = http.Get("/api/status", {{"Host", "127.0.0.1.rebind.example.org"}});
  ASSERT_TRUE(named);
  EXPECT_EQ(named->status, 403);
  auto local = http.Get("/api/status", {{"Host", fmt::format("localhost:{}", station.port())}});
  ASSERT_TRUE(local);
  EXPECT_EQ(local->status, 200);
  // A cross-site form cannot set the client id: actions without it are refused.
  auto form = http.Post("/api/dark", "", "application/x-www-form-urlencoded");
  ASSERT_TRUE(form);
  EXPECT_EQ(form->status, 403) << form->body;
  EXPECT_EQ(station.post("/api/dark", json::object(), "tab-b").status, 200);
}

// A request hidden in the body of a refused one must not be served.
TEST(StationApi, ARefusedRequestsBodyIsNotTakenForAnotherRequest) {
  StationUnderTest station;
  const std::string hidden =
      "POST /api/control HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Lightstage-Client: evil\r\n"
      "Content-Type: application/json\r\nContent-Length: 15\r\n\r\n{\"name\":\"Eve\"}";
  const std::string request =
      "POST /api/control HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: text/plain\r\n"
      "Content-Length: " +
      std::to_string(hidden.size()) + "\r\n\r\n" + hidden;
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(station.port()));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address), 0);
  ASSERT_EQ(::send(fd, request.data(), request.size(), 0), static_cast<ssize_t>(request.size()));
  timeval timeout{1, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  std::string answers;
  char chunk[4096];
  for (ssize_t n; (n = ::recv(fd, chunk, sizeof chunk, 0)) > 0;)
    answers.append(chunk, static_cast<std::size_t>(n));
  ::close(fd);
  EXPECT_NE(answers.find("403"), std::string::npos) << answers;
  EXPECT_EQ(answers.find("HTTP/1.1", 1), std::string::npos) << "a second answer:\n" << answers;
  EXPECT_TRUE(station.get("/api/access").body["operator"].is_null()) << "the hidden request took control";
}

TEST(StationApi, DarkFromAnyTabCutsTheTestSequenceShort) {
  StationUnderTest station;
  ASSERT_EQ(station.post("/api/control", json{{"name", "Ann"}}).status, 200);
  EXPECT_EQ(station.post("/api/test-sequence", json{{"on_us", 5'000'000}}).status, 400);
  EXPECT_EQ(station.post("/api/test-sequence", json{{"pace", 1}}).status, 400);
  // 96 LEDs lit 50 ms each: about 5 s to walk the dome.
  ASSERT_EQ(station.post("/api/test-sequence", json{{"on_us", 50'000}}).status, 200);
  json job = station.wait_progress(3);
  ASSERT_EQ(job["state"], "running") << job.dump();
  // A viewer darkens the dome: the running job must not keep it lit.
  const Answer dark = station.post("/api/dark", json::object(), "tab-b");
  ASSERT_EQ(dark.status, 200) << dark.text;
  job = station.wait_job("tab-a", seconds(10));
  EXPECT_EQ(job["state"], "stopped") << job.dump();
  EXPECT_LT(job["done"].get<int>(), 96);
  EXPECT_TRUE(station.get("/api/status").body["dome"]["controller"]["leds_on"].empty());
  EXPECT_TRUE(station.get("/api/status").body["dome"]["lit"].empty());
  // A finished job is not stopped again; the dome takes hand-lit LEDs again.
  EXPECT_EQ(station.post("/api/job/stop", json::object()).status, 409);
  EXPECT_EQ(station.post("/api/leds", json{{"leds", {{{"id", 7}}}}}).status, 200);
  EXPECT_EQ(station.post("/api/dark", json::object(), "tab-b").status, 200);
  EXPECT_TRUE(station.get("/api/status").body["dome"]["controller"]["leds_on"].empty());
}

TEST(StationApi, NoTokenIsRefusedOffLoopback) {
  StationOptions options;
  options.rig = testing::source_dir() / "hw" / "rigs" / "sim-dome.yaml";
  options.data = testing::scratch_dir() / "data";
  options.controller_uri = "unix:/nonexistent/domed.sock";
  options.camera_uri = "sim:/nonexistent/camera.sock";
  Station station(options);  // a dome that does not answer: the station still starts, and says why
  EXPECT_FALSE(station.status()["dome"]["connected"].get<bool>());
  EXPECT_FALSE(station.status()["dome"]["error"].get<std::string>().empty());
  ServerOptions server;
  server.host = "0.0.0.0";
  EXPECT_THROW(StationServer(station, server), InputError);
}

TEST(StationApi, MalformedUnknownAndOversizedRequestsGetJsonErrors) {
  ServerOptions options;
  options.max_body_bytes = 4096;
  StationUnderTest station(options);
  ASSERT_EQ(station.post("/api/control", json{{"name", "Ann"}}).status, 200);
  const auto is_error = [](const Answer& a, int status) {
    EXPECT_EQ(a.status, status) << a.text;
    EXPECT_TRUE(a.body.is_object() && a.body["error"].is_string() &&
                !a.body["error"].get<std::string>().empty())
        << a.text;
    return a.body.is_object() ? a.body.value("error", "") : "";
  };
  EXPECT_NE(
      is_error(station.post("/api/capture", std::string("{\"name\": \"a\""), "tab-a"), 400).find("not JSON"),
      std::string::npos);
  EXPECT_NE(is_error(station.post("/api/capture", json{{"name", "a"}, {"speed", 1}}), 400).find("speed"),
            std::string::npos);
  EXPECT_NE(is_error(station.post("/api/capture", json{{"name", 5}}), 400).find("capture.name"),
            std::string::npos);
  is_error(station.post("/api/capture", std::string(8192, ' '), "tab-a"), 413);
  is_error(station.post("/api/solve", json{{"stack", "none"}}), 404);
  is_error(station.post("/api/solve", json{{"stack", "none"}, {"method", "magic"}}), 400);
  is_error(station.post("/api/place", json{{"object", "teapot"}}), 400);
  is_error(station.post("/api/job/stop", json::object()), 409);
  is_error(station.get("/api/unknown"), 404);
  is_error(station.post("/api/unknown", json::object()), 404);
  is_error(station.post("/api/preview", json{{"led", 5000}, {"exposure_us", 1000}}), 400);
  // And the server still answers.
  EXPECT_EQ(station.get("/api/status").status, 200);
}

TEST(StationApi, ThePreviewGivesThePictureAndItsFigures) {
  StationUnderTest station;
  ASSERT_EQ(station.post("/api/control", json{{"name", "Ann"}}).status, 200);
  EXPECT_EQ(station.get("/api/preview.png").status, 404);
  const Answer dim = station.post("/api/preview", json{{"led", 1}, {"exposure_us", 500}});
  ASSERT_EQ(dim.status, 200) << dim.text;
  const Answer bright = station.post("/api/preview", json{{"led", 1}, {"exposure_us", 200000}});
  ASSERT_EQ(bright.status, 200) << bright.text;
  EXPECT_EQ(bright.body["width"], 64);
  EXPECT_EQ(bright.body["histogram"].size(), 64u);
  EXPECT_GT(bright.body["mean"].get<double>(), dim.body["mean"].get<double>());
  EXPECT_GT(bright.body["clipped"].get<double>(), dim.body["clipped"].get<double>());
  const Answer png = station.get("/api/preview.png");
  ASSERT_EQ(png.status, 200);
  EXPECT_EQ(png.text.substr(1, 3), "PNG");
  EXPECT_TRUE(station.get("/api/status").body["dome"]["controller"]["leds_on"].empty());
}

TEST(StationApi, LedsLitByHandGoDarkWhenTheirOperatorGoesAway) {
  ServerOptions options;
  options.lease = milliseconds(800);
  StationUnderTest station(options);
  ASSERT_EQ(station.post("/api/control", json{{"name", "Ann"}}).status, 200);
  ASSERT_EQ(station.post("/api/leds", json{{"leds", {{{"id", 3}}}}}).status, 200);
  EXPECT_EQ(station.get("/api/status", "tab-b").body["dome"]["controller"]["leds_on"], json::array({3}));
  // The operator's tab closes: no more requests from it. The LED's own on-time
  // limit (2 s on this rig) must not be what darkens it: the lease is shorter.
  const auto closed = std::chrono::steady_clock::now();
  json status;
  do {
    std::this_thread::sleep_for(milliseconds(100));
    status = station.get("/api/status", "tab-b").body;
  } while (!status["dome"]["controller"]["leds_on"].empty() &&
           std::chrono::steady_clock::now() - closed < seconds(5));
  const double dark_after = std::chrono::duration<double>(std::chrono::steady_clock::now() - closed).count();
  EXPECT_TRUE(status["dome"]["controller"]["leds_on"].empty());
  EXPECT_LT(dark_after, 1.6) << "dark only after " << dark_after << " s";
  EXPECT_EQ(status["dome"]["controller"]["last_fault"], "")
      << "the firmware's limit darkened it, not the station";
  const auto lines = audit_lines(station.station().data());
  EXPECT_TRUE(std::any_of(lines.begin(), lines.end(), [](const json& l) {
    return l["action"] == "dark" && l["details"]["why"] == "the operator's lease lapsed";
  }));
  EXPECT_EQ(station.get("/api/access", "tab-a").body["you"], "viewer");
}

TEST(StationApi, AnAbortedCaptureKeepsItsFramesButIsNotOfferedForResume) {
  StationUnderTest station;
  ASSERT_EQ(station.post("/api/control", json{{"name", "Ann"}}).status, 200);
  ASSERT_EQ(station.post("/api/capture", kCapture).status, 200);
  json job = station.wait_progress(10);
  ASSERT_EQ(station.post("/api/job/abort", json::object()).status, 200);
  job = station.wait_job();
  ASSERT_EQ(job["state"], "stopped") << job.dump();
  EXPECT_NE(job["error"].get<std::string>().find("aborted"), std::string::npos) << job.dump();
  const json stack = station.get("/api/data").body["stacks"][0];
  EXPECT_GE(stack["frames"].get<int>(), 10);
  EXPECT_FALSE(stack["resumable"].get<bool>());
  EXPECT_EQ(station.post("/api/capture/resume", json{{"name", "sphere"}}).status, 404);
}

// The chrome sphere's outline: detected on the stack, drawn by the operator
// (as the stack's mask.png, which the calibration reads), forgotten again.
TEST(StationApi, TheSpheresOutlineIsFoundDrawnAndForgotten) {
  StationUnderTest station;
  ASSERT_EQ(station.post("/api/control", json{{"name", "Ann"}}).status, 200);
  ASSERT_EQ(station.post("/api/place", json{{"object", "chrome-1"}}).status, 200);
  ASSERT_EQ(
      station.post("/api/capture", json{{"name", "c1"}, {"target", "chrome-sphere"}, {"dark_frames", 0}})
          .status,
      200);
  ASSERT_EQ(station.wait_job()["state"], "done");
  const Answer found = station.get("/api/stacks/c1/sphere");
  ASSERT_EQ(found.status, 200) << found.text;
  ASSERT_TRUE(found.body["circle"].is_object()) << found.text;
  EXPECT_EQ(found.body["circle"]["source"], "image");
  EXPECT_FALSE(found.body["drawn"].get<bool>());
  EXPECT_EQ(station.get("/api/stacks/c1/sphere.png").text.substr(1, 3), "PNG");

  const double x = found.body["circle"]["x_px"], y = found.body["circle"]["y_px"];
  const double r = found.body["circle"]["radius_px"];
  const Answer drawn =
      station.post("/api/stacks/c1/sphere", json{{"x_px", x + 3}, {"y_px", y}, {"radius_px", r}});
  ASSERT_EQ(drawn.status, 200) << drawn.text;
  EXPECT_TRUE(drawn.body["drawn"].get<bool>());
  EXPECT_EQ(drawn.body["circle"]["source"], "mask");
  EXPECT_NEAR(drawn.body["circle"]["x_px"].get<double>(), x + 3, 0.3);
  EXPECT_NEAR(drawn.body["circle"]["radius_px"].get<double>(), r, 0.5);
  EXPECT_TRUE(fs::exists(station.station().data() / "stacks" / "c1" / "mask.png"));
  EXPECT_EQ(station.post("/api/stacks/c1/sphere", json{{"x_px", 500}, {"y_px", y}, {"radius_px", r}}).status,
            400);

  const Answer forgotten = station.post("/api/stacks/c1/sphere/forget", json::object());
  ASSERT_EQ(forgotten.status, 200) << forgotten.text;
  EXPECT_FALSE(forgotten.body["drawn"].get<bool>());
  EXPECT_NEAR(forgotten.body["circle"]["x_px"].get<double>(), x, 1e-9);
  EXPECT_FALSE(fs::exists(station.station().data() / "stacks" / "c1" / "mask.png"));
  EXPECT_EQ(station.post("/api/stacks/c1/sphere/forget", json::object()).status, 409);
  EXPECT_EQ(station.get("/api/stacks/nothing/sphere").status, 404);
  EXPECT_EQ(station.get("/api/stacks/..%2F..%2Fetc/sphere").status, 404);

  // A mask the station did not draw is left alone.
  const fs::path mask = station.station().data() / "stacks" / "c1" / "mask.png";
  ASSERT_TRUE(cv::imwrite(mask.string(), cv::Mat(64, 64, CV_8UC1, cv::Scalar(255))));
  const Answer over = station.post("/api/stacks/c1/sphere", json{{"x_px", x}, {"y_px", y}, {"radius_px", r}});
  EXPECT_EQ(over.status, 409) << over.text;
  EXPECT_EQ(cv::countNonZero(cv::imread(mask.string(), cv::IMREAD_GRAYSCALE)), 64 * 64);
  EXPECT_EQ(station.post("/api/stacks/c1/sphere/forget", json::object()).status, 409);
  EXPECT_TRUE(fs::exists(mask));

  // Drawn here, then replaced by the operator's own mask: that one is left alone too.
  fs::remove(mask);
  ASSERT_EQ(station.post("/api/stacks/c1/sphere", json{{"x_px", x}, {"y_px", y}, {"radius_px", r}}).status,
            200);
  ASSERT_TRUE(cv::imwrite(mask.string(), cv::Mat(64, 64, CV_8UC1, cv::Scalar(255))));
  EXPECT_FALSE(station.get("/api/stacks/c1/sphere").body["drawn"].get<bool>());
  EXPECT_EQ(station.post("/api/stacks/c1/sphere", json{{"x_px", x}, {"y_px", y}, {"radius_px", r}}).status,
            409);
  EXPECT_EQ(station.post("/api/stacks/c1/sphere/forget", json::object()).status, 409);
  EXPECT_EQ(cv::countNonZero(cv::imread(mask.string(), cv::IMREAD_GRAYSCALE)), 64 * 64);

  // A crash after an outline's marker was written, before its mask was renamed into place: finished on the
  // next look.
  fs::remove(mask);
  ASSERT_EQ(station.post("/api/stacks/c1/sphere", json{{"x_px", x}, {"y_px", y}, {"radius_px", r}}).status,
            200);
  fs::rename(mask, mask.parent_path() / ".mask-drawn.png");
  EXPECT_TRUE(station.get("/api/stacks/c1/sphere").body["drawn"].get<bool>());
  EXPECT_TRUE(fs::exists(mask));
  EXPECT_FALSE(fs::exists(mask.parent_path() / ".mask-drawn.png"));
  EXPECT_EQ(station.post("/api/stacks/c1/sphere/forget", json::object()).status, 200);
}

}  // namespace
}  // namespace lightstage::station
