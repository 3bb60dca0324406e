// The report writer: per-light statistics, the viewer's shading and embedded
// data, and the page built from a small synthetic solve.
#include "lightstage/host/report/report.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/solve_output.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/report/deep_zoom.hpp"
#include "lightstage/host/report/light_statistics.hpp"
#include "lightstage/host/report/viewer_data.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <zlib.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

namespace lightstage {
namespace {

namespace fs = std::filesystem;

constexpr int kSize = 32;

// A Lambertian sphere of albedo 0.6 under 8 distant lights, 16-bit grey, with
// ground truth; the lights' directions are exact, one frame is dark (an LED
// that did not fire) and one saturates.
ImageStack sphere_stack() {
  ImageStack stack;
  stack.mask = cv::Mat(kSize, kSize, CV_8UC1, cv::Scalar(0));
  GroundTruth truth;
  truth.normals = cv::Mat(kSize, kSize, CV_32FC3, cv::Scalar::all(0));
  const double r = kSize / 2.0 - 1.5;
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x < kSize; ++x) {
      const double nx = (x + 0.5 - kSize / 2.0) / r, ny = -(y + 0.5 - kSize / 2.0) / r;
      if (nx * nx + ny * ny > 0.95) continue;
      stack.mask.at<std::uint8_t>(y, x) = 255;
      truth.normals.at<cv::Vec3f>(y, x) = cv::Vec3f(static_cast<float>(nx), static_cast<float>(ny),
                                                    static_cast<float>(std::sqrt(1 - nx * nx - ny * ny)));
    }
  }
  stack.ground_truth = truth;
  for (int i = 0; i < 8; ++i) {
    Frame frame;
    frame.filename = fmt::format("{:03}.png", i + 1);
    const double a = 0.785 * i;
    frame.light_direction = Vec3(0.5 * std::cos(a), 0.5 * std::sin(a), 0.85).normalized();
    frame.led_id = 20 + i;
    frame.exposure_us = 1000 * (i + 1);
    frame.image = cv::Mat(kSize, kSize, CV_16UC1, cv::Scalar(0));
    const double gain = i == 5 ? 3.0 : 1.0;  // frame 6 saturates
    for (int y = 0; y < kSize; ++y) {
      for (int x = 0; x < kSize; ++x) {
        const auto n = truth.normals.at<cv::Vec3f>(y, x);
        const double shading =
            0.6 * std::max(0.0, n[0] * frame.light_direction.x() + n[1] * frame.light_direction.y() +
                                    n[2] * frame.light_direction.z());
        frame.image.at<std::uint16_t>(y, x) =
            cv::saturate_cast<std::uint16_t>(std::lround(gain * shading * 65535));
      }
    }
    if (i == 2) frame.image.setTo(0);  // frame 3 is dark
    stack.frames.push_back(frame);
  }
  return stack;
}

// Writes the stack and a Lambertian solve of it under `dir`; returns the result folder.
fs::path solved_result(const fs::path& dir) {
  const ImageStack stack = sphere_stack();
  io::write_stack(dir / "stack", stack);
  L2Options options;
  options.shadow_threshold = 0.01;
  const SolveResult result = solve_lambertian(make_observations(stack), options);
  io::write_solve_outputs(dir / "result", result, dir / "stack");
  return dir / "result";
}

// The text between `open` and the next `close` after it.
std::string between(const std::string& text, const std::string& open, const std::string& close) {
  const auto start = text.find(open);
  if (start == std::string::npos) return {};
  const auto from = start + open.size();
  return text.substr(from, text.find(close, from) - from);
}

std::vector<std::uint8_t> decode_base64(const std::string& text) {
  std::vector<std::uint8_t> out;
  std::uint32_t buffer = 0;
  int bits = 0;
  for (const char c : text) {
    int v = -1;
    if (c >= 'A' && c <= 'Z')
      v = c - 'A';
    else if (c >= 'a' && c <= 'z')
      v = c - 'a' + 26;
    else if (c >= '0' && c <= '9')
      v = c - '0' + 52;
    else if (c == '+')
      v = 62;
    else if (c == '/')
      v = 63;
    else
      continue;
    buffer = (buffer << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<std::uint8_t>((buffer >> bits) & 255));
    }
  }
  return out;
}

