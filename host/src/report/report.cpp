#include "lightstage/host/report/report.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/common/version.hpp"
#include "lightstage/host/calibration/light_calibration.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/mask.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/row_reader.hpp"
#include "lightstage/host/io/solve_folder_rows.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/reflectance/bipolynomial_model.hpp"
#include "lightstage/host/report/light_statistics.hpp"
#include "lightstage/host/report/viewer_data.hpp"
#include "report/html.hpp"
#include "report/maps.hpp"
#include "report/result_maps.hpp"
#include "report/svg.hpp"
#include "report_web_assets.hpp"
#include "util/atomic_file.hpp"
#include "util/utc_time.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <numbers>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace lightstage::report {

namespace fs = std::filesystem;

namespace {

nlohmann::json read_json_file(const fs::path& path) {
  std::ifstream in(path);
  if (!in) fail("{}: cannot open", path.string());
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    fail("{}: not valid JSON: {}", path.string(), e.what());
  }
}

// A path named inside a JSON file: as written, else relative to `base`.
std::optional<fs::path> resolve(const std::string& named, const fs::path& base) {
  if (named.empty()) return std::nullopt;
  const fs::path p(named);
  if (fs::exists(p)) return p;
  if (p.is_relative() && fs::exists(base / p)) return base / p;
  return std::nullopt;
}

// "file" of a JSON value that is either a path string or an object naming one.
std::string named_file(const nlohmann::json& value) {
  if (value.is_string()) return value.get<std::string>();
  if (value.is_object() && value.contains("file") && value["file"].is_string())
    return value["file"].get<std::string>();
  return {};
}

std::string figure(const std::string& uri, const std::string& alt, const std::string& caption,
                   const std::string& cls = "map") {
  return fmt::format("<figure><img class=\"{}\" src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>\n",
                     cls, uri, escape_html(alt), caption);
}

std::string note(const std::string& text) { return "<p class=\"note\">" + escape_html(text) + "</p>\n"; }

double azimuth_deg(const Vec3& d) { return std::fmod(std::atan2(d.y(), d.x()) * kDeg + 360.0, 360.0); }
double elevation_deg(const Vec3& d) { return std::asin(std::clamp(d.normalized().z(), -1.0, 1.0)) * kDeg; }

std::string percent(double share) { return format_number(100.0 * share, 3) + "%"; }

// Everything the sections read, gathered once.
struct Inputs {
  fs::path result_dir;
  nlohmann::json summary = nlohmann::json::object();
  std::optional<fs::path> stack_dir;
  std::optional<ImageStack> stack;  // without ground truth (read by rows: result_maps.hpp)
  std::optional<cv::Rect> crop;     // of the stack, a `solve --crop` result's
  std::optional<calibration::LightCalibration> calibration;
  std::optional<fs::path> calibration_file;
  std::vector<std::string> notes;
};

// The page's sections, kept as they come and joined once at the end: the
// viewer's data (tens of MB for a large result) is then copied once, not at
// every section appended after it.
class Page {
 public:
  void section(const std::string& id, const std::string& title, std::string body) {
    sections_.push_back(id);
    nav_ += fmt::format("<a href=\"#{}\">{}</a>", id, escape_html(title));
    pieces_.push_back(fmt::format("<section id=\"{}\">\n<h2>{}</h2>\n", id, escape_html(title)));
    pieces_.push_back(std::move(body));
    pieces_.push_back("</section>\n");
  }
  const std::vector<std::string>& sections() const { return sections_; }
  const std::string& nav() const { return nav_; }
  std::size_t body_size() const {
    std::size_t size = 0;
    for (const auto& piece : pieces_) size += piece.size();
    return size;
  }
  void append_body(std::string& out) const {
    for (const auto& piece : pieces_) out += piece;
  }

 private:
  std::vector<std::string> sections_;
  std::string nav_;
  std::vector<std::string> pieces_;
};

// A result of `solve --crop` covers summary.json's "crop" [x, y, w, h] of the
// stack: its frames and mask are cut to it (the ground truth as it is read). Returns the region.
cv::Rect cut_to_crop(ImageStack& stack, const nlohmann::json& crop) {
  if (!crop.is_array() || crop.size() != 4 ||
      !std::all_of(crop.begin(), crop.end(), [](const auto& v) { return v.is_number_integer(); }))
    fail("summary.json: crop must be [x, y, width, height], got {}", crop.dump());
  const cv::Rect region(crop[0].get<int>(), crop[1].get<int>(), crop[2].get<int>(), crop[3].get<int>());
  const auto cut = [&](cv::Mat& map, const char* what) {
    if (map.empty()) return;
    if ((region & cv::Rect({0, 0}, map.size())) != region)
      fail("summary.json: crop {} reaches outside the stack's {}x{} {}", crop.dump(), map.cols, map.rows,
           what);
    map = map(region).clone();
  };
  for (Frame& frame : stack.frames) {
    cut(frame.image, "frames");
    cut(frame.dark, "dark frames");
  }
  cut(stack.mask, "mask");
  return region;
}

