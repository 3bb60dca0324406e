#include "lightstage/pipeline/rti_exchange.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/calibration/lp_file.hpp"
#include "lightstage/host/io/exif.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/output_folder.hpp"
#include "lightstage/host/io/relight_web.hpp"
#include "lightstage/host/io/rti_files.hpp"
#include "lightstage/host/io/rti_import.hpp"
#include "lightstage/host/io/solve_output.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/io/tiff_image.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/reflectance/relight.hpp"
#include "lightstage/host/reflectance/rti_basis.hpp"
#include "lightstage/host/reflectance/rti_stack_fit.hpp"
#include "lightstage/host/shadow_threshold.hpp"
#include "lightstage/pipeline/solve_methods.hpp"

#include <Eigen/Dense>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <optional>

#include <unistd.h>

namespace lightstage::pipeline {

std::filesystem::path export_stack_folder(const std::filesystem::path& input, nlohmann::json* solve_summary) {
  if (!std::filesystem::is_directory(input))
    fail("--input {}: not a folder (a stack or a solve folder)", input.string());
  // A solve folder holds summary.json and normal.png (io/solve_output.hpp); anything else is read as a stack.
  if (!std::filesystem::is_regular_file(input / "summary.json") ||
      !std::filesystem::is_regular_file(input / "normal.png"))
    return input;
  const io::SolveFolder solve = io::read_solve_folder(input);
  const std::string summary = (input / "summary.json").string();
  const auto recorded = solve.summary.find("input");
  if (recorded == solve.summary.end() || !recorded->is_string() || recorded->get<std::string>().empty())
    fail("{}: input: no stack recorded; export the stack itself with --input STACK", summary);
  const std::filesystem::path stack = recorded->get<std::string>();
  if (!std::filesystem::is_directory(stack))
    fail(
        "{}: input: the solve's stack {} is not a folder (moved, or recorded relative to another directory); "
        "export the stack itself with --input STACK",
        summary, stack.string());
  if (solve_summary != nullptr) *solve_summary = solve.summary;
  return stack;
}

nlohmann::json export_rti(const ExportSettings& s) {
  if (s.format != "ptm" && s.format != "hsh" && s.format != "relight")
    fail("--format: '{}' is not ptm, hsh or relight", s.format);
  const std::string colour = !s.colour.empty() ? s.colour : s.format == "relight" ? "rgb" : "lrgb";
  if (colour != "lrgb" && colour != "rgb") fail("--colour: '{}' is not lrgb or rgb", colour);
  if (s.hsh_order != 2 && s.hsh_order != 3) fail("--order: {} is not 2 or 3", s.hsh_order);
  if (s.model != "ptm" && s.model != "hsh") fail("--model: '{}' is not ptm or hsh", s.model);
  io::RelightWebOptions web;
  web.colorspace = colour;
  web.image_format = s.planes;
  web.quality = s.quality;
  if (s.format == "relight") {
    web.check();
    io::require_empty_folder(s.out, "--out", "choose a new --out folder");
  } else if (std::filesystem::exists(s.out)) {
    fail("--out: {} already exists; choose another file", s.out.string());
  }
  nlohmann::json solve_summary;
  const std::filesystem::path stack_dir = export_stack_folder(s.input, &solve_summary);
  const ImageStack stack = io::load_stack(stack_dir, {.min_images = 3, .load_ground_truth = false});
  const std::string model = s.format == "relight" ? s.model : s.format;
  const RtiBasis basis = model == "ptm" ? RtiBasis::ptm : s.hsh_order == 2 ? RtiBasis::hsh2 : RtiBasis::hsh3;
  const io::RtiImage image = fit_rti_stack(stack, basis);
  std::uintmax_t bytes = 0;
  nlohmann::json written;
  if (s.format == "relight") {
    const nlohmann::json info = io::write_relight_web(s.out, image, web);
    for (const auto& e : std::filesystem::directory_iterator(s.out)) {
      bytes += e.file_size();
      written.push_back(e.path().filename().string());
    }
    std::sort(written.begin(), written.end());
  } else {
    if (s.format == "ptm")
      io::write_ptm(s.out, image, colour == "rgb" ? io::PtmFormat::rgb : io::PtmFormat::lrgb);
    else
      io::write_hsh(s.out, image);
    bytes = std::filesystem::file_size(s.out);
    written.push_back(s.out.filename().string());
  }
  nlohmann::json r = {{"out", s.out.string()},
                      {"stack", stack_dir.string()},
                      {"format", s.format},
                      {"model", rti_basis_name(basis)},
                      {"width", image.width},
                      {"height", image.height},
                      {"terms", rti_term_count(basis)},
                      {"lights", stack.frames.size()},
                      {"colour", s.format == "hsh" ? std::string("rgb") : colour},
                      {"bytes", bytes},
                      {"files", written}};
  if (!solve_summary.is_null()) {
    r["solve"] = s.input.string();
    // The fit needs the photographs, so it is the stack's: the solve only names it.
    if (solve_summary.contains("calibration"))
      r["note"] = "the solve applied a light calibration; the export fits the stack's own light directions";
  }
  return r;
}

namespace {

// Least-squares b with value ≈ max(b·l, 0) fitted as b·l (the l2 baseline).
Eigen::VectorXf l2_relight(const Eigen::MatrixXf& values, const Eigen::MatrixX3d& lights, const Vec3& light) {
  const Eigen::MatrixXd pinv =
      lights.colPivHouseholderQr().solve(Eigen::MatrixXd::Identity(lights.rows(), lights.rows()));
  const Eigen::MatrixXf b = (values.cast<double>() * pinv.transpose()).cast<float>();
  return (b * light.normalized().cast<float>()).cwiseMax(0.0f);
}

}  // namespace

namespace {

// The columns `keep` of the observations: the stack without some of its lights.
Observations select_lights(const Observations& obs, const std::vector<int>& keep) {
  Observations out;
  out.size = obs.size;
  out.mask = obs.mask;
  out.pixels = obs.pixels;
  // The median over every frame: one held-out light barely moves it.
  out.chroma = obs.chroma;
  const auto m = static_cast<Eigen::Index>(keep.size());
  out.intensities.resize(obs.intensities.rows(), m);
  out.saturated.resize(obs.saturated.rows(), m);
  out.lights.resize(m, 3);
  for (Eigen::Index k = 0; k < m; ++k) {
    out.intensities.col(k) = obs.intensities.col(keep[static_cast<std::size_t>(k)]);
    if (obs.saturated.cols() == obs.intensities.cols())
      out.saturated.col(k) = obs.saturated.col(keep[static_cast<std::size_t>(k)]);
    else
      out.saturated.col(k).setConstant(false);
    out.lights.row(k) = obs.lights.row(keep[static_cast<std::size_t>(k)]);
  }
  return out;
}

// A solve method relit at `light` on the pixels of `observations`, as `solve
// --method M` on the stack without the held-out light and then `relight`
// give it: the shadow threshold estimated from that stack, the result through
// a solve folder (io/solve_output.hpp) and relight.hpp's model of it.
Eigen::VectorXf solve_and_relight(const std::string& method, const ImageStack& stack, const Observations& obs,
                                  const Vec3& light, const std::filesystem::path& scratch, int threads) {
  SolveSettings settings;
  settings.method = method;
  if (threads > 0) settings.threads = threads;
  settings.resolve();
  const SolveResult result = solve_with(obs, settings, estimate_shadow_threshold(stack, obs));
  std::filesystem::remove_all(scratch);
  io::write_solve_outputs(scratch, result, "holdout");
  const cv::Mat relit = relight(load_relight_model(scratch), light);
  Eigen::VectorXf v(static_cast<Eigen::Index>(obs.pixel_count()));
  for (std::size_t i = 0; i < obs.pixels.size(); ++i)
    v(static_cast<Eigen::Index>(i)) = relit.at<float>(obs.pixels[i]);
  return v;
}

// A scratch folder removed when the holdout ends, however it ends.
struct ScratchFolder {
  std::filesystem::path path;
  ScratchFolder()
      : path(std::filesystem::temp_directory_path() / fmt::format("lightstage-holdout-{}", ::getpid())) {}
  ~ScratchFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
};

}  // namespace

nlohmann::json rti_holdout(const HoldoutSettings& s) {
  std::vector<std::string> methods;
  for (const auto& method : s.methods)
    if (!method.empty() && method != "none")
      methods.push_back(find_solve_method(method).name);  // fails early
  const ImageStack stack = io::load_stack(s.input, {.min_images = 3, .load_ground_truth = false});
  const Observations obs = make_observations(stack);
  const auto m = static_cast<int>(obs.image_count());
  if (s.held_out < 1 || s.held_out > m)
    fail("--held-out: {} is not in 1..{} (the stack's lights)", s.held_out, m);
  std::vector<int> held;
  for (int i = 0; i < s.held_out; ++i)
    held.push_back(static_cast<int>(static_cast<long>(i) * m / s.held_out));
  std::vector<std::string> names = {"ptm", "hsh2", "hsh3", "l2"};
  for (const auto& method : methods)
    if (std::find(names.begin(), names.end(), method) == names.end()) names.push_back(method);
  nlohmann::json models = nlohmann::json::object();
  for (const auto& name : names) models[name] = {{"per_light", nlohmann::json::array()}};
  const ScratchFolder scratch;
  for (const int h : held) {
    std::vector<int> keep;
    for (int j = 0; j < m; ++j)
      if (j != h) keep.push_back(j);
    const Observations fit = select_lights(obs, keep);
    const Eigen::MatrixXf values = fit.intensities;
    const Vec3 light = obs.lights.row(h).transpose();
    const Eigen::VectorXf photo = obs.intensities.col(h);
    // The stack without the held-out light, for the solve methods (made as `solve` makes it).
    ImageStack rest;
    Observations rest_obs;
    if (!methods.empty()) {
      rest = stack;
      rest.frames.erase(rest.frames.begin() + h);
      rest_obs = make_observations(rest);
    }
    for (const auto& name : names) {
      Eigen::VectorXf relit;
      if (name == "l2")
        relit = l2_relight(values, fit.lights, light);
      else if (name == "ptm" || name == "hsh2" || name == "hsh3")
        relit =
            evaluate_rti(parse_rti_basis(name), fit_rti(parse_rti_basis(name), values, fit.lights), light);
      else
        relit = solve_and_relight(name, rest, rest_obs, light, scratch.path, s.threads);
      const double err = (relit - photo).norm() / std::max(photo.norm(), 1e-12f);
      models[name]["per_light"].push_back(err);
    }
  }
  for (const auto& name : names) {
    double sum = 0;
    for (const auto& e : models[name]["per_light"]) sum += e.get<double>();
    models[name]["relative_rmse"] = sum / static_cast<double>(held.size());
  }
  return {{"input", s.input.string()},   {"held_out", held}, {"lights", m},
          {"pixels", obs.pixel_count()}, {"order", names},   {"models", models}};
}

std::string format_holdout_table(const nlohmann::json& r) {
  std::string out = fmt::format(
      "leave-one-light-out on {} ({} of {} lights held out, {} pixels): relative RMSE\n",
      r["input"].get<std::string>(), r["held_out"].size(), r["lights"].get<int>(), r["pixels"].get<long>());
  for (const auto& name : r["order"])
    out += fmt::format("  {:12} {:.4f}\n", name.get<std::string>(),
                       r["models"][name.get<std::string>()]["relative_rmse"].get<double>());
  return out;
}

namespace {

// One photograph as decoded: RAW through io/raw_image.hpp (its decode noted in
// `extra`), TIFF as stored (io/tiff_image.hpp), JPEG and PNG (io/image_io.hpp).
cv::Mat read_photo(const std::filesystem::path& file, io::RawDemosaic demosaic, nlohmann::json& extra) {
  if (io::is_raw_file(file)) {
    io::RawImage decoded = io::read_raw(file, demosaic);
    extra["raw"] = decoded.describe();
    return std::move(decoded.image);
  }
  if (io::is_tiff_file(file)) return io::read_tiff(file);
  return io::read_image(file);
}

std::filesystem::path find_lp(const ImportSettings& s) {
  if (!s.lp.empty()) return s.lp;
  std::vector<std::filesystem::path> found;
  for (const auto& e : std::filesystem::directory_iterator(s.input))
    if (e.is_regular_file() && e.path().extension() == ".lp") found.push_back(e.path());
  if (found.empty()) fail("{}: no .lp file in the folder; name one with --lp", s.input.string());
  if (found.size() > 1)
    fail("{}: {} .lp files ({}, {}, ...); choose one with --lp", s.input.string(), found.size(),
         found[0].filename().string(), found[1].filename().string());
  return found.front();
}

}  // namespace

nlohmann::json import_rti(const ImportSettings& s) {
  if (!std::filesystem::is_directory(s.input)) fail("{}: not a folder", s.input.string());
  io::require_empty_folder(s.out, "--out", "choose a new --out folder");
  io::require_separate_output(s.out, {s.input});
  std::optional<InverseResponse> response;
  if (!s.response.empty()) response = InverseResponse::load(s.response);
  const std::filesystem::path lp = find_lp(s);
  const auto entries = calibration::read_lp(lp);
  if (entries.size() < 3) fail("{}: {} lights; a stack needs at least 3", lp.string(), entries.size());
  ImageStack stack;
  int eight_bit = 0, sixteen_bit = 0, raw_files = 0;
  nlohmann::json frames_extra = nlohmann::json::array();
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const std::string where = fmt::format("{}:{}", lp.string(), i + 2);
    const std::string name = io::rti_image_name(entries[i].filename, where);
    const std::filesystem::path file = s.input / name;
    if (!std::filesystem::is_regular_file(file))
      fail("{}: image: {} is not in {}", where, name, s.input.string());
    nlohmann::json extra = {{"source_image", name}};
    cv::Mat photo = read_photo(file, s.raw_demosaic, extra);
    io::ExifInfo exif;
    try {
      exif = io::read_exif(file);
    } catch (const InputError& e) {
      // The pixels decoded: a damaged EXIF block costs the metadata (and the orientation), not the frame.
      logger("host")->warn("{}", e.what());
    }
    // JPEG and PNG as a viewer shows them; RAW keeps the sensor's orientation, TIFF is read as stored.
    if (!extra.contains("raw") && !io::is_tiff_file(file))
      photo = io::turn_upright(photo, exif.orientation.value_or(1));
    if (extra.contains("raw"))
      ++raw_files;
    else
      (photo.depth() == CV_8U ? eight_bit : sixteen_bit) += 1;
    Frame frame;
    if (!exif.empty()) extra["exif"] = exif.to_json();
    if (exif.exposure_s) frame.exposure_us = *exif.exposure_s * 1e6;
    frame.image = io::linear_frame(photo, response, file.string());
    frame.filename = fmt::format("{:03d}.png", i + 1);
    frame.light_direction = entries[i].direction.normalized();
    if (!stack.frames.empty() && (frame.image.size() != stack.frames[0].image.size() ||
                                  frame.image.type() != stack.frames[0].image.type()))
      fail("{}: size or channels differ from {}", file.string(),
           io::rti_image_name(entries[0].filename, lp.string()));
    stack.frames.push_back(std::move(frame));
    frames_extra.push_back(std::move(extra));
  }
  nlohmann::json sources = nlohmann::json::array();
  for (const auto& e : entries) sources.push_back(io::rti_image_name(e.filename, lp.string()));
  nlohmann::json info = {{"from", s.input.string()},
                         {"lp", lp.string()},
                         {"images", sources},
                         {"linearised", response ? "response " + s.response.string() : std::string("srgb")},
                         {"eight_bit_images", eight_bit},
                         {"sixteen_bit_images_taken_as_linear", sixteen_bit},
                         {"raw_images", raw_files}};
  if (raw_files > 0) info["raw_demosaic"] = io::to_string(s.raw_demosaic);
  io::write_stack(s.out, stack, {{"import", info}, {"frames", frames_extra}});
  return info;
}

}  // namespace lightstage::pipeline