std::vector<std::uint8_t> inflate_zlib(const std::vector<std::uint8_t>& bytes, std::size_t size) {
  std::vector<std::uint8_t> out(size);
  uLongf length = static_cast<uLongf>(size);
  EXPECT_EQ(uncompress(out.data(), &length, bytes.data(), static_cast<uLong>(bytes.size())), Z_OK);
  EXPECT_EQ(length, size);
  return out;
}

TEST(LightStatistics, FindsTheDarkAndTheSaturatedFrame) {
  const ImageStack stack = sphere_stack();
  const auto stats = report::light_statistics(stack, 0.01);
  ASSERT_EQ(stats.size(), 8u);
  EXPECT_EQ(stats[2].shadow_share, 1.0);  // dark: every pixel at or below the threshold
  EXPECT_EQ(stats[2].mean_value, 0.0);
  EXPECT_GT(stats[5].saturated_share, 0.3);
  EXPECT_EQ(stats[0].saturated_share, 0.0);
  EXPECT_LT(stats[0].shadow_share, 0.2);
  EXPECT_NEAR(stats[0].mean_value, stats[1].mean_value, 0.05);
  EXPECT_EQ(stats[3].file, "004.png");
  EXPECT_EQ(stats[3].led_id, 23);
  EXPECT_EQ(stats[3].exposure_us, 4000);
  EXPECT_NE(testing::error_of([&] { report::light_statistics(stack, -1); }).find("shadow_threshold"),
            std::string::npos);
}

TEST(LightStatistics, PartsAddUpToTheWholeAndComeBackFromJson) {
  const ImageStack stack = sphere_stack();
  const Observations observations = make_observations(stack);
  const std::vector<std::string> files = report::frame_files(stack);
  report::LightStatisticsTally whole(files, {0.01, "the solver's"});
  whole.add(observations);
  // Two parts (a tile job's, read back from its part.json) count every pixel twice, with the same shares.
  report::LightStatisticsTally twice = report::LightStatisticsTally::from_json(whole.to_json(), "part.json");
  twice.add(report::LightStatisticsTally::from_json(whole.to_json(), "part.json"));
  const nlohmann::json once = whole.summary_json(), doubled = twice.summary_json();
  EXPECT_EQ(doubled["pixels"].get<std::size_t>(), 2 * observations.pixel_count());
  EXPECT_EQ(doubled["threshold_source"], "the solver's");
  EXPECT_EQ(doubled["frames"], once["frames"]);
  // What the solve recorded reads back as the statistics computed from the stack.
  const auto recorded = report::recorded_light_statistics(once, stack);
  ASSERT_TRUE(recorded);
  const auto computed = report::light_statistics(stack, 0.01);
  for (std::size_t i = 0; i < computed.size(); ++i)
    EXPECT_EQ((*recorded)[i].to_json(), computed[i].to_json());
  // Statistics of other frames are not taken for this stack's.
  nlohmann::json renamed = once;
  renamed["frames"][3]["file"] = "other.png";
  EXPECT_FALSE(report::recorded_light_statistics(renamed, stack));
  EXPECT_FALSE(report::recorded_light_statistics(nlohmann::json::object(), stack));
  // Bad parts name their file; parts of other frames do not add.
  nlohmann::json cut = whole.to_json();
  cut["sums"].erase(0);
  EXPECT_NE(testing::error_of([&] {
              report::LightStatisticsTally::from_json(cut, "tiles/part-1-of-2");
            }).find("tiles/part-1-of-2"),
            std::string::npos);
  report::LightStatisticsTally other({"a.png"}, {0.01, "the default"});
  EXPECT_NE(testing::error_of([&] { twice.add(other); }).find("different frames"), std::string::npos);
  report::LightStatisticsTally other_threshold(files, {0.5, "--shadow-threshold"});
  EXPECT_NE(testing::error_of([&] { twice.add(other_threshold); }).find("different shadow thresholds"),
            std::string::npos);
}