void load_inputs(Inputs& in, const io::SolveFolder& folder, const ReportOptions& options) {
  in.summary = folder.summary;
  if (!fs::exists(in.result_dir / "summary.json")) {
    in.notes.push_back(
        "No summary.json in the result folder: the solver's settings and numbers are not shown.");
  }

  // The input stack.
  if (options.stack) {
    if (!fs::is_directory(*options.stack)) fail("--stack {}: not a folder", options.stack->string());
    in.stack_dir = *options.stack;
  } else if (const std::string input = in.summary.value("input", std::string()); !input.empty()) {
    in.stack_dir = resolve(input, in.result_dir);
    if (!in.stack_dir) {
      in.notes.push_back(
          fmt::format("The input stack named in summary.json ('{}') was not found from here: light "
                      "directions and per-light "
                      "statistics are omitted (give it with --stack).",
                      input));
    }
  } else {
    in.notes.push_back(
        "summary.json names no input stack: light directions and per-light statistics are omitted.");
  }
  if (in.stack_dir) {
    io::LoadOptions load;
    load.min_images = 1;
    // Only statistics the solve did not record need the frames' pixels.
    load.frame_pixels = options.light_statistics &&
                        (options.shadow_threshold.has_value() || !in.summary.contains("light_statistics"));
    load.load_ground_truth = false;  // read a band at a time (result_maps.hpp)
    try {
      in.stack = io::load_stack(*in.stack_dir, load);
      if (const auto crop = in.summary.find("crop"); crop != in.summary.end())
        in.crop = cut_to_crop(*in.stack, *crop);
    } catch (const InputError& e) {
      in.stack.reset();
      if (options.stack) throw;
      in.notes.push_back(
          fmt::format("The input stack could not be read ({}); its sections are omitted.", e.what()));
    }
  }

  // The light calibration.
  std::optional<fs::path> calibration_file;
  if (options.calibration) {
    calibration_file = *options.calibration;
  } else if (fs::exists(in.result_dir / "calibration.json")) {
    calibration_file = in.result_dir / "calibration.json";
  } else if (const auto it = in.summary.find("calibration"); it != in.summary.end()) {
    calibration_file = resolve(named_file(*it), in.result_dir);
  }
  if (!calibration_file && in.stack_dir && fs::exists(*in.stack_dir / "manifest.json")) {
    const auto manifest = read_json_file(*in.stack_dir / "manifest.json");
    if (const auto it = manifest.find("calibration"); it != manifest.end())
      calibration_file = resolve(named_file(*it), *in.stack_dir);
  }
  if (calibration_file) {
    try {
      in.calibration = calibration::read_calibration(*calibration_file);
      in.calibration_file = calibration_file;
    } catch (const InputError& e) {
      if (options.calibration) throw;
      in.notes.push_back(fmt::format("The light calibration could not be read ({}).", e.what()));
    }
  }
}

std::string header_html(const Inputs& in) {
  const auto& s = in.summary;
  std::string html =
      fmt::format("<h1>Lightstage report: {}</h1>\n",
                  escape_html(fs::absolute(in.result_dir).lexically_normal().filename().string()));
  std::string line;
  if (s.contains("method"))
    line += fmt::format("method <b>{}</b>", escape_html(s["method"].get<std::string>()));
  if (s.contains("pixels_solved") && s.contains("pixels_in_mask"))
    line += fmt::format(" · {} of {} pixels solved", s["pixels_solved"].dump(), s["pixels_in_mask"].dump());
  if (s.contains("width") && s.contains("height"))
    line += fmt::format(" · {}×{}", s["width"].dump(), s["height"].dump());
  if (s.contains("seconds") && s["seconds"].is_number())
    line += fmt::format(" · {} s", format_number(s["seconds"].get<double>(), 3));
  if (!line.empty()) html += "<p>" + line + "</p>\n";
  if (s.contains("message") && s["message"].is_string())
    html += "<p>" + escape_html(s["message"].get<std::string>()) + "</p>\n";
  std::string provenance = "result " + escape_html(in.result_dir.string());
  if (s.contains("input") && s["input"].is_string())
    provenance += " · input " + escape_html(s["input"].get<std::string>());
  if (s.contains("time") && s["time"].is_string())
    provenance += " · solved " + escape_html(s["time"].get<std::string>());
  provenance +=
      " · report by lightstage " + std::string(kVersion) + ", " + escape_html(util::utc_timestamp());
  html += "<p>" + provenance + "</p>\n";
  return html;
}

std::string viewer_section(const SurfaceModel& model, const Inputs& in) {
  std::vector<Vec3> lights;
  if (in.stack)
    for (const auto& frame : in.stack->frames) lights.push_back(frame.light_direction);
  const ViewerPayload payload = encode_viewer_payload(model, lights, Vec3(-0.4, 0.4, 0.82));
  std::string model_text =
      model.kind == ShadingKind::kBiPolynomial
          ? fmt::format("the fitted {} model: ρ(n·h, l·h) · max(0, n·l){}", bipolynomial_name(model.order),
                        model.lobe_width > 0
                            ? fmt::format(", ρ with a specular lobe of width {:.2f}", model.lobe_width)
                            : std::string())
          : std::string("Lambertian: albedo · max(0, n·l)");
  if (!model.chroma.empty()) model_text += ", in the albedo's colour (a specular lobe stays white)";
  // Colour results can be shown grey too, as `relight --grey` writes them.
  const std::string grey_box = model.chroma.empty()
                                   ? std::string()
                                   : "<label><input id=\"viewer-grey\" type=\"checkbox\"> grey</label>\n";
  std::string html = fmt::format(
      "<p>Drag on the hemisphere (mouse, pen or finger) to move a distant light; or focus it and use the "
      "arrow keys "
      "(Shift: small steps, Home: light at the camera). Shading: {}. The canvas shows the linear value, "
      "white at {} "
      "(the albedo picture's scale) × the exposure.</p>\n"
      "<div class=\"viewer\">\n<canvas id=\"viewer-canvas\" width=\"{}\" height=\"{}\"></canvas>\n"
      "<div class=\"controls\">\n<canvas id=\"viewer-hemisphere\" width=\"240\" height=\"240\"></canvas>\n"
      "<span id=\"viewer-readout\"></span>\n"
      "<label>exposure <input id=\"viewer-exposure\" type=\"range\" min=\"-3\" max=\"3\" step=\"0.1\" "
      "value=\"0\"> "
      "(stops)</label>\n<label><input id=\"viewer-srgb\" type=\"checkbox\"> sRGB tone curve</label>\n{}"
      "<span id=\"viewer-status\"></span>\n</div>\n</div>\n",
      escape_html(model_text), format_number(model.display_scale), model.normals.cols, model.normals.rows,
      grey_box);
  html += "<script type=\"application/json\" id=\"lightstage-viewer-meta\">" + payload.meta.dump() +
          "</script>\n";
  html.reserve(html.size() + payload.data_base64.size() + 128);
  html += "<script type=\"application/octet-stream\" id=\"lightstage-viewer-data\">";
  html += payload.data_base64;
  html += "</script>\n";
  return html;
}

