#include "lightstage/host/io/solve_output.hpp"
#include "lightstage/host/io/solve_folder_rows.hpp"
#include "lightstage/host/io/solve_output_writer.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/version.hpp"
#include "lightstage/host/io/exr.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/write_fault.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"
#include "synthetic.hpp"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <vector>

namespace lightstage {
namespace {

TEST(HostSolveOutput, WritesEveryFileAndASummary) {
  const auto scene = testing::make_scene(20, 10, 8, 3, false);
  const SolveResult result = solve_lambertian(scene.observations, L2Options{});
  const auto dir = testing::scratch_dir() / "out";
  const auto written = io::write_solve_outputs(dir, result, "/some/input", {{"stack_images", 8}});

  for (const char* name :
       {"normal.png", "normal_vis.png", "albedo.png", "albedo.pfm", "residual.pfm", "summary.json"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / name)) << name;
  }
  const auto normals = io::read_normal_map(dir / "normal.png");
  EXPECT_EQ(cv::countNonZero(normals.valid), 200);
  EXPECT_LT(cv::norm(normals.normals, result.normals, cv::NORM_INF), 1e-4);
  EXPECT_EQ(io::read_image(dir / "normal_vis.png").type(), CV_8UC3);
  EXPECT_EQ(cv::norm(io::read_pfm(dir / "albedo.pfm"), result.albedo, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(io::read_pfm(dir / "residual.pfm"), result.residual, cv::NORM_INF), 0);

  const double scale = written["albedo_png_scale"];
  EXPECT_GT(scale, 0.5);
  const cv::Mat albedo16 = io::read_image(dir / "albedo.png");
  ASSERT_EQ(albedo16.type(), CV_16UC1);
  // Decoding albedo.png with the recorded scale gives the albedo (up to quantisation and the clip at 1).
  const float a = result.albedo.at<float>(5, 5);
  if (a < scale) {
    EXPECT_NEAR(albedo16.at<std::uint16_t>(5, 5) / 65535.0 * scale, a, scale / 65535.0);
  }

  std::ifstream in(dir / "summary.json");
  const auto summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary, written);
  EXPECT_EQ(summary["method"], "l2");
  EXPECT_EQ(summary["pixels_solved"], 200);
  EXPECT_EQ(summary["input"], "/some/input");
  EXPECT_EQ(summary["software"], std::string("lightstage ") + kVersion);
  EXPECT_EQ(summary["parameters"]["t_low"], 1.0);
  EXPECT_EQ(summary["stack_images"], 8);
  EXPECT_TRUE(summary.contains("time"));
}

TEST(HostSolveFolder, AChoiceMapIsWrittenInColourWithItsLegendAndCounts) {
  const auto scene = testing::make_scene(20, 10, 8, 3, false);
  SolveResult result = solve_lambertian(scene.observations, L2Options{});
  result.choices = {"first", "second"};
  result.choice = cv::Mat(result.normals.size(), CV_8UC1, cv::Scalar::all(0));
  result.choice.setTo(1, result.solved);
  result.choice(cv::Rect(0, 0, 5, 10)).setTo(2);
  const auto dir = testing::scratch_dir() / "out";
  const auto summary = io::write_solve_outputs(dir, result, "/some/input");
  ASSERT_TRUE(summary.contains("method_map"));
  const auto& choices = summary["method_map"]["choices"];
  ASSERT_EQ(choices.size(), 2u);
  EXPECT_EQ(choices[0]["method"], "first");
  EXPECT_EQ(choices[0]["pixels"], 150);
  EXPECT_EQ(choices[1]["pixels"], 50);
  EXPECT_EQ(summary["files"]["method_map"], "method_map.png");
  const cv::Mat picture = io::read_image(dir / "method_map.png");
  ASSERT_EQ(picture.type(), CV_8UC3);
  // Each choice in its legend colour (the PNG holds BGR).
  const std::string first = choices[0]["colour"], second = choices[1]["colour"];
  const auto colour_at = [&](int x, int y) {
    const cv::Vec3b bgr = picture.at<cv::Vec3b>(y, x);
    return fmt::format("#{:02x}{:02x}{:02x}", bgr[2], bgr[1], bgr[0]);
  };
  EXPECT_EQ(colour_at(10, 5), first);
  EXPECT_EQ(colour_at(2, 5), second);
  EXPECT_NE(first, second);
}

TEST(HostSolveFolder, ReadsBackWhatWasWritten) {
  const auto scene = testing::make_scene(20, 10, 8, 3, false);
  SolveResult result = solve_lambertian(scene.observations, L2Options{});
  result.confidence = cv::Mat(result.normals.size(), CV_32FC1, cv::Scalar(0.25));
  const auto dir = testing::scratch_dir() / "out";
  const auto written = io::write_solve_outputs(dir, result, "/some/input");

  const io::SolveFolder folder = io::read_solve_folder(dir);
  EXPECT_EQ(folder.summary, written);
  EXPECT_EQ(folder.method(), "l2");
  EXPECT_EQ(cv::countNonZero(folder.solved), 200);
  EXPECT_LT(cv::norm(folder.normals, result.normals, cv::NORM_INF), 1e-4);
  EXPECT_FALSE(folder.albedo_from_png);
  EXPECT_EQ(cv::norm(folder.albedo, result.albedo, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(folder.residual, result.residual, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(folder.confidence, result.confidence, cv::NORM_INF), 0);
  EXPECT_DOUBLE_EQ(folder.albedo_png_scale, written["albedo_png_scale"].get<double>());
  EXPECT_TRUE(folder.coefficients.empty());
  EXPECT_EQ(folder.reflectance_order, 0);
  // The display albedo is what albedo.png shows.
  const cv::Mat png = io::read_image(dir / "albedo.png");
  cv::Mat shown;
  png.convertTo(shown, CV_32FC1, 1.0 / 65535);
  EXPECT_LT(cv::norm(folder.display_albedo(), shown, cv::NORM_INF), 1.0 / 65535 + 1e-6);
}

// A colour stack's result: the colour albedo beside the grey one, read back
// as the same chroma, shown (and so meshed) in colour, relit in colour.
TEST(HostSolveFolder, AColourResultKeepsItsChromaThroughTheFiles) {
  const auto scene = testing::make_scene(20, 10, 8, 3, false);
  SolveResult result = solve_lambertian(scene.observations, L2Options{});
  result.chroma = cv::Mat(result.normals.size(), CV_32FC3, cv::Scalar(0.5, 1.0, 1.6));  // B G R
  const auto dir = testing::scratch_dir() / "out";
  const auto written = io::write_solve_outputs(dir, result, "/some/input");
  EXPECT_EQ(written["files"]["albedo_colour"], "albedo_rgb.png");
  EXPECT_EQ(written["files"]["albedo_colour_float"], "albedo_rgb.pfm");
  // Grey files as before.
  EXPECT_EQ(cv::norm(io::read_pfm(dir / "albedo.pfm"), result.albedo, cv::NORM_INF), 0);
  EXPECT_EQ(io::read_image(dir / "albedo.png").type(), CV_16UC1);
  const cv::Mat colour = io::read_pfm(dir / "albedo_rgb.pfm");
  ASSERT_EQ(colour.type(), CV_32FC3);
  const float a = result.albedo.at<float>(4, 7);
  EXPECT_FLOAT_EQ(colour.at<cv::Vec3f>(4, 7)[2], 1.6f * a);  // R
  EXPECT_EQ(io::read_image(dir / "albedo_rgb.png").type(), CV_16UC3);
  EXPECT_FLOAT_EQ(io::read_exr(dir / "albedo_rgb.exr", {"R"}).at<float>(4, 7), 1.6f * a);
  EXPECT_FLOAT_EQ(io::read_exr(dir / "albedo.exr", {"Y"}).at<float>(4, 7), a);
  // The colour picture's white is the 99.5th percentile of every channel's values.
  const double colour_scale = written["albedo_rgb_png_scale"];
  std::size_t above = 0, total = 0;
  for (int y = 0; y < colour.rows; ++y)
    for (int x = 0; x < colour.cols; ++x)
      for (int c = 0; c < 3; ++c, ++total) above += colour.at<cv::Vec3f>(y, x)[c] > colour_scale ? 1 : 0;
  EXPECT_LE(above, total / 200 + 1);
  EXPECT_GT(colour_scale, written["albedo_png_scale"].get<double>());  // the red channel sets it

  const io::SolveFolder folder = io::read_solve_folder(dir);
  ASSERT_EQ(folder.chroma.type(), CV_32FC3);
  EXPECT_LT(cv::norm(folder.chroma, result.chroma, cv::NORM_INF), 1e-6);
  const cv::Mat shown = folder.display_albedo();
  ASSERT_EQ(shown.type(), CV_32FC3);
  EXPECT_NEAR(shown.at<cv::Vec3f>(4, 7)[0], std::min(1.0, 0.5 * a / colour_scale), 1e-6);

  // Solved again from a grey stack into the same folder: the old colour files stay but are not read.
  result.chroma.release();
  io::write_solve_outputs(dir, result, "/some/input");
  EXPECT_TRUE(std::filesystem::exists(dir / "albedo_rgb.pfm"));
  EXPECT_TRUE(io::read_solve_folder(dir).chroma.empty());
}

TEST(HostSolveFolder, AlbedoFallsBackToThePngTimesItsScale) {
  const auto scene = testing::make_scene(20, 10, 8, 3, false);
  const SolveResult result = solve_lambertian(scene.observations, L2Options{});
  const auto dir = testing::scratch_dir() / "out";
  const auto written = io::write_solve_outputs(dir, result, "/some/input");
  std::filesystem::remove(dir / "albedo.pfm");
  const io::SolveFolder folder = io::read_solve_folder(dir);
  ASSERT_TRUE(folder.albedo_from_png);
  const double scale = written["albedo_png_scale"];
  for (int y = 0; y < result.albedo.rows; ++y) {
    for (int x = 0; x < result.albedo.cols; ++x) {
      const float a = result.albedo.at<float>(y, x);
      if (a < scale) {
        EXPECT_NEAR(folder.albedo.at<float>(y, x), a, scale / 65535.0) << x << "," << y;
      }
    }
  }
}

TEST(HostSolveFolder, RefusesMapsOfAnotherSizeAndBadSummaries) {
  const auto scene = testing::make_scene(20, 10, 8, 3, false);
  const SolveResult result = solve_lambertian(scene.observations, L2Options{});
  const auto dir = testing::scratch_dir() / "out";
  io::write_solve_outputs(dir, result, "/some/input");
  io::write_pfm(dir / "residual.pfm", cv::Mat(3, 4, CV_32FC1, cv::Scalar(0)));
  EXPECT_THROW(
      {
        try {
          io::read_solve_folder(dir);
        } catch (const InputError& e) {
          EXPECT_THAT(e.what(), ::testing::HasSubstr("residual.pfm"));
          throw;
        }
      },
      InputError);
  io::write_pfm(dir / "residual.pfm", result.residual);
  std::ofstream(dir / "summary.json") << "[1, 2]";
  EXPECT_THROW(io::read_solve_folder(dir), InputError);
  std::ofstream(dir / "summary.json") << "{ not json";
  EXPECT_THROW(io::read_solve_folder(dir), InputError);
  EXPECT_THROW(io::read_solve_folder(dir / "missing"), InputError);
}

}  // namespace
}  // namespace lightstage

namespace lightstage {
namespace {

namespace fs = std::filesystem;

// A result with every optional map: colour, confidence, a reflectance model and a choice per pixel;
// its top rows and a band in the middle have no solved pixel.
SolveResult full_result(cv::Size size) {
  SolveResult r;
  r.normals = cv::Mat(size, CV_32FC3, cv::Scalar::all(0));
  r.albedo = cv::Mat(size, CV_32FC1, cv::Scalar::all(0));
  r.residual = cv::Mat(size, CV_32FC1, cv::Scalar::all(0));
  r.solved = cv::Mat(size, CV_8UC1, cv::Scalar::all(0));
  r.confidence = cv::Mat(size, CV_32FC1, cv::Scalar::all(0));
  r.chroma = cv::Mat(size, CV_32FC3, cv::Scalar::all(0));
  r.coefficients = cv::Mat(size, CV_32FC(3), cv::Scalar::all(0));
  r.choice = cv::Mat(size, CV_8UC1, cv::Scalar::all(0));
  r.choices = {"biquadratic", "monotonic"};
  r.reflectance = {{"model", "bipolynomial"}, {"order", 1}, {"terms", {"1", "x", "y"}}};
  cv::RNG rng(7);
  for (int y = 0; y < size.height; ++y) {
    if (y < 6 || (y >= 13 && y < 17)) continue;
    for (int x = 2; x < size.width - 1; ++x) {
      const cv::Vec3f n = cv::normalize(cv::Vec3f(rng.uniform(-1.f, 1.f), rng.uniform(-1.f, 1.f), 1.f));
      r.normals.at<cv::Vec3f>(y, x) = n;
      r.albedo.at<float>(y, x) = rng.uniform(0.05f, 1.2f);
      r.residual.at<float>(y, x) = rng.uniform(0.f, 0.01f);
      r.solved.at<std::uint8_t>(y, x) = 255;
      r.confidence.at<float>(y, x) = rng.uniform(0.f, 1.f);
      r.chroma.at<cv::Vec3f>(y, x) = cv::Vec3f(rng.uniform(0.5f, 1.5f), 1.f, rng.uniform(0.5f, 1.5f));
      r.coefficients.at<cv::Vec3f>(y, x) = cv::Vec3f(rng.uniform(0.f, 1.f), rng.uniform(-1.f, 1.f), 0.25f);
      r.choice.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(1 + (x + y) % 2);
    }
  }
  r.summary.method = "auto";
  return r;
}

// Rows [y0, y0 + rows) of every map of `r`.
SolveResult rows_of(const SolveResult& r, int y0, int rows) {
  SolveResult band = r;
  for (cv::Mat* map : {&band.normals, &band.albedo, &band.residual, &band.solved, &band.confidence,
                       &band.chroma, &band.coefficients, &band.choice})
    *map = map->rowRange(y0, y0 + rows).clone();
  return band;
}

std::string bytes_of(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(SolveOutputWriter, BandsWriteTheFilesOfTheWholeResultByteForByte) {
  const cv::Size size(23, 29);
  const SolveResult whole = full_result(size);
  const fs::path dir = lightstage::testing::scratch_dir();
  const nlohmann::json written = io::write_solve_outputs(dir / "whole", whole, "/in", {{"extra", 1}});
  io::SolveOutputWriter writer(dir / "bands", size);
  // Empty bands before the first pixel and in the middle, bands of every height.
  writer.add_empty(4);
  writer.add(rows_of(whole, 4, 5));
  writer.add(rows_of(whole, 9, 4));
  writer.add_empty(4);
  for (int y = 17; y < size.height; y += 3) writer.add(rows_of(whole, y, std::min(3, size.height - y)));
  EXPECT_FALSE(fs::exists(dir / "bands" / "normal.png")) << "files appear only when complete";
  SolveResult meta = whole;
  meta.normals = meta.albedo = cv::Mat();
  nlohmann::json banded = writer.finish(meta, "/in", {{"extra", 1}});
  for (nlohmann::json* summary : {&banded, const_cast<nlohmann::json*>(&written)}) summary->erase("time");
  EXPECT_EQ(banded, written);
  EXPECT_EQ(written["method_map"]["choices"][0]["pixels"].get<int>() +
                written["method_map"]["choices"][1]["pixels"].get<int>(),
            cv::countNonZero(whole.solved));
  for (const auto& entry : fs::directory_iterator(dir / "whole")) {
    const std::string name = entry.path().filename().string();
    if (name == "summary.json") continue;
    EXPECT_EQ(bytes_of(dir / "bands" / name), bytes_of(entry.path())) << name;
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "bands"), fs::directory_iterator()),
            std::distance(fs::directory_iterator(dir / "whole"), fs::directory_iterator()));
  // The PNG whites are the 99.5th percentiles of the solved values.
  std::vector<float> solved;
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x)
      if (whole.solved.at<std::uint8_t>(y, x) != 0) solved.push_back(whole.albedo.at<float>(y, x));
  const auto at = static_cast<std::ptrdiff_t>(std::floor(0.995 * static_cast<double>(solved.size() - 1)));
  std::nth_element(solved.begin(), solved.begin() + at, solved.end());
  EXPECT_EQ(written["albedo_png_scale"].get<double>(),
            static_cast<double>(solved[static_cast<std::size_t>(at)]));
}

TEST(SolveOutputWriter, BandsThatDisagreeOrDoNotCoverTheImageAreRefusedAndLeaveNoFile) {
  const cv::Size size(23, 29);
  const SolveResult whole = full_result(size);
  const fs::path dir = lightstage::testing::scratch_dir();
  {
    io::SolveOutputWriter writer(dir / "a", size);
    writer.add(rows_of(whole, 0, 10));
    SolveResult grey = rows_of(whole, 10, 5);
    grey.chroma = cv::Mat();
    EXPECT_THAT(testing::error_of([&] { writer.add(grey); }),
                ::testing::HasSubstr("no colour where the rows above had one"));
    EXPECT_THAT(testing::error_of([&] { writer.add(rows_of(whole, 0, 20)); }),
                ::testing::HasSubstr("20 more rows given after 10 of 29"));
    EXPECT_THAT(testing::error_of([&] { writer.finish(whole, "/in", nlohmann::json::object()); }),
                ::testing::HasSubstr("10 of 29 rows of the result given"));
  }
  EXPECT_TRUE(!fs::exists(dir / "a") || fs::is_empty(dir / "a"));
}

TEST(SolveOutputWriter, AFinishThatFailsHalfWayTakesBackTheFilesItHadWritten) {
  const cv::Size size(23, 29);
  const SolveResult whole = full_result(size);
  const fs::path dir = lightstage::testing::scratch_dir();
  {
    // albedo.png is written after the float maps are in place: a full disk then.
    const io::ScopedWriteFault full(
        [](const fs::path& target) { return target.filename() == "albedo.png" ? ENOSPC : 0; });
    EXPECT_THAT(testing::device_error_of([&] { io::write_solve_outputs(dir / "out", whole, "/in"); }),
                ::testing::HasSubstr("albedo.png: cannot write: no space left on the device"));
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(SolveFolderRows, BandsReadBackWhatTheWholeReadGives) {
  const cv::Size size(19, 31);
  const fs::path dir = lightstage::testing::scratch_dir() / "result";
  SolveResult result = full_result(size);
  // Order 1 has four terms (the writer's own tests write three, which it does not check).
  std::vector<cv::Mat> planes;
  cv::split(result.coefficients, planes);
  planes.push_back(planes[1] * 0.5);
  cv::merge(planes, result.coefficients);
  result.reflectance["terms"] = {"1", "x", "y", "xy"};
  io::write_solve_outputs(dir, result, "/in");
  const io::SolveFolder whole = io::read_solve_folder(dir);
  ASSERT_FALSE(whole.chroma.empty());
  ASSERT_FALSE(whole.coefficients.empty());
  io::SolveFolderRows rows(dir);
  EXPECT_EQ(rows.size(), size);
  EXPECT_TRUE(rows.has_albedo() && rows.has_chroma() && rows.has_residual() && rows.has_confidence());
  EXPECT_EQ(rows.facts().summary, whole.summary);
  EXPECT_EQ(rows.facts().reflectance_order, 1);
  EXPECT_TRUE(rows.facts().normals.empty()) << "the facts hold no map";
  const auto same = [](const cv::Mat& a, const cv::Mat& b, const char* what) {
    ASSERT_EQ(a.type(), b.type()) << what;
    ASSERT_EQ(a.size(), b.size()) << what;
    EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0) << what;
  };
  for (int y = 0; y < size.height; y += 6) {
    const int n = std::min(6, size.height - y);
    const io::SolveFolder band = rows.read(y, n);
    const cv::Range r(y, y + n);
    same(band.normals, whole.normals.rowRange(r), "normals");
    same(band.solved, whole.solved.rowRange(r), "solved");
    same(band.albedo, whole.albedo.rowRange(r), "albedo");
    same(band.chroma, whole.chroma.rowRange(r), "chroma");
    same(band.residual, whole.residual.rowRange(r), "residual");
    same(band.confidence, whole.confidence.rowRange(r), "confidence");
    same(band.coefficients, whole.coefficients.rowRange(r), "coefficients");
    EXPECT_EQ(band.albedo_rgb_png_scale, whole.albedo_rgb_png_scale);
  }
  // The normals are the float ones of normal.exr, not normal.png's 16-bit code.
  const cv::Mat solved_rows = whole.normals.rowRange(6, 13);
  cv::Mat exact;
  result.normals.rowRange(6, 13).copyTo(exact);
  EXPECT_LT(cv::norm(solved_rows, exact, cv::NORM_INF), 1e-6);
}

TEST(SolveFolderRows, ALaterPassTakesTheSolvedMaskAndDecodesOnlyTheMapsItWants) {
  const cv::Size size(200, 160);
  const fs::path dir = lightstage::testing::scratch_dir() / "result";
  SolveResult result = full_result(size);
  result.coefficients = cv::Mat();  // no reflectance model
  result.reflectance = nlohmann::json();
  io::write_solve_outputs(dir, result, "/in");
  const io::SolveFolder whole = io::read_solve_folder(dir);
  io::SolveFolderRows rows(dir);
  {
    // normal.png damaged past its first few kB, after it was opened: decoding its rows fails.
    const auto bytes = static_cast<std::streamoff>(fs::file_size(dir / "normal.png"));
    ASSERT_GT(bytes, 65536);
    std::fstream png(dir / "normal.png", std::ios::in | std::ios::out | std::ios::binary);
    png.seekp(16384);
    const std::string zeros(static_cast<std::size_t>(bytes - 16384), '\0');
    png.write(zeros.data(), static_cast<std::streamsize>(zeros.size()));
  }
  const cv::Range r(100, 160);
  io::SolveFolderRows::Wanted wanted;
  wanted.albedo = wanted.colour = wanted.confidence = wanted.coefficients = false;
  const io::SolveFolder band = rows.read(r.start, r.size(), wanted, whole.solved.rowRange(r));
  EXPECT_EQ(cv::norm(band.normals, whole.normals.rowRange(r), cv::NORM_INF), 0) << "normal.exr's";
  EXPECT_EQ(cv::norm(band.solved, whole.solved.rowRange(r), cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(band.residual, whole.residual.rowRange(r), cv::NORM_INF), 0);
  EXPECT_TRUE(band.albedo.empty() && band.chroma.empty() && band.confidence.empty());
  wanted.normals = false;
  wanted.colour = true;  // the chroma is the colour albedo over the grey: both read
  const io::SolveFolder maps = rows.read(r.start, r.size(), wanted, whole.solved.rowRange(r));
  EXPECT_TRUE(maps.normals.empty());
  EXPECT_EQ(cv::norm(maps.albedo, whole.albedo.rowRange(r), cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(maps.chroma, whole.chroma.rowRange(r), cv::NORM_INF), 0);
  // Without the mask the rows of normal.png are decoded again, and the damage shows.
  io::SolveFolderRows again(dir);
  EXPECT_THROW(again.read(r.start, r.size(), wanted), InputError);
  EXPECT_THROW(rows.read(0, 10, wanted, whole.solved.rowRange(0, 9)), std::logic_error);
}

TEST(BandQuantile, EqualsNthElementOverEveryValueWhateverTheirSign) {
  cv::RNG rng(3);
  for (const int n : {1, 2, 17, 5000}) {
    std::vector<float> values(static_cast<std::size_t>(n));
    for (float& v : values)
      v = rng.uniform(-2.f, 3.f) * static_cast<float>(rng.uniform(0, 3) == 0 ? 1e-3 : 1);
    io::BandQuantile quantile;
    for (std::size_t i = 0; i < values.size(); i += 7)
      quantile.count(values.data() + i, std::min<std::size_t>(7, values.size() - i));
    ASSERT_TRUE(quantile.locate(0.995));
    for (std::size_t i = 0; i < values.size(); i += 5)
      quantile.gather(values.data() + i, std::min<std::size_t>(5, values.size() - i));
    const auto at = static_cast<std::ptrdiff_t>(std::floor(0.995 * (n - 1)));
    std::nth_element(values.begin(), values.begin() + at, values.end());
    EXPECT_EQ(quantile.value(), values[static_cast<std::size_t>(at)]) << n;
  }
  io::BandQuantile none;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  none.count(&nan, 1);
  EXPECT_FALSE(none.locate(0.5));
}

}  // namespace
}  // namespace lightstage