// The tally sums four frames to a vector; each frame's sum must still be the
// double of a loop over its pixels in order, and the counts exact. Seven
// frames: one vector and three left over.
TEST(LightStatistics, TallyIsEachFramesSumAndCountsOverThePixelsInOrder) {
  constexpr int kFrames = 7, kPixels = 53;
  constexpr double kThreshold = 0.25;
  Observations observations;
  observations.lights = Eigen::MatrixX3d::Zero(kFrames, 3);
  observations.intensities.resize(kPixels, kFrames);
  observations.saturated.resize(kPixels, kFrames);
  for (int p = 0; p < kPixels; ++p) {
    observations.pixels.emplace_back(p, 0);
    for (int i = 0; i < kFrames; ++i) {
      // Values of every size, so that the order of the sum shows in its last bits; some exactly at the
      // threshold.
      observations.intensities(p, i) = (p + i) % 11 == 0
                                           ? static_cast<float>(kThreshold)
                                           : static_cast<float>(std::pow(1.37, (p * 7 + i * 3) % 29) * 1e-3);
      observations.saturated(p, i) = (p * 3 + i) % 5 == 0;
    }
  }
  std::vector<std::string> files;
  for (int i = 0; i < kFrames; ++i) files.push_back(fmt::format("{:03}.png", i));
  report::LightStatisticsTally tally(files, {kThreshold, "the test's"});
  tally.add(observations);
  const nlohmann::json counted = tally.to_json();
  for (int i = 0; i < kFrames; ++i) {
    double sum = 0;
    std::size_t clipped = 0, dark = 0;
    for (int p = 0; p < kPixels; ++p) {
      sum += observations.intensities(p, i);
      clipped += observations.saturated(p, i) ? 1 : 0;
      dark += observations.intensities(p, i) <= kThreshold ? 1 : 0;
    }
    const auto frame = static_cast<std::size_t>(i);
    EXPECT_EQ(counted["sums"][frame].get<double>(), sum) << "frame " << i;
    EXPECT_EQ(counted["saturated"][frame].get<std::size_t>(), clipped) << "frame " << i;
    EXPECT_EQ(counted["shadow"][frame].get<std::size_t>(), dark) << "frame " << i;
  }
}

TEST(Report, ShowsThePerLightStatisticsTheSolveRecordedWithoutDecodingTheStack) {
  const auto dir = testing::scratch_dir();
  const auto result = solved_result(dir);
  nlohmann::json summary = nlohmann::json::parse(testing::read_text(result / "summary.json"));
  const ImageStack stack = sphere_stack();
  report::LightStatisticsTally tally(report::frame_files(stack), {0.25, "the solver's"});
  tally.add(make_observations(stack));
  summary["light_statistics"] = tally.summary_json();
  summary["light_statistics"]["frames"][0]["mean_value"] = 0.7654321;  // only the solve knows this one
  std::ofstream(result / "summary.json") << summary.dump();
  // The frames now read black: statistics from their pixels would say so.
  for (const Frame& frame : stack.frames)
    io::write_png16(dir / "stack" / frame.filename, cv::Mat(kSize, kSize, CV_16UC1, cv::Scalar(0)));
  std::string html = testing::read_text(report::write_report(result).file);
  EXPECT_NE(html.find("<section id=\"light-statistics\">"), std::string::npos);
  EXPECT_NE(html.find("<td>0.7654</td>"), std::string::npos);
  EXPECT_NE(html.find("value ≤ 0.25, the solver's threshold"), std::string::npos);
  // --shadow-threshold asks for statistics from the stack's pixels.
  report::ReportOptions options;
  options.shadow_threshold = 0.05;
  const auto again = report::write_report(result, result / "again.html", options);
  html = testing::read_text(again.file);
  EXPECT_EQ(html.find("<td>0.7654</td>"), std::string::npos);
  EXPECT_NE(html.find("8 light(s) look dark"), std::string::npos);
}

TEST(ViewerData, LambertianShadingIsAlbedoTimesClampedCosine) {
  report::SurfaceModel model;
  model.normals = cv::Mat(1, 3, CV_32FC3, cv::Scalar::all(0));
  model.normals.at<cv::Vec3f>(0, 0) = cv::Vec3f(0, 0, 1);
  model.normals.at<cv::Vec3f>(0, 1) = cv::Vec3f(1, 0, 0);
  model.valid = cv::Mat(1, 3, CV_8UC1, cv::Scalar(255));
  model.valid.at<std::uint8_t>(0, 2) = 0;
  model.albedo = cv::Mat(1, 3, CV_32FC1, cv::Scalar(0.5));
  const Vec3 light(0, 3, 4);  // normalised inside: (0, 0.6, 0.8)
  EXPECT_NEAR(report::shade(model, 0, 0, light), 0.5 * 0.8, 1e-6);
  EXPECT_EQ(report::shade(model, 1, 0, light), 0.0);             // n·l = 0
  EXPECT_EQ(report::shade(model, 1, 0, Vec3(-1, 0, 0.1)), 0.0);  // facing away: clamped
  EXPECT_EQ(report::shade(model, 2, 0, light), 0.0);             // no normal
  const cv::Mat image = report::relight(model, light);
  EXPECT_NEAR(image.at<float>(0, 0), 0.4, 1e-6);
}