// A relative link's path segment: what is not unreserved (RFC 3986) percent-encoded, so that a page named
// "run #3.html" links its folder and not a fragment.
std::string url_segment(std::string_view text) {
  std::string out;
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (std::isalnum(byte) || c == '-' || c == '.' || c == '_' || c == '~')
      out += c;
    else
      out += fmt::format("%{:02X}", byte);
  }
  return out;
}

// PAGE_files/, the page's own folder (pyramids, zoom page) while this mark is in it.
constexpr const char* kPageFolderMark = ".lightstage-report";

// Makes `folder` ready for the page's files: refused when it exists and is not the report's.
void claim_page_folder(const fs::path& folder) {
  if (fs::exists(folder) && !fs::exists(folder / kPageFolderMark))
    fail(
        "{}: exists and is not a folder a report wrote (no {} inside); remove it or write the page elsewhere",
        folder.string(), kPageFolderMark);
  fs::create_directories(folder);
  std::ofstream(folder / kPageFolderMark) << "files of the report page beside this folder\n";
}

std::string surface_section(const ResultPictures& pictures, const fs::path& pyramid_dir) {
  std::string html = "<div class=\"row\">\n";
  html +=
      figure(png_data_uri(pictures.normals), "normal map",
             "Normals, colour = (n + 1) / 2: red = x (right), green = y (up), blue = z (toward the camera).");
  html +=
      figure(png_data_uri(normal_sphere_legend(160)), "reference sphere",
             "Reference: a sphere's normals in the same code (the light toward the camera is the centre).",
             "legend");
  html += figure(png_data_uri(pictures.albedo), "albedo",
                 fmt::format("{}, white at {} (99.5th percentile of the solved albedo).",
                             pictures.colour_albedo ? "Colour albedo (linear)" : "Albedo",
                             format_number(pictures.albedo_shown)));
  html += "</div>\n";
  if (!pictures.pyramids.empty()) {
    // Relative links: the page and its folder move together.
    const std::string folder = url_segment(pyramid_dir.filename().string());
    std::vector<std::string> links;
    for (const DeepZoomSummary& pyramid : pictures.pyramids) {
      const std::string name = pyramid_dir.filename().string() + "/" + pyramid.descriptor.filename().string();
      links.push_back(fmt::format("<a href=\"{}/{}\">{}</a>", folder,
                                  url_segment(pyramid.descriptor.filename().string()), escape_html(name)));
    }
    html += fmt::format(
        "<p class=\"note\">Full resolution ({}x{}): <a href=\"{}/zoom.html\">zoom in</a> on the normals "
        "and albedo, from their Deep Zoom pyramids ({} levels: {}; any Deep Zoom viewer opens them).</p>\n",
        pictures.pyramids.front().size.width, pictures.pyramids.front().size.height, folder,
        pictures.pyramids.front().levels, fmt::join(links, " and "));
  }
  return html;
}

// PAGE_files/zoom.html: the pyramids in OpenSeadragon (web/zoom.js), a link back to the page.
void write_zoom_page(const ResultPictures& pictures, const fs::path& page_file, const fs::path& pyramid_dir,
                     const fs::path& result_dir) {
  nlohmann::ordered_json sources = nlohmann::ordered_json::object();  // in page order: the first is shown
  const std::map<std::string, std::pair<std::string, std::string>> text = {
      {"normal", {"Normals", "Normals, colour = (n + 1) / 2: red = x (right), green = y (up), blue = z."}},
      {"albedo", {"Albedo", fmt::format("Albedo, white at {}.", format_number(pictures.albedo_shown))}}};
  for (const DeepZoomSummary& pyramid : pictures.pyramids) {
    const std::string name = pyramid.descriptor.stem().string();
    const auto& [label, caption] = text.at(name);
    sources[name] = {{"label", label},
                     {"caption", caption},
                     {"tiles", name + "_files/"},
                     {"format", pyramid.format},
                     {"tile_size", pyramid.tile_size},
                     {"overlap", pyramid.overlap},
                     {"width", pyramid.size.width},
                     {"height", pyramid.size.height}};
  }
  // "</" cannot end the JSON's script element early.
  std::string json = sources.dump();
  for (std::size_t at = json.find("</"); at != std::string::npos; at = json.find("</", at))
    json.replace(at, 2, "<\\/");
  std::string html =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
      "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; img-src 'self' file: data: "
      "blob:; worker-src blob:; style-src 'unsafe-inline'; script-src 'unsafe-inline'\">\n";
  html +=
      "<title>Lightstage: " + escape_html(fs::absolute(result_dir).lexically_normal().filename().string()) +
      " at full resolution</title>\n<style>\n"
      "html, body { margin: 0; height: 100%; background: #1e1e1e; color: #ddd; font: 14px system-ui, "
      "sans-serif; }\n"
      "header { height: 36px; display: flex; gap: 12px; align-items: center; padding: 0 10px; }\n"
      "button[aria-pressed=true] { font-weight: bold; }\n a { color: #9cf; }\n"
      "#zoom { position: absolute; top: 36px; bottom: 0; left: 0; right: 0; }\n</style>\n</head>\n<body>\n"
      "<header><a href=\"../" +
      url_segment(page_file.filename().string()) +
      "\">report</a><span id=\"pictures\"></span>"
      "<span id=\"caption\"></span><span>drag to pan, wheel or +/- to zoom</span></header>\n"
      "<div id=\"zoom\"></div>\n<script type=\"application/json\" id=\"lightstage-zoom-sources\">" +
      json + "</script>\n<script>\n" + std::string(web::kZoomScript) + "</script>\n</body>\n</html>\n";
  util::write_text_atomic(pyramid_dir / "zoom.html", html);
}

