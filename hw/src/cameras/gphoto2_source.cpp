// The gphoto2: shot source: a camera libgphoto2 drives over USB (PTP), its
// settings set through configuration widgets (gphoto2_settings.hpp reads
// their strings) and its files downloaded as they are taken
// (download_file.hpp writes them).
//
// libgphoto2 is not thread-safe per camera and a Camera* is used from one
// thread at a time, as the ShotSource contract already asks of the caller.
#include "lightstage/hw/gphoto2_source.hpp"

#include "download_file.hpp"
#include "gphoto2_settings.hpp"

#include <gphoto2/gphoto2.h>
#include <unistd.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <deque>
#include <limits>
#include <set>
#include <thread>
#include <utility>

namespace lightstage::hw {

namespace {

using camera::CameraError;
using Kind = camera::CameraError::Kind;
using gphoto2::Setting;

// Owners of libgphoto2's objects; each calls the library's own release.
template <auto Release>
struct Releaser {
  template <typename T>
  void operator()(T* p) const {
    Release(p);
  }
};
using ListPtr = std::unique_ptr<CameraList, Releaser<gp_list_unref>>;
using PortListPtr = std::unique_ptr<GPPortInfoList, Releaser<gp_port_info_list_free>>;
using AbilitiesListPtr = std::unique_ptr<CameraAbilitiesList, Releaser<gp_abilities_list_free>>;
using WidgetPtr = std::unique_ptr<CameraWidget, Releaser<gp_widget_free>>;
using FilePtr = std::unique_ptr<CameraFile, Releaser<gp_file_unref>>;
using GpCameraPtr = std::unique_ptr<Camera, Releaser<gp_camera_unref>>;
using ContextPtr = std::unique_ptr<GPContext, Releaser<gp_context_unref>>;
using EventData = std::unique_ptr<void, Releaser<std::free>>;

// A GPContext whose error and message callbacks collect the library's own
// explanation ("PTP Access Denied", "Could not claim the USB device"), which
// the error codes alone do not carry.
class Context {
 public:
  Context() : context_(gp_context_new()) {
    if (!context_) throw CameraError("gphoto2: cannot create a libgphoto2 context (out of memory)");
    gp_context_set_error_func(context_.get(), &Context::collect, this);
    gp_context_set_message_func(context_.get(), &Context::collect, this);
  }
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  GPContext* get() const { return context_.get(); }
  // The text collected since the last call, then forgotten.
  std::string take() { return std::exchange(text_, {}); }

 private:
  static void collect(GPContext*, const char* text, void* self) {
    auto* context = static_cast<Context*>(self);
    if (!text || !*text) return;
    if (!context->text_.empty()) context->text_ += "; ";
    context->text_ += text;
  }