TEST(ViewerData, BiPolynomialShadingUsesTheFittedModel) {
  report::SurfaceModel model;
  model.kind = report::ShadingKind::kBiPolynomial;
  model.order = 1;
  model.normals = cv::Mat(1, 1, CV_32FC3, cv::Scalar(0, 0, 1));
  model.valid = cv::Mat(1, 1, CV_8UC1, cv::Scalar(255));
  model.albedo = cv::Mat(1, 1, CV_32FC1, cv::Scalar(9));                          // not used by the model
  model.coefficients = cv::Mat(1, 1, CV_32FC4, cv::Scalar(0.3, 0.2, 0.1, 0.05));  // C00 C01 C10 C11
  const Vec3 l = Vec3(0.6, 0, 0.8);
  const Vec3 h = (l + Vec3::UnitZ()).normalized();
  const double x = h.z(), y = l.dot(h);
  const double rho = 0.3 + 0.2 * y + 0.1 * x + 0.05 * x * y;
  EXPECT_NEAR(report::shade(model, 0, 0, l), rho * 0.8, 1e-6);
}

TEST(ViewerData, PayloadCarriesTheResultFiles) {
  const auto dir = testing::scratch_dir();
  const auto result = solved_result(dir);
  std::vector<std::string> notes;
  const nlohmann::json summary = nlohmann::json::parse(testing::read_text(result / "summary.json"));
  io::SolveFolderRows folder(result);
  const auto model = report::load_surface_model(folder, 1 << 20, notes);
  EXPECT_EQ(model.stride, 1);
  EXPECT_EQ(model.kind, report::ShadingKind::kLambertian);
  EXPECT_DOUBLE_EQ(model.display_scale, summary["albedo_png_scale"].get<double>());
  const auto payload = report::encode_viewer_payload(model, {Vec3::UnitZ()}, Vec3(0, 0, 1));
  EXPECT_EQ(payload.meta["width"], kSize);
  EXPECT_EQ(payload.meta["model"]["kind"], "lambertian");
  std::size_t size = 0;
  for (const auto& plane : payload.meta["planes"]) size += plane["bytes"].get<std::size_t>();
  const auto bytes = inflate_zlib(decode_base64(payload.data_base64), size);
  // Albedo: the float map, bit for bit.
  const cv::Mat albedo = io::read_pfm(result / "albedo.pfm");
  const auto& albedo_plane = payload.meta["planes"][0];
  EXPECT_EQ(albedo_plane["name"], "albedo");
  EXPECT_EQ(std::memcmp(bytes.data() + albedo_plane["offset"].get<std::size_t>(), albedo.data,
                        kSize * kSize * sizeof(float)),
            0);
  // Normals: the normal.png encoding (x y z order), decoding to the file's normals.
  const auto& normal_plane = payload.meta["planes"][1];
  EXPECT_EQ(normal_plane["name"], "normals");
  const auto decoded = io::read_normal_map(result / "normal.png");
  const auto* encoded =
      reinterpret_cast<const std::uint16_t*>(bytes.data() + normal_plane["offset"].get<std::size_t>());
  int checked = 0;
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x < kSize; ++x) {
      const auto* e = encoded + 3 * (y * kSize + x);
      if (decoded.valid.at<std::uint8_t>(y, x) == 0) {
        EXPECT_TRUE(e[0] == 0 && e[1] == 0 && e[2] == 0);
        continue;
      }
      const auto n = decoded.normals.at<cv::Vec3f>(y, x);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(e[c] / 65535.0 * 2 - 1, n[c], 2.0 / 65535);
      ++checked;
    }
  }
  EXPECT_GT(checked, 400);
}