// How depth.pfm's values read: the integration's camera (surface.json beside it).
struct DepthUnit {
  std::string unit = "depth units";
  bool perspective = false;
};

DepthUnit depth_camera(const fs::path& surface_dir, DepthSource& source) {
  DepthUnit unit;
  if (!fs::exists(surface_dir / "surface.json")) return unit;
  const auto surface = read_json_file(surface_dir / "surface.json");
  const auto camera = surface.value("camera", nlohmann::json::object());
  if (camera.is_object() && camera.value("model", "") == "orthographic") {
    source.pixel_size = camera.value("pixel_size", 1.0);
    unit.unit = source.pixel_size == 1.0 ? "pixels" : "mm";
  } else if (camera.is_object() && camera.contains("K") && camera["K"].is_array() &&
             camera["K"].size() == 9) {
    // Perspective: a pixel spans depth / fx at the typical depth.
    source.focal_px = camera["K"][0].is_number() ? camera["K"][0].get<double>() : 0.0;
    unit.unit = "mm along the optical axis";
    unit.perspective = true;
  }
  return unit;
}

std::string depth_section(const DepthPictures& depth, const DepthUnit& unit, int index) {
  std::string html = "<div class=\"row\">\n";
  html += figure(png_data_uri(depth.shaded), "shaded depth",
                 fmt::format("depth.pfm as a relief lit from the upper left ({} {} per pixel).",
                             format_number(depth.pixel_size), unit.unit));
  html += "<figure>" + std::string("<img class=\"map\" src=\"") + png_data_uri(depth.colour) +
          "\" alt=\"depth\">" +
          colour_bar_svg(kDepthColormap, depth.low, depth.high,
                         fmt::format("depth ({}; {})", unit.unit,
                                     unit.perspective ? "larger = farther" : "larger = nearer the camera"),
                         fmt::format("bar-{}", index)) +
          "</figure>\n</div>\n";
  return html;
}

std::string lights_section(const Inputs& in) {
  std::vector<LightSeries> series;
  std::string extra;
  bool link = false;
  if (in.calibration) {
    const auto& cal = *in.calibration;
    LightSeries nominal{"nominal (rig)", "#c2410c", true, {}};
    LightSeries calibrated{"calibrated", "#1d4ed8", false, {}};
    double sum = 0, worst = 0;
    std::size_t compared = 0;
    bool every_nominal = true;
    for (const auto& light : cal.lights) {
      if (!light.measured) continue;
      const std::string label =
          light.led_id >= 0 ? fmt::format("{} · LED {}", light.image, light.led_id) : light.image;
      calibrated.lights.push_back({light.direction, label});
      if (light.nominal_position_mm) {
        const Vec3 d = (*light.nominal_position_mm - cal.object_position_mm).normalized();
        nominal.lights.push_back({d, label});
        const double angle = std::acos(std::clamp(d.dot(light.direction.normalized()), -1.0, 1.0)) * kDeg;
        sum += angle;
        worst = std::max(worst, angle);
        ++compared;
      } else {
        every_nominal = false;
      }
    }
    if (every_nominal && !nominal.lights.empty()) {
      series.push_back(nominal);
      link = true;
    }
    series.push_back(calibrated);
    extra += fmt::format("<p>Calibration: {} ({} lights measured of {}, directions by {}).</p>\n",
                         escape_html(in.calibration_file->string()), calibrated.lights.size(),
                         cal.lights.size(), escape_html(cal.direction_method));
    if (compared > 0) {
      extra += fmt::format("<p>Calibrated against nominal: mean {}°, max {}° over {} lights.</p>\n",
                           format_number(sum / static_cast<double>(compared), 3), format_number(worst, 3),
                           compared);
    }
    if (!every_nominal)
      extra += note("Some lights have no nominal position: only the calibrated ones are drawn.");
  }
  if (in.stack) {
    LightSeries used{"directions in the stack (used by the solver)", "#15803d", false, {}};
    if (!series.empty()) used.colour = "#16a34a80";
    for (const auto& frame : in.stack->frames) {
      const std::string label =
          frame.led_id >= 0 ? fmt::format("{} · LED {}", frame.filename, frame.led_id) : frame.filename;
      used.lights.push_back({frame.light_direction, label});
    }
    if (series.empty())
      series.push_back(used);
    else
      series.push_back(used);
  }
  if (series.empty()) return {};
  std::string html =
      "<div class=\"row\"><figure>" + hemisphere_svg(series, link) +
      "<figcaption>Seen from the camera: azimuth around (0° = right, 90° = up), elevation from 0° "
      "at the rim to 90° at the centre. Hover a mark for its image and LED.</figcaption></figure>"
      "<div>" +
      extra;
  if (!in.calibration)
    html += note("No calibration.json found: only the stack's light directions are drawn.");
  html += "</div></div>\n";
  return html;
}