  ContextPtr context_;
  std::string text_;
};

constexpr std::string_view kAutomounterAdvice =
    "another program holds the camera: most often the desktop's auto-mounter (gvfs-gphoto2-volume-monitor; "
    "unmount the camera with `gio mount -u gphoto2://...` as `gio mount -l` lists it, or stop it for good "
    "with `systemctl --user mask --now gvfs-gphoto2-volume-monitor`), or another gphoto2, darktable or "
    "Entangle; see hw/docs/cameras.md";

// Every libgphoto2 failure as a CameraError: the URI, what was being done,
// the library's name for the code and its own text, and what to do.
[[noreturn]] void throw_gp(const std::string& uri, std::string_view operation, int code, std::string text,
                           bool capturing = false, const std::string& seen = {}) {
  Kind kind = Kind::kFailed;
  std::string advice;
  switch (code) {
    case GP_ERROR_IO_USB_CLAIM:
    case GP_ERROR_IO_LOCK:
      kind = Kind::kBusy;
      advice = kAutomounterAdvice;
      break;
    case GP_ERROR_CAMERA_BUSY:
      kind = Kind::kBusy;
      advice = "the camera is busy (still writing the last shot, in a menu or in playback); try again";
      break;
    case GP_ERROR_MODEL_NOT_FOUND:
    case GP_ERROR_UNKNOWN_PORT:
      kind = Kind::kNotFound;
      advice = seen;
      break;
    case GP_ERROR_NO_SPACE:
      advice = "the camera's memory card is full: free or change the card";
      break;
    case GP_ERROR_IO_USB_FIND:
    case GP_ERROR_IO:
    case GP_ERROR_IO_READ:
    case GP_ERROR_IO_WRITE:
      kind = Kind::kDisconnected;
      advice = "the camera went away (unplugged, switched off, or asleep: turn auto power off off)";
      break;
    case GP_ERROR_TIMEOUT:
      kind = Kind::kTimeout;
      break;
    case GP_ERROR_NOT_SUPPORTED:
      kind = Kind::kUnsupported;
      if (capturing) {
        advice =
            "the camera refuses to shoot over USB: set its mode dial to M, and turn auto-review and live "
            "view off where the model needs it (see hw/docs/cameras.md)";
      }
      break;
    default:
      break;
  }
  std::string message = fmt::format("{}: {}: {}", uri, operation, gp_result_as_string(code));
  if (!text.empty()) message += fmt::format(" ({})", text);
  if (!advice.empty()) message += "; " + advice;
  throw CameraError(kind, message);
}

struct Detected {
  std::string model;
  std::string port;
};

// The cameras gp_camera_autodetect lists; throws only when the library fails.
std::vector<Detected> autodetect(Context& context, const std::string& uri) {
  CameraList* raw = nullptr;
  if (const int code = gp_list_new(&raw); code < GP_OK) throw_gp(uri, "create a list", code, context.take());
  ListPtr list(raw);
  const int count = gp_camera_autodetect(list.get(), context.get());
  if (count < GP_OK) throw_gp(uri, "detect cameras", count, context.take());
  std::vector<Detected> found;
  for (int i = 0; i < count; ++i) {
    const char* model = nullptr;
    const char* port = nullptr;
    gp_list_get_name(list.get(), i, &model);
    gp_list_get_value(list.get(), i, &port);
    if (model && port) found.push_back({model, port});
  }
  return found;
}

std::string seen_text(const std::vector<Detected>& found) {
  if (found.empty()) {
    return "libgphoto2 detects no camera (is it on, connected by USB, set to PTP / \"PC remote\" mode, and "
           "not held by the desktop's auto-mounter? `gphoto2 --auto-detect` shows what it sees)";
  }
  std::string text = "cameras: ";
  for (std::size_t i = 0; i < found.size(); ++i) {
    text += fmt::format("{}{} on {}", i ? ", " : "", found[i].model, found[i].port);
  }
  return text;
}

class Gphoto2Source final : public camera::ShotSource {
 public:
  Gphoto2Source(const camera::CameraUri& uri, const std::filesystem::path& download_dir)
      : ShotSource(uri.uri), download_dir_(download_dir) {
    std::optional<std::string> model_option;
    for (const auto& [key, value] : uri.options) {
      if (key == "download") {
        download_dir_ = value;
      } else if (key == "model") {
        model_option = value;
      } else {
        fail("camera URI '{}': unknown option '{}' (gphoto2: takes download, model)", uri.uri, key);
      }
    }
    check_download_dir(download_dir_, this->uri());
    choose_camera(uri, model_option);
    open_camera();
    keep_shots_on_card();
  }

  ~Gphoto2Source() override {
    if (camera_) gp_camera_exit(camera_.get(), context_.get());
  }

  camera::CameraInfo info() const override { return {uri(), model_, "libgphoto2 " + port_}; }

  bool software_trigger() const override { return true; }