TEST(Report, HasEverySectionForASolvedSimulatedStack) {
  const auto dir = testing::scratch_dir();
  const auto result = solved_result(dir);
  const auto summary = report::write_report(result);
  EXPECT_EQ(summary.file, result / "report.html");
  const std::vector<std::string> expected = {"viewer",   "surface", "lights", "light-statistics",
                                             "residual", "error",   "notes"};
  EXPECT_EQ(summary.sections, expected);
  const std::string html = testing::read_text(summary.file);
  EXPECT_EQ(html.size(), summary.bytes);
  // Self-contained: images are data URIs, nothing is fetched.
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_NE(html.find("src=\"data:image/png;base64,"), std::string::npos);
  EXPECT_NE(html.find("window.lightstageViewer"), std::string::npos);
  EXPECT_EQ(html.find("\nimport "), std::string::npos);  // modules joined at build time
  // The per-light table flags the dark frame and counts the saturated one.
  EXPECT_NE(html.find("1 light(s) look dark"), std::string::npos);
  EXPECT_NE(html.find("<td class=\"text\">003.png</td><td>22</td>"), std::string::npos);
  // The viewer's metadata parses and matches the result.
  const auto meta = nlohmann::json::parse(
      between(html, "<script type=\"application/json\" id=\"lightstage-viewer-meta\">", "</script>"));
  EXPECT_EQ(meta["width"], kSize);
  EXPECT_EQ(meta["lights"].size(), 8u);
  // The error numbers are the solve's.
  EXPECT_NE(html.find("id=\"error-numbers\""), std::string::npos);
  // No depth.pfm: a note says so.
  bool depth_note = false;
  for (const auto& note : summary.notes) depth_note |= note.find("depth.pfm") != std::string::npos;
  EXPECT_TRUE(depth_note);
}

TEST(Report, DrawsDepthAndCalibrationWhenPresentAndOmitsWhatIsMissing) {
  const auto dir = testing::scratch_dir();
  const auto result = solved_result(dir);
  cv::Mat depth(kSize, kSize, CV_32FC1, cv::Scalar(0));
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) depth.at<float>(y, x) = static_cast<float>(std::hypot(x - 16, y - 16));
  io::write_pfm(result / "depth.pfm", depth);
  fs::remove_all(dir / "stack");  // the input stack is gone: no lights, no statistics, no ground truth
  report::ReportSummary summary = report::write_report(result, dir / "out" / "page.html");
  EXPECT_TRUE(fs::exists(dir / "out" / "page.html"));
  const std::vector<std::string> expected = {"viewer", "surface", "depth", "residual", "notes"};
  EXPECT_EQ(summary.sections, expected);
  std::string notes;
  for (const auto& note : summary.notes) notes += note + "\n";
  EXPECT_NE(notes.find("was not found"), std::string::npos) << notes;
  EXPECT_NE(notes.find("No ground truth"), std::string::npos) << notes;

  // Ground truth given by flag: the error section comes back.
  io::write_normal_map(dir / "gt.png", sphere_stack().ground_truth->normals);
  report::ReportOptions options;
  options.ground_truth = dir / "gt.png";
  summary = report::write_report(result, {}, options);
  EXPECT_NE(std::find(summary.sections.begin(), summary.sections.end(), "error"), summary.sections.end());

  // Depth from a `lightstage integrate` folder: its camera sets the relief's pixel size.
  fs::create_directories(dir / "surface");
  fs::rename(result / "depth.pfm", dir / "surface" / "depth.pfm");
  std::ofstream(dir / "surface" / "surface.json")
      << R"({"camera": {"model": "orthographic", "pixel_size": 0.5}})";
  options = {};
  options.depth = dir / "surface";
  const std::string html = report::render_report(result, options, &summary);
  EXPECT_NE(std::find(summary.sections.begin(), summary.sections.end(), "depth"), summary.sections.end());
  EXPECT_NE(html.find("(0.5 mm per pixel)"), std::string::npos);
  options.depth = dir / "nowhere";
  EXPECT_NE(testing::error_of([&] { report::render_report(result, options); }).find("--depth"),
            std::string::npos);
}