std::string light_statistics_section(const Inputs& in, const ReportOptions& options,
                                     std::vector<std::string>& notes) {
  const auto parameters = in.summary.find("parameters");
  StatisticsThreshold threshold = statistics_threshold(
      parameters == in.summary.end() ? nlohmann::json() : *parameters, options.shadow_threshold);
  std::vector<LightStatistics> stats;
  if (const auto recorded = in.summary.find("light_statistics");
      recorded != in.summary.end() && !options.shadow_threshold) {
    // Gathered by the solve from the observations it made (its radiometry, response and calibration).
    const auto from_solve = recorded_light_statistics(*recorded, *in.stack);
    if (!from_solve) {
      notes.push_back(
          "Per-light statistics in summary.json are malformed or were made of other frames than the stack's: "
          "not shown (run "
          "`lightstage report --shadow-threshold T` to compute them from the stack).");
      return {};
    }
    stats = *from_solve;
    threshold = *recorded_threshold(*recorded);
  } else {
    RadiometryOptions radiometry;
    if (const auto it = in.summary.find("radiometry"); it != in.summary.end() && it->is_object())
      radiometry.clamp_to_one = it->value("clamp_to_one", true);
    try {
      stats = light_statistics(*in.stack, threshold.value, radiometry);
    } catch (const InputError& e) {
      notes.push_back(fmt::format("Per-light statistics could not be computed: {}", e.what()));
      return {};
    }
  }
  std::vector<double> means, saturated, shadow;
  for (const auto& s : stats) {
    means.push_back(s.mean_value);
    saturated.push_back(100.0 * s.saturated_share);
    shadow.push_back(100.0 * s.shadow_share);
  }
  std::vector<double> sorted = means;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted.empty() ? 0 : sorted[sorted.size() / 2];
  std::size_t dark = 0, clipping = 0;
  for (const auto& s : stats) {
    if (s.mean_value < 0.05 * median || s.mean_value <= 0) ++dark;
    if (s.saturated_share > 0.01) ++clipping;
  }
  std::string html = fmt::format(
      "<p>{} lights. Over the mask: mean value (linear, divided by the light's intensity), the share of "
      "pixels "
      "with a saturated channel, and the share in shadow (value ≤ {}, {} threshold).</p>\n",
      stats.size(), format_number(threshold.value), threshold.source);
  html += fmt::format(
      "<p><b>{}</b> · <b>{}</b></p>\n",
      dark == 0 ? std::string("every light lit the object")
                : fmt::format("{} light(s) look dark (mean below 5% of the median): did they fire?", dark),
      clipping == 0 ? std::string("no light clips more than 1% of the object")
                    : fmt::format("{} light(s) clip more than 1% of the object", clipping));
  html += "<div class=\"row\"><figure>" +
          bar_chart_svg(means, 0, "mean value", "light (filenames.txt order)", "#3b6fb6") +
          "</figure><figure>" + bar_chart_svg(shadow, 100, "shadow share (%)", "light", "#6b7280") +
          "</figure><figure>" + bar_chart_svg(saturated, 0, "saturated share (%)", "light", "#c2410c") +
          "</figure></div>\n";
  html +=
      "<div class=\"scroll\"><table id=\"light-statistics\"><thead><tr><th>#</th><th "
      "class=\"text\">image</th>"
      "<th>LED</th><th>azimuth °</th><th>elevation °</th><th>exposure µs</th><th>gain</th><th>mean value</th>"
      "<th>saturated</th><th>shadow</th></tr></thead><tbody>\n";
  for (std::size_t i = 0; i < stats.size(); ++i) {
    const auto& s = stats[i];
    html += fmt::format(
        "<tr><td>{}</td><td "
        "class=\"text\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>"
        "<td>{}</td><td>{}</td></tr>\n",
        i + 1, escape_html(s.file), s.led_id >= 0 ? std::to_string(s.led_id) : "–",
        format_number(azimuth_deg(s.direction), 4), format_number(elevation_deg(s.direction), 3),
        s.exposure_us > 0 ? format_number(s.exposure_us, 6) : "unknown", format_number(s.gain, 3),
        format_number(s.mean_value, 4), percent(s.saturated_share), percent(s.shadow_share));
  }
  html += "</tbody></table></div>\n";
  return html;
}

std::string map_figure(const cv::Mat& picture, double high, const std::string& what,
                       const std::string& caption, int index) {
  return "<figure><img class=\"map\" src=\"" + png_data_uri(picture) + "\" alt=\"" + escape_html(what) +
         "\">" + colour_bar_svg(kMagnitudeColormap, 0, high, what, fmt::format("bar-{}", index)) +
         "<figcaption>" + escape_html(caption) + "</figcaption></figure>\n";
}