  camera::ShotSettings apply(const camera::ShotSettings& wanted) override {
    const bool any = wanted.exposure_us || wanted.iso || wanted.f_number || wanted.image_format;
    if (any) {
      WidgetPtr root = config_tree();
      if (wanted.exposure_us) {
        set_numeric(root.get(), Setting::kShutter, *wanted.exposure_us, gphoto2::parse_shutter_us,
                    gphoto2::describe_shutter_us(*wanted.exposure_us));
      }
      if (wanted.iso) {
        set_numeric(root.get(), Setting::kIso, *wanted.iso, gphoto2::parse_iso,
                    fmt::format("{:g}", *wanted.iso));
      }
      if (wanted.f_number) {
        set_numeric(root.get(), Setting::kAperture, *wanted.f_number, gphoto2::parse_f_number,
                    fmt::format("f/{:g}", *wanted.f_number));
      }
      if (wanted.image_format) {
        auto [widget, name, choices] = choice_widget(root.get(), Setting::kImageFormat);
        const auto index = gphoto2::choice_by_name(choices, *wanted.image_format);
        if (!index) {
          throw CameraError(Kind::kUnsupported,
                            fmt::format("{}: image format '{}' is none the camera offers ({})", uri(),
                                        *wanted.image_format, gphoto2::describe_choices(choices)));
        }
        set_choice(widget, name, Setting::kImageFormat, choices[*index]);
      }
    }
    return read_back();
  }

  void start() override {
    pending_.clear();
    taken_.clear();
    triggered_ = false;
    // Events queued before now are files from before start(): read and drop them.
    constexpr int kMaxStale = 200;
    for (int i = 0; i < kMaxStale; ++i) {
      CameraEventType type = GP_EVENT_UNKNOWN;
      void* data = nullptr;
      const int code = gp_camera_wait_for_event(camera_.get(), 0, &type, &data, context_.get());
      EventData owned(data);
      if (code == GP_ERROR_NOT_SUPPORTED) {
        context_.take();
        break;  // no events on this camera: trigger() is the only way to shoot
      }
      if (code < GP_OK) throw_gp(uri(), "read the camera's events", code, context_.take());
      if (type == GP_EVENT_TIMEOUT) break;
    }
    started_ = true;
  }

  void stop() override {
    started_ = false;
    pending_.clear();
  }

  void trigger() override {
    if (!started_) throw CameraError(fmt::format("{}: trigger() before start()", uri()));
    CameraFilePath path{};
    const int code = gp_camera_capture(camera_.get(), GP_CAPTURE_IMAGE, &path, context_.get());
    if (code < GP_OK) throw_gp(uri(), "capture", code, context_.take(), /*capturing=*/true);
    pending_.push_back(path);
    triggered_ = true;
  }

  std::optional<camera::ArrivedFile> wait_file(std::chrono::milliseconds timeout) override {
    if (!started_) throw CameraError(fmt::format("{}: wait_file() before start()", uri()));
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      while (!pending_.empty()) {
        const CameraFilePath path = pending_.front();
        pending_.pop_front();
        // A capture's file can come back as a FILE_ADDED event too: one download each.
        if (!taken_.insert(std::string(path.folder) + "/" + path.name).second) continue;
        return download(path);
      }
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      CameraEventType type = GP_EVENT_UNKNOWN;
      void* data = nullptr;
      const auto wait_ms = std::clamp<std::int64_t>(left.count(), 0, std::numeric_limits<int>::max());
      const int code =
          gp_camera_wait_for_event(camera_.get(), static_cast<int>(wait_ms), &type, &data, context_.get());
      EventData owned(data);
      if (code == GP_ERROR_NOT_SUPPORTED) {
        const std::string text = context_.take();
        // Files of trigger() were all announced by the capture itself: nothing more comes.
        if (triggered_) {
          std::this_thread::sleep_until(deadline);
          return std::nullopt;
        }
        throw CameraError(Kind::kUnsupported,
                          fmt::format("{}: the camera reports no new files over USB (libgphoto2: {}); only "
                                      "shots fired by trigger() arrive, not those of its remote-release port",
                                      uri(), text));
      }
      if (code < GP_OK) throw_gp(uri(), "wait for the camera's events", code, context_.take());
      if (type == GP_EVENT_FILE_ADDED && data) pending_.push_back(*static_cast<const CameraFilePath*>(data));
      if (pending_.empty() && std::chrono::steady_clock::now() >= deadline) return std::nullopt;
    }
  }