TEST(Report, ErrorsNameTheFile) {
  const auto dir = testing::scratch_dir();
  EXPECT_NE(testing::error_of([&] { report::render_report(dir / "missing"); }).find("missing: not a folder"),
            std::string::npos);
  EXPECT_NE(testing::error_of([&] { report::render_report(dir); }).find("normal.png"), std::string::npos);
  const auto result = solved_result(dir);
  report::ReportOptions options;
  options.ground_truth = dir / "nowhere.png";
  EXPECT_NE(testing::error_of([&] { report::render_report(result, options); }).find("--gt"),
            std::string::npos);
  options = {};
  options.viewer_max_pixels = 0;
  EXPECT_NE(testing::error_of([&] { report::render_report(result, options); }).find("viewer_max_pixels"),
            std::string::npos);
}

TEST(Report, LargeResultsAreSubsampledForTheViewer) {
  const auto dir = testing::scratch_dir();
  const auto result = solved_result(dir);
  report::ReportOptions options;
  options.viewer_max_pixels = 300;  // 32×32 = 1024 pixels → stride 2
  report::ReportSummary summary;
  const std::string html = report::render_report(result, options, &summary);
  const auto meta = nlohmann::json::parse(
      between(html, "<script type=\"application/json\" id=\"lightstage-viewer-meta\">", "</script>"));
  EXPECT_EQ(meta["stride"], 2);
  EXPECT_EQ(meta["width"], 16);
}

// The page without the line that says when it was made.
std::string without_time(std::string html) {
  const auto at = html.find("report by lightstage");
  if (at != std::string::npos) html.erase(at, html.find("</p>", at) - at);
  return html;
}

// The picture of the <img> whose alt text is `alt`, decoded from its data URI.
cv::Mat picture(const std::string& html, const std::string& alt) {
  const auto end = html.find("\" alt=\"" + alt + "\"");
  const auto start = html.rfind("base64,", end) + 7;
  const auto bytes = decode_base64(html.substr(start, end - start));
  return cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
}

// The sphere's solve with every map the report draws: depth, confidence, a choice per pixel.
fs::path result_with_every_map(const fs::path& dir) {
  const ImageStack stack = sphere_stack();
  io::write_stack(dir / "stack", stack);
  L2Options options;
  options.shadow_threshold = 0.01;
  SolveResult result = solve_lambertian(make_observations(stack), options);
  result.confidence = cv::Mat(result.normals.size(), CV_32FC1, cv::Scalar(0));
  result.choice = cv::Mat(result.normals.size(), CV_8UC1, cv::Scalar(0));
  result.choices = {"l2", "robust"};
  cv::Mat depth(kSize, kSize, CV_32FC1, cv::Scalar(0));
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x < kSize; ++x) {
      depth.at<float>(y, x) = static_cast<float>(std::sin(0.3 * x) * std::cos(0.2 * y) + 2);
      if (result.solved.at<std::uint8_t>(y, x) == 0) continue;
      result.confidence.at<float>(y, x) = static_cast<float>((x * 7 + y * 3) % 11) / 10.0f;
      result.choice.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(1 + (x / 4 + y / 5) % 2);
    }
  }
  io::write_solve_outputs(dir / "result", result, dir / "stack");
  io::write_pfm(dir / "result" / "depth.pfm", depth);
  return dir / "result";
}

TEST(Report, BandsOfAFewRowsDrawTheSamePageAsTheWholeResult) {
  const auto dir = testing::scratch_dir();
  const auto result = result_with_every_map(dir);
  report::ReportOptions options;
  options.band_rows = kSize;  // one band: decoded once and kept for every pass
  report::ReportSummary whole_summary;
  const std::string whole = without_time(report::render_report(result, options, &whole_summary));
  const std::vector<std::string> expected = {"viewer",           "surface",  "depth", "lights",
                                             "light-statistics", "residual", "error"};
  EXPECT_EQ(whole_summary.sections, expected) << "every map drawn, nothing to note";
  EXPECT_NE(whole.find("alt=\"method per pixel\""), std::string::npos);
  EXPECT_NE(whole.find("alt=\"confidence (0.5"), std::string::npos);
  for (const int rows : {1, 5, 13}) {
    options.band_rows = rows;
    EXPECT_EQ(without_time(report::render_report(result, options)), whole) << rows << " rows a band";
  }
  // Without normal.exr the later passes decode normal.png again for the
  // normals: the same page as the whole result without it.
  std::filesystem::remove(result / "normal.exr");
  options.band_rows = kSize;
  const std::string whole_png = without_time(report::render_report(result, options));
  options.band_rows = 5;
  EXPECT_EQ(without_time(report::render_report(result, options)), whole_png);
}

