#include "lightstage/pipeline/rti_exchange.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/calibration/lp_file.hpp"
#include "lightstage/host/io/output_folder.hpp"
#include "lightstage/host/io/rti_files.hpp"
#include "lightstage/host/io/rti_import.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/reflectance/rti_basis.hpp"
#include "lightstage/host/reflectance/rti_stack_fit.hpp"

#include <Eigen/Dense>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <optional>

namespace lightstage::pipeline {

nlohmann::json export_rti(const ExportSettings& s) {
  if (s.format != "ptm" && s.format != "hsh") fail("--format: '{}' is not ptm or hsh", s.format);
  if (s.colour != "lrgb" && s.colour != "rgb") fail("--colour: '{}' is not lrgb or rgb", s.colour);
  if (s.hsh_order != 2 && s.hsh_order != 3) fail("--order: {} is not 2 or 3", s.hsh_order);
  if (std::filesystem::exists(s.out)) fail("--out: {} already exists; choose another file", s.out.string());
  const ImageStack stack = io::load_stack(s.input, {.min_images = 3, .load_ground_truth = false});
  const RtiBasis basis = s.format == "ptm"  ? RtiBasis::ptm
                         : s.hsh_order == 2 ? RtiBasis::hsh2
                                            : RtiBasis::hsh3;
  const io::RtiImage image = fit_rti_stack(stack, basis);
  if (s.format == "ptm")
    io::write_ptm(s.out, image, s.colour == "rgb" ? io::PtmFormat::rgb : io::PtmFormat::lrgb);
  else
    io::write_hsh(s.out, image);
  return {{"out", s.out.string()},
          {"model", rti_basis_name(basis)},
          {"width", image.width},
          {"height", image.height},
          {"terms", rti_term_count(basis)},
          {"lights", stack.frames.size()},
          {"colour", s.format == "ptm" ? s.colour : std::string("rgb")}};
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

nlohmann::json rti_holdout(const HoldoutSettings& s) {
  const ImageStack stack = io::load_stack(s.input, {.min_images = 3, .load_ground_truth = false});
  const Observations obs = make_observations(stack);
  const auto m = static_cast<int>(obs.image_count());
  if (s.held_out < 1 || s.held_out > m)
    fail("--held-out: {} is not in 1..{} (the stack's lights)", s.held_out, m);
  std::vector<int> held;
  for (int i = 0; i < s.held_out; ++i)
    held.push_back(static_cast<int>(static_cast<long>(i) * m / s.held_out));
  const Eigen::MatrixXf all = obs.intensities;
  const char* names[] = {"ptm", "hsh2", "hsh3", "l2"};
  nlohmann::json models = nlohmann::json::object();
  for (const char* name : names) models[name] = {{"per_light", nlohmann::json::array()}};
  for (const int h : held) {
    std::vector<int> keep;
    for (int j = 0; j < m; ++j)
      if (j != h) keep.push_back(j);
    Eigen::MatrixXf values(all.rows(), static_cast<Eigen::Index>(keep.size()));
    Eigen::MatrixX3d lights(static_cast<Eigen::Index>(keep.size()), 3);
    for (std::size_t k = 0; k < keep.size(); ++k) {
      values.col(static_cast<Eigen::Index>(k)) = all.col(keep[k]);
      lights.row(static_cast<Eigen::Index>(k)) = obs.lights.row(keep[k]);
    }
    const Vec3 light = obs.lights.row(h).transpose();
    const Eigen::VectorXf photo = all.col(h);
    for (const char* name : names) {
      Eigen::VectorXf relit;
      if (std::string(name) == "l2") {
        relit = l2_relight(values, lights, light);
      } else {
        const RtiBasis basis = parse_rti_basis(name);
        relit = evaluate_rti(basis, fit_rti(basis, values, lights), light);
      }
      const double err = (relit - photo).norm() / std::max(photo.norm(), 1e-12f);
      models[name]["per_light"].push_back(err);
    }
  }
  for (const char* name : names) {
    double sum = 0;
    for (const auto& e : models[name]["per_light"]) sum += e.get<double>();
    models[name]["relative_rmse"] = sum / static_cast<double>(held.size());
  }
  return {{"input", s.input.string()},
          {"held_out", held},
          {"lights", m},
          {"pixels", obs.pixel_count()},
          {"models", models}};
}

namespace {

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
  int eight_bit = 0, sixteen_bit = 0;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const std::string where = fmt::format("{}:{}", lp.string(), i + 2);
    const std::string name = io::rti_image_name(entries[i].filename, where);
    const std::filesystem::path file = s.input / name;
    if (!std::filesystem::is_regular_file(file))
      fail("{}: image: {} is not in {}", where, name, s.input.string());
    cv::Mat raw = cv::imread(file.string(), cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
    if (raw.empty()) fail("{}: not an image OpenCV can read (JPEG, PNG, TIFF)", file.string());
    if (raw.channels() == 4) cv::cvtColor(raw, raw, cv::COLOR_BGRA2BGR);
    if (raw.channels() != 1 && raw.channels() != 3)
      fail("{}: channels: {} (1 or 3 expected)", file.string(), raw.channels());
    (raw.depth() == CV_8U ? eight_bit : sixteen_bit) += 1;
    Frame frame;
    frame.image = io::linear_frame(raw, response, file.string());
    frame.filename = fmt::format("{:03d}.png", i + 1);
    frame.light_direction = entries[i].direction.normalized();
    if (!stack.frames.empty() && (frame.image.size() != stack.frames[0].image.size() ||
                                  frame.image.type() != stack.frames[0].image.type()))
      fail("{}: size or channels differ from {}", file.string(),
           io::rti_image_name(entries[0].filename, lp.string()));
    stack.frames.push_back(std::move(frame));
  }
  nlohmann::json sources = nlohmann::json::array();
  for (const auto& e : entries) sources.push_back(io::rti_image_name(e.filename, lp.string()));
  const nlohmann::json info = {
      {"from", s.input.string()},
      {"lp", lp.string()},
      {"images", sources},
      {"linearised", response ? "response " + s.response.string() : std::string("srgb")},
      {"eight_bit_images", eight_bit},
      {"sixteen_bit_images_taken_as_linear", sixteen_bit}};
  io::write_stack(s.out, stack, {{"import", info}});
  return info;
}

}  // namespace lightstage::pipeline