 private:
  void choose_camera(const camera::CameraUri& uri, const std::optional<std::string>& model_option) {
    const std::vector<Detected> found = autodetect(context_, this->uri());
    const std::string& target = uri.target;
    if (target.empty()) {
      if (found.empty())
        throw CameraError(Kind::kNotFound, fmt::format("{}: no camera; {}", uri.uri, seen_text(found)));
      model_ = model_option.value_or(found.front().model);
      port_ = found.front().port;
      return;
    }
    if (target.find(':') != std::string::npos) {  // a port: model names hold no colon
      const auto it =
          std::find_if(found.begin(), found.end(), [&](const Detected& d) { return d.port == target; });
      if (it == found.end() && !model_option) {
        throw CameraError(Kind::kNotFound, fmt::format("{}: no camera on port '{}'; {} (a port autodetection "
                                                       "does not list needs ?model=MODEL)",
                                                       uri.uri, target, seen_text(found)));
      }
      port_ = target;
      model_ = model_option ? *model_option : it->model;
      return;
    }
    if (model_option) fail("camera URI '{}': give either a model or ?model=, not both", uri.uri);
    std::vector<Detected> matches;
    for (const auto& d : found) {
      if (d.model == target) matches.push_back(d);
    }
    if (matches.empty()) {
      throw CameraError(Kind::kNotFound,
                        fmt::format("{}: no camera of model '{}'; {}", uri.uri, target, seen_text(found)));
    }
    if (matches.size() > 1) {
      std::string ports;
      for (const auto& m : matches) ports += (ports.empty() ? "" : ", ") + ("gphoto2:" + m.port);
      fail("camera URI '{}': {} cameras are a {}; name one by its port: {}", uri.uri, matches.size(), target,
           ports);
    }
    model_ = matches.front().model;
    port_ = matches.front().port;
  }

  void open_camera() {
    CameraAbilitiesList* raw_abilities = nullptr;
    if (const int code = gp_abilities_list_new(&raw_abilities); code < GP_OK)
      throw_gp(uri(), "create the driver list", code, context_.take());
    AbilitiesListPtr abilities_list(raw_abilities);
    if (const int code = gp_abilities_list_load(abilities_list.get(), context_.get()); code < GP_OK)
      throw_gp(uri(), "load libgphoto2's camera drivers", code, context_.take());
    const int model_index = gp_abilities_list_lookup_model(abilities_list.get(), model_.c_str());
    if (model_index < GP_OK) {
      throw_gp(uri(), fmt::format("find a driver for model '{}'", model_), model_index, context_.take(),
               false, "libgphoto2 has no camera of that name (`gphoto2 --list-cameras` lists them)");
    }
    CameraAbilities abilities{};
    gp_abilities_list_get_abilities(abilities_list.get(), model_index, &abilities);

    GPPortInfoList* raw_ports = nullptr;
    if (const int code = gp_port_info_list_new(&raw_ports); code < GP_OK)
      throw_gp(uri(), "create the port list", code, context_.take());
    PortListPtr ports(raw_ports);
    if (const int code = gp_port_info_list_load(ports.get()); code < GP_OK)
      throw_gp(uri(), "load libgphoto2's port drivers", code, context_.take());
    const int port_index = gp_port_info_list_lookup_path(ports.get(), port_.c_str());
    if (port_index < GP_OK) {
      throw_gp(uri(), fmt::format("find port '{}'", port_), port_index, context_.take(), false,
               "ports look like usb:BUS,DEV, ptpip:ADDRESS or disk:PATH");
    }
    GPPortInfo port_info = nullptr;
    gp_port_info_list_get_info(ports.get(), port_index, &port_info);

    Camera* raw_camera = nullptr;
    if (const int code = gp_camera_new(&raw_camera); code < GP_OK)
      throw_gp(uri(), "create a camera", code, context_.take());
    GpCameraPtr camera(raw_camera);
    if (const int code = gp_camera_set_abilities(camera.get(), abilities); code < GP_OK)
      throw_gp(uri(), "set the camera's driver", code, context_.take());
    if (const int code = gp_camera_set_port_info(camera.get(), port_info); code < GP_OK)
      throw_gp(uri(), "set the camera's port", code, context_.take());
    if (const int code = gp_camera_init(camera.get(), context_.get()); code < GP_OK)
      throw_gp(uri(), fmt::format("open the {} on {}", model_, port_), code, context_.take());
    camera_ = std::move(camera);
  }