TEST(Report, PicturesOfAResultOverTheBudgetAreBlockMeansOfTheFullPictures) {
  const auto dir = testing::scratch_dir();
  const auto result = result_with_every_map(dir);
  const std::string full = report::render_report(result);
  report::ReportOptions options;
  options.picture_max_pixels = 300;  // 32×32 = 1024 pixels → blocks of 2×2
  options.band_rows = 3;             // bands that split the blocks
  report::ReportSummary summary;
  const std::string small = report::render_report(result, options, &summary);
  bool noted = false;
  for (const auto& note : summary.notes) noted |= note.find("at 1/2 of its size") != std::string::npos;
  EXPECT_TRUE(noted);
  for (const std::string alt : {"normal map", "albedo", "shaded depth", "angular error map"}) {
    const cv::Mat big = picture(full, alt), overview = picture(small, alt);
    ASSERT_EQ(big.size(), cv::Size(kSize, kSize)) << alt;
    ASSERT_EQ(overview.size(), cv::Size(kSize / 2, kSize / 2)) << alt;
    ASSERT_EQ(overview.type(), CV_8UC4) << alt;
    for (int y = 0; y < overview.rows; ++y) {
      for (int x = 0; x < overview.cols; ++x) {
        cv::Vec4d sum(0, 0, 0, 0);
        for (int dy = 0; dy < 2; ++dy) {
          for (int dx = 0; dx < 2; ++dx) {
            const auto p = big.at<cv::Vec4b>(2 * y + dy, 2 * x + dx);
            if (p[3] == 0) continue;
            sum += cv::Vec4d(p[0], p[1], p[2], 1);
          }
        }
        const auto o = overview.at<cv::Vec4b>(y, x);
        ASSERT_EQ(o[3], std::lround(255 * sum[3] / 4)) << alt << " at " << x << "," << y;
        if (sum[3] == 0) continue;
        for (int c = 0; c < 3; ++c)
          ASSERT_EQ(o[c], std::lround(sum[c] / sum[3])) << alt << " at " << x << "," << y;
      }
    }
  }
}

// A result over the page's picture budget gets full-size Deep Zoom pyramids beside the page, linked from
// it, their last level the full pictures; "never" and a result within the budget get none.
TEST(Report, AResultOverThePictureBudgetGetsFullSizePyramidsBesideThePage) {
  const auto dir = testing::scratch_dir();
  const auto result = result_with_every_map(dir);
  const std::string full = report::render_report(result);
  report::ReportOptions options;
  options.picture_max_pixels = 300;
  const report::ReportSummary summary = report::write_report(result, dir / "page.html", options);
  ASSERT_EQ(summary.pyramids.size(), 2u);
  EXPECT_EQ(summary.pyramids[0], dir / "page_files" / "normal.dzi");
  EXPECT_EQ(summary.pyramids[1], dir / "page_files" / "albedo.dzi");
  const std::string page = testing::read_text(dir / "page.html");
  EXPECT_NE(page.find("<a href=\"page_files/normal.dzi\">"), std::string::npos);
  EXPECT_NE(page.find("<a href=\"page_files/albedo.dzi\">"), std::string::npos);
  EXPECT_EQ(summary.to_json()["pyramids"].size(), 2u);
  const int top = report::deep_zoom_levels({kSize, kSize}) - 1;
  for (const auto& [alt, name] : {std::pair{"normal map", "normal"}, std::pair{"albedo", "albedo"}}) {
    EXPECT_NE(testing::read_text(dir / "page_files" / (std::string(name) + ".dzi"))
                  .find(fmt::format("<Size Width=\"{}\" Height=\"{}\"/>", kSize, kSize)),
              std::string::npos);
    // One tile holds the whole 32×32 picture at the last level: the full-size page picture.
    const cv::Mat tile = cv::imread(
        (dir / "page_files" / (std::string(name) + "_files") / std::to_string(top) / "0_0.png").string(),
        cv::IMREAD_UNCHANGED);
    const cv::Mat big = picture(full, alt);
    ASSERT_EQ(tile.size(), big.size()) << alt;
    EXPECT_EQ(cv::norm(tile, big, cv::NORM_INF), 0) << alt;
  }

  // A page name that is not a plain URL segment: its links are percent-encoded.
  report::write_report(result, dir / "run #3.html", options);
  EXPECT_NE(testing::read_text(dir / "run #3.html").find("<a href=\"run%20%233_files/zoom.html\">"),
            std::string::npos);
  EXPECT_NE(testing::read_text(dir / "run #3_files" / "zoom.html").find("<a href=\"../run%20%233.html\">"),
            std::string::npos);
  // A PAGE_files the report did not write is refused, not written into.
  fs::create_directories(dir / "saved_files");
  EXPECT_NE(testing::error_of([&] {
              report::write_report(result, dir / "saved.html", options);
            }).find("saved_files: exists and is not a folder a report wrote"),
            std::string::npos);
  EXPECT_TRUE(fs::is_empty(dir / "saved_files"));

  options.pyramids = "never";
  EXPECT_TRUE(report::write_report(result, dir / "never.html", options).pyramids.empty());
  EXPECT_FALSE(fs::exists(dir / "never_files"));
  // The same page again without pyramids: the earlier ones go with it.
  report::write_report(result, dir / "page.html", options);
  EXPECT_FALSE(fs::exists(dir / "page_files"));
  EXPECT_TRUE(report::write_report(result, dir / "within.html").pyramids.empty()) << "within the budget";
  EXPECT_FALSE(fs::exists(dir / "within_files"));
  options.pyramids = "sometimes";
  EXPECT_NE(testing::error_of([&] {
              report::write_report(result, dir / "bad.html", options);
            }).find("--pyramids: auto, always or never, got 'sometimes'"),
            std::string::npos);
}