std::string residual_section(const Inputs& in, const ResultPictures& pictures) {
  std::string html = "<div class=\"row\">\n";
  bool any = false;
  if (!pictures.residual.empty()) {
    html +=
        map_figure(pictures.residual, pictures.residual_high, "RMS residual of the fit",
                   "residual.pfm: each pixel's RMS misfit over the observations it used (colour clipped at "
                   "the 99th percentile, rounded up).",
                   1);
    any = true;
  }
  if (!pictures.confidence.empty()) {
    html += map_figure(pictures.confidence, 1.0, "confidence (0.5 = predicted error of 1 degree)",
                       "confidence.pfm: c = 1 / (1 + e / 1 deg), e the normal's error predicted from the lit "
                       "lights' geometry and the fit's residual; e = 1/c - 1 degrees.",
                       2);
    any = true;
  }
  // auto's per-pixel choices, with the legend and counts the solve recorded.
  if (!pictures.method_map.empty()) {
    std::string legend;
    for (const auto& choice : in.summary["method_map"].value("choices", nlohmann::json::array())) {
      if (!choice.is_object()) continue;
      legend += fmt::format("<span class=\"swatch\" style=\"background:{}\"></span>{} ({} px) ",
                            escape_html(choice.value("colour", "#000000")),
                            escape_html(choice.value("method", "?")), choice.value("pixels", 0));
    }
    html += "<figure><img class=\"map\" src=\"" + png_data_uri(pictures.method_map) +
            "\" alt=\"method per pixel\"><figcaption>method_map.png: the answer each pixel took. " + legend +
            "</figcaption></figure>\n";
    any = true;
  }
  html += "</div>\n";
  return any ? html : std::string();
}

std::string error_section(const ErrorPictures& error, const std::string& source) {
  const auto& s = error.stats;
  std::string html =
      fmt::format("<p>Against {} (the DiLiGenT measure: the angle between normals, per pixel).</p>\n",
                  escape_html(source));
  html += "<div class=\"row\">\n<figure><img class=\"map\" src=\"" + png_data_uri(error.map) +
          "\" alt=\"angular error map\">" +
          colour_bar_svg(kMagnitudeColormap, 0, error.high, "angular error (degrees)", "bar-error") +
          "<figcaption>Angular error; brightest = " + format_number(error.high) +
          "° or more (the 95th percentile, rounded up).</figcaption></figure>\n";
  html += "<figure>" + histogram_svg(error.histogram, "angular error (degrees)") +
          "<figcaption>Histogram of the per-pixel error; the last bar counts the pixels at or above " +
          format_number(error.high) + "°.</figcaption></figure>\n";
  html += fmt::format(
      "<dl class=\"numbers\" id=\"error-numbers\"><dt>mean</dt><dd>{}°</dd><dt>median</dt><dd>{}°</dd>"
      "<dt>90th percentile</dt><dd>{}°</dd><dt>max</dt><dd>{}°</dd><dt>pixels compared</dt><dd>{}</dd>"
      "<dt>without a prediction</dt><dd>{}</dd></dl>\n</div>\n",
      format_number(s.mean, 4), format_number(s.median, 4), format_number(s.p90, 4), format_number(s.max, 4),
      s.count, s.missing);
  return html;
}

// Ground-truth normals and the mask to compare in, from --gt or the stack; none without either.
std::unique_ptr<TruthRows> ground_truth(Inputs& in, const ReportOptions& options, cv::Size result_size) {
  std::unique_ptr<TruthRows> truth;
  cv::Mat mask;
  if (options.ground_truth) {
    fs::path file = *options.ground_truth;
    if (fs::is_directory(file)) {
      if (fs::exists(file / "mask.png")) mask = io::read_mask(file / "mask.png");
      file /= "Normal_gt.png";
    }
    truth = truth_from_file(file);
  } else if (in.stack && fs::exists(*in.stack_dir / "Normal_gt.png")) {
    try {
      truth = truth_from_file(*in.stack_dir / "Normal_gt.png", in.crop);
    } catch (const InputError& e) {
      if (options.stack) throw;
      in.notes.push_back(
          fmt::format("The stack's ground truth could not be read ({}); no error map.", e.what()));
      return nullptr;
    }
    mask = in.stack->mask;
  } else {
    return nullptr;
  }
  if (truth->size() != result_size)
    fail("{}: ground truth is {}x{}, the result {}x{}", truth->source, truth->size().width,
         truth->size().height, result_size.width, result_size.height);
  if (mask.size() == result_size) truth->mask = mask;
  return truth;
}

}  // namespace

void ReportOptions::check() const {
  if (viewer_max_pixels < 1) fail("report: viewer_max_pixels must be ≥ 1, got {}", viewer_max_pixels);
  if (picture_max_pixels < 1) fail("report: picture_max_pixels must be ≥ 1, got {}", picture_max_pixels);
  if (band_rows < 0) fail("report: band_rows must be ≥ 0, got {}", band_rows);
  if (threads < 0) fail("report: threads must be 0 (every core) or positive, got {}", threads);
  if (pyramids != "auto" && pyramids != "always" && pyramids != "never")
    fail("--pyramids: auto, always or never, got '{}'", pyramids);
  if (pyramid_format != "png" && pyramid_format != "jpg")
    fail("--pyramid-format: png or jpg, got '{}'", pyramid_format);
  if (shadow_threshold && (!(*shadow_threshold >= 0) || !std::isfinite(*shadow_threshold)))
    fail("report: shadow_threshold must be a number ≥ 0, got {}", *shadow_threshold);
  if (ground_truth && !fs::exists(*ground_truth))
    fail("--gt {}: no such file or folder", ground_truth->string());
  if (calibration && !fs::exists(*calibration)) fail("--calibration {}: no such file", calibration->string());
}

namespace {

// Whether a result of `pixels` gets pyramids: "always", or "auto" over the page's picture budget.
bool writes_pyramids(const ReportOptions& options, std::size_t pixels) {
  return options.pyramids == "always" ||
         (options.pyramids == "auto" && pixels > static_cast<std::size_t>(options.picture_max_pixels));
}

}  // namespace

