#include "lightstage/host/capture/folder_source.hpp"

#include "io/file_extension.hpp"
#include "lightstage/common/clock.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/raw_image.hpp"
#include "lightstage/host/io/tiff_image.hpp"

#include <algorithm>
#include <charconv>
#include <deque>
#include <map>
#include <set>
#include <thread>

namespace fs = std::filesystem;

namespace lightstage {
namespace {

bool is_camera_image(const fs::path& path) {
  const std::string name = path.filename().string();
  if (name.empty() || name.front() == '.') return false;  // hidden: a tethering program's temporary
  const std::string extension = io::lower_extension(path);
  return io::is_raw_file(path) || io::is_tiff_file(path) || extension == ".jpg" || extension == ".jpeg" ||
         extension == ".png";
}

class FolderSource final : public camera::ShotSource {
 public:
  FolderSource(const camera::CameraUri& uri, fs::path folder, std::chrono::milliseconds poll)
      : ShotSource(uri.uri), folder_(std::move(folder)), poll_(poll) {}

  camera::CameraInfo info() const override { return {uri(), "files in " + folder_.string(), "folder"}; }
  bool software_trigger() const override { return false; }
  camera::ShotSettings apply(const camera::ShotSettings&) override { return {}; }  // set on the camera

  void start() override {
    known_.clear();
    pending_.clear();
    for (const auto& [path, state] : scan()) known_.insert(path);
    started_ = true;
  }
  void stop() override { started_ = false; }

  void trigger() override {
    throw camera::CameraError(
        camera::CameraError::Kind::kUnsupported,
        uri() + ": a folder cannot fire the camera; its remote port (the rig's trigger) does");
  }

  std::optional<camera::ArrivedFile> wait_file(std::chrono::milliseconds timeout) override {
    if (!started_) throw camera::CameraError(uri() + ": wait_file before start");
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      poll();
      if (!ready_.empty()) {
        camera::ArrivedFile file = std::move(ready_.front());
        ready_.pop_front();
        return file;
      }
      if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
      std::this_thread::sleep_for(
          std::min<std::chrono::nanoseconds>(poll_, deadline - std::chrono::steady_clock::now()));
    }
  }

 private:
  struct State {
    std::uintmax_t size = 0;
    fs::file_time_type time;
    bool operator==(const State&) const = default;
  };
  struct Pending {
    State state;
    std::int64_t since_ns = 0;  // CLOCK_MONOTONIC when it was first seen in this state
  };

  std::map<fs::path, State> scan() const {
    std::map<fs::path, State> found;
    std::error_code ec;
    fs::directory_iterator it(folder_, ec);
    if (ec) {
      throw camera::CameraError(camera::CameraError::Kind::kDisconnected,
                                uri() + ": cannot read " + folder_.string() + ": " + ec.message());
    }
    for (const auto& entry : it) {
      std::error_code e1, e2;
      if (!entry.is_regular_file(e1) || !is_camera_image(entry.path())) continue;
      const State state{entry.file_size(e1), entry.last_write_time(e2)};
      if (!e1 && !e2) found.emplace(entry.path(), state);  // gone meanwhile: seen on the next poll
    }
    return found;
  }

  void poll() {
    std::vector<std::pair<fs::file_time_type, fs::path>> complete;
    const std::int64_t now = monotonic_now_ns();
    const std::int64_t settled_ns = std::chrono::nanoseconds(poll_).count();
    for (const auto& [path, state] : scan()) {
      if (known_.contains(path)) continue;
      const auto it = pending_.find(path);
      if (it == pending_.end() || !(it->second.state == state)) {
        pending_[path] = {state, now};  // new, or still being written
      } else if (state.size > 0 && now - it->second.since_ns >= settled_ns) {
        complete.emplace_back(state.time, path);
        pending_.erase(it);
        known_.insert(path);
      }
    }
    // Several complete in one poll: in the order written (names break ties, cameras number shots).
    std::ranges::sort(complete);
    for (auto& [time, path] : complete) ready_.push_back({std::move(path), now});
  }

  fs::path folder_;
  std::chrono::milliseconds poll_;
  bool started_ = false;
  std::set<fs::path> known_;
  std::map<fs::path, Pending> pending_;
  std::deque<camera::ArrivedFile> ready_;
};

}  // namespace

std::unique_ptr<camera::ShotSource> open_folder_source(const camera::CameraUri& uri) {
  const fs::path folder = uri.target;
  std::error_code ec;
  if (folder.empty()) fail("{}: give the folder the camera's files arrive in (folder:PATH)", uri.uri);
  if (!fs::is_directory(folder, ec)) fail("{}: {} is not a folder", uri.uri, folder.string());
  int poll_ms = 50;
  if (const auto text = uri.option("poll_ms")) {
    const auto [end, err] = std::from_chars(text->data(), text->data() + text->size(), poll_ms);
    if (err != std::errc() || end != text->data() + text->size() || poll_ms < 1 || poll_ms > 10'000)
      fail("{}: poll_ms must be a whole number of milliseconds in 1..10000, got '{}'", uri.uri, *text);
  }
  for (const auto& [key, value] : uri.options) {
    if (key != "poll_ms") fail("{}: unknown option '{}' (folder: takes poll_ms)", uri.uri, key);
  }
  return std::make_unique<FolderSource>(uri, folder, std::chrono::milliseconds(poll_ms));
}

}  // namespace lightstage