  // Tethered shots go to the memory card rather than the camera's RAM: each
  // file then stays on the card as well as being downloaded, so a failed
  // download or a host crash mid-session never loses a shot, and RAW+JPEG
  // pairs are written whole before they are announced. The price is card
  // space; a full card is reported as such.
  void keep_shots_on_card() {
    CameraWidget* raw = nullptr;
    const int code = gp_camera_get_single_config(camera_.get(), "capturetarget", &raw, context_.get());
    if (code < GP_OK) {
      context_.take();
      return;  // no such setting (or no settings at all): the camera decides
    }
    WidgetPtr widget(raw);
    const std::vector<std::string> choices = choices_of(widget.get());
    const auto card = gphoto2::memory_card_choice(choices);
    if (!card) return;  // e.g. a camera without a card slot
    set_choice(widget.get(), "capturetarget", Setting::kCaptureTarget, choices[*card]);
  }

  // The camera's whole configuration tree; nullptr when it offers none.
  WidgetPtr config_tree() {
    CameraWidget* root = nullptr;
    const int code = gp_camera_get_config(camera_.get(), &root, context_.get());
    if (code == GP_ERROR_NOT_SUPPORTED) {
      last_config_text_ = context_.take();
      return nullptr;
    }
    if (code < GP_OK) throw_gp(uri(), "read the camera's settings", code, context_.take());
    return WidgetPtr(root);
  }

  // The first widget of `setting`'s names in `root`, and its name.
  std::pair<CameraWidget*, std::string_view> find_widget(CameraWidget* root, Setting setting) const {
    if (!root) return {nullptr, {}};
    for (std::string_view name : gphoto2::widget_names(setting)) {
      CameraWidget* child = nullptr;
      if (gp_widget_get_child_by_name(root, std::string(name).c_str(), &child) == GP_OK && child)
        return {child, name};
    }
    return {nullptr, {}};
  }

  static std::vector<std::string> choices_of(CameraWidget* widget) {
    std::vector<std::string> choices;
    const int count = gp_widget_count_choices(widget);
    for (int i = 0; i < count; ++i) {
      const char* choice = nullptr;
      if (gp_widget_get_choice(widget, i, &choice) == GP_OK && choice) choices.emplace_back(choice);
    }
    return choices;
  }

  struct ChoiceWidget {
    CameraWidget* widget;
    std::string_view name;
    std::vector<std::string> choices;
  };

  ChoiceWidget choice_widget(CameraWidget* root, Setting setting) {
    const auto [widget, name] = find_widget(root, setting);
    if (!widget) {
      std::string names;
      for (std::string_view n : gphoto2::widget_names(setting))
        names += fmt::format("{}{}", names.empty() ? "" : ", ", n);
      std::string why = root ? fmt::format("it has none of the settings {}", names)
                             : fmt::format("it offers no settings over USB{}",
                                           last_config_text_.empty() ? "" : " (" + last_config_text_ + ")");
      throw CameraError(Kind::kUnsupported,
                        fmt::format("{}: cannot set the {}: {}", uri(), gphoto2::to_string(setting), why));
    }
    CameraWidgetType type = GP_WIDGET_TEXT;
    gp_widget_get_type(widget, &type);
    if (type != GP_WIDGET_RADIO && type != GP_WIDGET_MENU) {
      throw CameraError(Kind::kUnsupported,
                        fmt::format("{}: the camera's {} setting '{}' is not a list of choices", uri(),
                                    gphoto2::to_string(setting), name));
    }
    return {widget, name, choices_of(widget)};
  }

  void set_numeric(CameraWidget* root, Setting setting, double wanted,
                   std::optional<double> (*parse)(std::string_view), const std::string& wanted_text) {
    auto [widget, name, choices] = choice_widget(root, setting);
    const auto index = gphoto2::nearest_choice(choices, wanted, parse, gphoto2::max_log2_ratio(setting));
    if (!index) {
      throw CameraError(
          Kind::kUnsupported,
          fmt::format("{}: {} {} is not within half a stop of any the camera offers ({})", uri(),
                      gphoto2::to_string(setting), wanted_text, gphoto2::describe_choices(choices)));
    }
    set_choice(widget, name, setting, choices[*index]);
  }