std::size_t report_memory_bytes(int width, int height, const ReportOptions& options) {
  // Held for the whole image: the solved mask, the ground truth's mask, the compared pixels' mask, a double
  // per compared pixel in a growing vector (up to three while it moves).
  constexpr std::size_t kWholeImageBytes = 1 + 1 + 1 + 24;
  // Per picture pixel: eight BGRA pictures, their PNGs and base64 in the page, and the page's copy.
  constexpr std::size_t kPictureBytes = 48;
  // Per viewer pixel: its model (normals, albedo, chroma, up to 10 coefficients) and its payload.
  constexpr std::size_t kViewerBytes = 12 + 1 + 4 + 12 + 40 + 60;
  // A band of the maps, or all of them when they fit options.kept_map_bytes (result_maps.hpp): from 83 bytes
  // a pixel (normal.png alone, with the truth, error and pictures) to 269 (every map, bicubic's 17
  // coefficients).
  constexpr std::size_t kMapPixelBytesLeast = 83, kMapPixelBytesMost = 269;
  const auto pixels =
      static_cast<std::size_t>(std::max(width, 0)) * static_cast<std::size_t>(std::max(height, 0));
  const std::size_t maps =
      pixels * kMapPixelBytesLeast <= options.kept_map_bytes
          ? std::max(2 * kReportBandBytes, std::min(pixels * kMapPixelBytesMost, options.kept_map_bytes))
          : 2 * kReportBandBytes;  // a band visited, the next read beside it
  // Pyramids: the level under the picture whole (a quarter of its BGRA pixels) and a strip of tiles, for
  // the normals and the albedo.
  const bool pyramids = writes_pyramids(options, pixels);
  const std::size_t pyramid_bytes =
      pyramids ? 2 * (pixels * 5 / 4 + static_cast<std::size_t>(std::max(width, 0)) * 256 * 4 * 3) : 0;
  return pixels * kWholeImageBytes + maps + pyramid_bytes +
         std::min(pixels, static_cast<std::size_t>(options.picture_max_pixels)) * kPictureBytes +
         std::min(pixels, static_cast<std::size_t>(options.viewer_max_pixels)) * kViewerBytes;
}

nlohmann::json ReportSummary::to_json() const {
  nlohmann::json written = nlohmann::json::array();
  for (const auto& pyramid : pyramids) written.push_back(pyramid.string());
  return {{"file", file.string()},
          {"bytes", bytes},
          {"sections", sections},
          {"notes", notes},
          {"pyramids", written}};
}