TEST(Report, ABadCropOrABrokenGroundTruthInTheStackIsANoteNotAFailure) {
  const auto dir = testing::scratch_dir();
  const auto result = result_with_every_map(dir);
  const auto summary_path = result / "summary.json";
  const nlohmann::json summary = nlohmann::json::parse(testing::read_text(summary_path));
  const auto notes_of = [&](const nlohmann::json& crop) {
    nlohmann::json edited = summary;
    edited["crop"] = crop;
    std::ofstream(summary_path) << edited.dump();
    report::ReportSummary page;
    report::render_report(result, {}, &page);
    std::string notes;
    for (const auto& note : page.notes) notes += note + "\n";
    EXPECT_EQ(std::find(page.sections.begin(), page.sections.end(), "error"), page.sections.end()) << notes;
    return notes;
  };
  EXPECT_NE(notes_of({1, 2}).find("crop must be [x, y, width, height]"), std::string::npos);
  EXPECT_NE(notes_of({0, 0, 64, 64}).find("reaches outside the stack's 32x32"), std::string::npos);

  std::ofstream(summary_path) << summary.dump();
  std::ofstream(dir / "stack" / "Normal_gt.png", std::ios::trunc) << "not a PNG";
  report::ReportSummary page;
  report::render_report(result, {}, &page);
  std::string notes;
  for (const auto& note : page.notes) notes += note + "\n";
  EXPECT_NE(notes.find("The stack's ground truth could not be read"), std::string::npos) << notes;
  EXPECT_NE(std::find(page.sections.begin(), page.sections.end(), "lights"), page.sections.end())
      << "the rest of the stack's sections stay";
}

TEST(Report, TheMethodMapOverviewKeepsItsCategoriesAndPartBlocksAreDrawn) {
  const auto dir = testing::scratch_dir();
  const auto result = result_with_every_map(dir);
  report::ReportOptions options;
  options.picture_max_pixels = 121;  // 32×32 → blocks of 3×3, the last row and column of blocks partial
  const std::string html = report::render_report(result, options);
  const cv::Mat choices = cv::imread((result / "method_map.png").string(), cv::IMREAD_UNCHANGED);
  const cv::Mat overview = picture(html, "method per pixel");
  ASSERT_EQ(overview.size(), cv::Size(11, 11));
  ASSERT_EQ(overview.type(), CV_8UC3);
  for (int y = 0; y < overview.rows; ++y)
    for (int x = 0; x < overview.cols; ++x)
      ASSERT_EQ(overview.at<cv::Vec3b>(y, x), choices.at<cv::Vec3b>(3 * y, 3 * x)) << x << "," << y;
  EXPECT_EQ(picture(html, "normal map").size(), cv::Size(11, 11));
}

}  // namespace
}  // namespace lightstage