  void set_choice(CameraWidget* widget, std::string_view name, Setting setting, const std::string& choice) {
    if (const int code = gp_widget_set_value(widget, choice.c_str()); code < GP_OK)
      throw_gp(uri(), fmt::format("set the {} to '{}'", gphoto2::to_string(setting), choice), code,
               context_.take());
    const int code =
        gp_camera_set_single_config(camera_.get(), std::string(name).c_str(), widget, context_.get());
    if (code < GP_OK)
      throw_gp(uri(), fmt::format("set the {} to '{}'", gphoto2::to_string(setting), choice), code,
               context_.take());
  }

  // What the camera reports now, each setting it has and can state as a value.
  camera::ShotSettings read_back() {
    camera::ShotSettings now;
    WidgetPtr root = config_tree();
    if (!root) return now;
    auto text_of = [&](Setting setting) -> std::optional<std::string> {
      const auto [widget, name] = find_widget(root.get(), setting);
      if (!widget) return std::nullopt;
      const char* value = nullptr;
      if (gp_widget_get_value(widget, &value) != GP_OK || !value) return std::nullopt;
      return std::string(value);
    };
    if (auto t = text_of(Setting::kShutter)) now.exposure_us = gphoto2::parse_shutter_us(*t);
    if (auto t = text_of(Setting::kIso)) now.iso = gphoto2::parse_iso(*t);
    if (auto t = text_of(Setting::kAperture)) now.f_number = gphoto2::parse_f_number(*t);
    now.image_format = text_of(Setting::kImageFormat);
    return now;
  }

  camera::ArrivedFile download(const CameraFilePath& path) {
    const std::filesystem::path written = write_new_file(download_dir_, path.name, uri(), [&](int fd) {
      const int own_fd = ::dup(fd);  // the CameraFile closes the descriptor it is given
      if (own_fd < 0) throw CameraError(fmt::format("{}: cannot duplicate a file descriptor", uri()));
      CameraFile* raw = nullptr;
      if (const int code = gp_file_new_from_fd(&raw, own_fd); code < GP_OK) {
        ::close(own_fd);
        throw_gp(uri(), "create a file", code, context_.take());
      }
      FilePtr file(raw);
      const int code = gp_camera_file_get(camera_.get(), path.folder, path.name, GP_FILE_TYPE_NORMAL,
                                          file.get(), context_.get());
      if (code < GP_OK)
        throw_gp(uri(), fmt::format("download {}/{}", path.folder, path.name), code, context_.take());
    });
    return {written, camera::clock_now_ns(camera::ClockDomain::kMonotonic)};
  }

  Context context_;  // declared first: the camera is closed through it
  GpCameraPtr camera_;
  std::filesystem::path download_dir_;
  std::string model_;
  std::string port_;
  std::string last_config_text_;
  bool started_ = false;
  bool triggered_ = false;              // trigger() succeeded since start()
  std::deque<CameraFilePath> pending_;  // captured or announced, not yet downloaded
  std::set<std::string> taken_;         // "folder/name" of every file downloaded since start()
};

}  // namespace

std::vector<camera::CameraInfo> list_gphoto2_cameras() {
  std::vector<camera::CameraInfo> cameras;
  std::vector<Detected> found;
  try {
    Context context;
    found = autodetect(context, "gphoto2:");
  } catch (const CameraError&) {
    return cameras;  // a library that cannot enumerate lists nothing
  }
  for (const auto& d : found) {
    const auto same_model =
        std::count_if(found.begin(), found.end(), [&](const Detected& o) { return o.model == d.model; });
    cameras.push_back({"gphoto2:" + (same_model > 1 ? d.port : d.model), d.model, "libgphoto2 " + d.port});
  }
  return cameras;
}

std::unique_ptr<camera::ShotSource> open_gphoto2_source(const camera::CameraUri& uri,
                                                        const std::filesystem::path& download_dir) {
  if (uri.scheme != "gphoto2") fail("camera URI '{}': not a gphoto2: URI", uri.uri);
  return std::make_unique<Gphoto2Source>(uri, download_dir);
}

}  // namespace lightstage::hw