std::string render_report(const fs::path& result_dir, const ReportOptions& options, ReportSummary* summary,
                          const fs::path& page_file) {
  options.check();
  if (!fs::is_directory(result_dir)) fail("{}: not a folder (expected a solve result)", result_dir.string());
  if (!fs::exists(result_dir / "normal.png"))
    fail("{}: no normal.png: not a solve result folder", (result_dir / "normal.png").string());
  io::SolveFolderRows folder(result_dir);
  Inputs in;
  in.result_dir = result_dir;
  load_inputs(in, folder.facts(), options);
  const cv::Size size = folder.size();

  MapSources sources;
  sources.folder = &folder;
  sources.band_rows = options.band_rows;
  sources.kept_bytes = options.kept_map_bytes;
  sources.picture_max_pixels = options.picture_max_pixels;
  sources.viewer_max_pixels = options.viewer_max_pixels;
  const bool pyramids =
      writes_pyramids(options, static_cast<std::size_t>(size.width) * static_cast<std::size_t>(size.height));
  // The page's folder: the pyramids and their zoom page, or none (a folder of an earlier page removed).
  const fs::path pyramid_dir =
      page_file.empty() ? fs::path() : page_file.parent_path() / (page_file.stem().string() + "_files");
  if (!pyramid_dir.empty() && !pyramids && fs::exists(pyramid_dir / kPageFolderMark))
    fs::remove_all(pyramid_dir);
  if (pyramids && !pyramid_dir.empty()) {
    claim_page_folder(pyramid_dir);
    sources.pyramid_dir = pyramid_dir;
    sources.pyramid.format = options.pyramid_format;
    // Every core free (in bands, a core reads the next band beside the drawing):
    // a tile row is held whatever the threads, and each tile's encoding needs only its own few hundred kB.
    sources.pyramid.threads = 0;
  }
  sources.albedo_scale = in.summary.value(
      folder.has_albedo() && folder.has_chroma() ? "albedo_rgb_png_scale" : "albedo_png_scale", 0.0);

  // Depth: --depth (a depth.pfm, or a `lightstage integrate` folder), else RESULT_DIR/depth.pfm.
  fs::path depth_file = result_dir / "depth.pfm";
  if (options.depth)
    depth_file = fs::is_directory(*options.depth) ? *options.depth / "depth.pfm" : *options.depth;
  DepthUnit depth_unit;
  // Notes in the order of the page's sections: the viewer's (drawn with the maps) come first.
  std::vector<std::string> depth_notes, method_notes;
  if (fs::exists(depth_file)) {
    DepthSource depth;
    depth.rows = io::open_row_reader(depth_file);
    if (depth.rows->type() != CV_32FC1 || depth.rows->size() != size) {
      if (options.depth)
        fail(
            "{}: depth must be one float channel of {}x{} (the normal map's size), got {} channel(s) of "
            "{}x{}",
            depth_file.string(), size.width, size.height, CV_MAT_CN(depth.rows->type()),
            depth.rows->size().width, depth.rows->size().height);
      depth_notes.push_back(fmt::format("{} is not one float channel of the normal map's size; not shown.",
                                        depth_file.string()));
    } else {
      depth_unit = depth_camera(depth_file.parent_path(), depth);
      sources.depth = std::move(depth);
    }
  } else if (options.depth) {
    fail("--depth {}: no depth.pfm there", options.depth->string());
  } else {
    depth_notes.push_back(
        "No depth.pfm in the result folder (run `lightstage integrate`, then give its folder with --depth): "
        "no depth "
        "relief.");
  }

  // auto's per-pixel choices.
  if (const auto it = in.summary.find("method_map");
      it != in.summary.end() && it->is_object() && fs::exists(result_dir / "method_map.png")) {
    try {
      sources.method_map = io::open_row_reader(result_dir / "method_map.png");
    } catch (const InputError&) {
    }
    if (!sources.method_map || sources.method_map->type() != CV_8UC3 || sources.method_map->size() != size) {
      method_notes.push_back("method_map.png: not an image of the result's size; not shown.");
      sources.method_map.reset();
    }
  }

  sources.truth = ground_truth(in, options, size);
  const ResultPictures pictures = draw_result_maps(sources, in.notes);
  if (!pictures.pyramids.empty()) write_zoom_page(pictures, page_file, pyramid_dir, result_dir);
  in.notes.insert(in.notes.end(), depth_notes.begin(), depth_notes.end());
  if (pictures.factor > 1)
    in.notes.push_back(
        fmt::format("The pictures show the {}x{} result at 1/{} of its size, each pixel the mean of {}x{} "
                    "(the method map: the block's first pixel; page budget {} pixels a picture).",
                    size.width, size.height, pictures.factor, pictures.factor, pictures.factor,
                    options.picture_max_pixels));

  // The sections of pictures encode their PNGs, the viewer its payload: side by side.
  std::string viewer_html, surface_html, depth_html, residual_html, error_html;
  const std::vector<std::function<void()>> encoded = {
      [&] { viewer_html = viewer_section(pictures.viewer, in); },
      [&] { surface_html = surface_section(pictures, pyramid_dir); },
      [&] {
        if (pictures.depth) depth_html = depth_section(*pictures.depth, depth_unit, 0);
      },
      [&] { residual_html = residual_section(in, pictures); },
      [&] {
        if (pictures.error) error_html = error_section(*pictures.error, sources.truth->source);
      }};
  parallel_invoke(encoded, options.threads);

  Page page;
  // The viewer first: it is what people come for.
  page.section("viewer", "Relighting viewer", std::move(viewer_html));
  page.section("surface", "Normals and albedo", surface_html);
  if (pictures.depth) page.section("depth", "Depth", depth_html);

  if (const std::string lights = lights_section(in); !lights.empty()) {
    page.section("lights", "Lights on the hemisphere", lights);
  }

  if (in.stack && options.light_statistics) {
    if (const std::string html = light_statistics_section(in, options, in.notes); !html.empty())
      page.section("light-statistics", "Per-light statistics", html);
  } else if (!options.light_statistics) {
    in.notes.push_back("Per-light statistics were not asked for.");
  } else {
    in.notes.push_back(
        "Per-light statistics (exposure, saturation and shadow share) need the input stack, which was not "
        "found.");
  }

  in.notes.insert(in.notes.end(), method_notes.begin(), method_notes.end());
  if (!residual_html.empty())
    page.section("residual", "Residual and confidence", residual_html);
  else
    in.notes.push_back("No residual.pfm or confidence.pfm in the result folder.");

  if (pictures.error)
    page.section("error", "Angular error against ground truth", error_html);
  else
    in.notes.push_back("No ground truth (Normal_gt.png in the input stack, or --gt): no error map.");

  std::string notes_html;
  for (const auto& n : in.notes) notes_html += "<li>" + escape_html(n) + "</li>\n";
  if (!notes_html.empty()) page.section("notes", "Notes", "<ul>\n" + notes_html + "</ul>\n");

  std::string html =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
      "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; img-src data:; "
      "style-src 'unsafe-inline'; script-src 'unsafe-inline'; connect-src data:\">\n";
  html += "<title>Lightstage report: " +
          escape_html(fs::absolute(result_dir).lexically_normal().filename().string()) +
          "</title>\n<style>\n" + web::kReportCss + "</style>\n</head>\n<body>\n<header>\n" +
          header_html(in) + "<nav>" + page.nav() + "</nav>\n</header>\n<main>\n";
  const std::string_view script = web::kViewerScript;
  html.reserve(html.size() + page.body_size() + script.size() + 256);
  page.append_body(html);
  html += "</main>\n<script type=\"module\">\n";
  html += script;
  html += "</script>\n</body>\n</html>\n";
  if (summary) {
    summary->sections = page.sections();
    summary->notes = in.notes;
    for (const DeepZoomSummary& pyramid : pictures.pyramids) summary->pyramids.push_back(pyramid.descriptor);
  }
  return html;
}

ReportSummary write_report(const fs::path& result_dir, const fs::path& out, const ReportOptions& options) {
  // Any other name could be one of the files the report reads (normal.png, summary.json, a frame).
  if (!out.empty() && (out.extension() != ".html" || fs::is_directory(out)))
    fail("--out {}: the report is one HTML file; name a new .html file", out.string());
  ReportSummary summary;
  summary.file = out.empty() ? result_dir / "report.html" : out;
  const std::string html = render_report(result_dir, options, &summary, summary.file);
  if (summary.file.has_parent_path()) {
    std::error_code error;
    fs::create_directories(summary.file.parent_path(), error);
    if (error) fail("{}: cannot create folder: {}", summary.file.parent_path().string(), error.message());
  }
  util::write_text_atomic(summary.file, html);
  summary.bytes = html.size();
  logger("host")->debug("report: wrote {} ({:.1f} MB, sections: {})", summary.file.string(),
                        static_cast<double>(summary.bytes) / 1e6, fmt::join(summary.sections, ", "));
  return summary;
}

}  // namespace lightstage::report
