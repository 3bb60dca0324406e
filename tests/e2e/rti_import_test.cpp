// `lightstage import rti` and `export` end to end: a simulated stack is
// written as a dome operator would have it (JPEG, 16-bit TIFF or a DSLR's DNG
// plus an .lp), imported, solved, and its normals compared with the simulator's.
#include "lightstage/host/calibration/lp_file.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/io/rti_files.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/sim/dng_writer.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"

#include <gtest/gtest.h>
#include <exiv2/exiv2.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <fstream>

namespace lightstage {
namespace {

using testing::run_lightstage;

constexpr double kDngBlack = 256, kDngWhite = 16383;
constexpr double kDngExposure = 1.0 / 60;

// A DSLR's shot of `linear` (values in [0, 1], grey or BGR): an RGGB mosaic at
// twice the size, each 2×2 block one pixel of the frame, 14-bit with a black level.
void write_dng_shot(const std::filesystem::path& path, const cv::Mat& linear, std::size_t index) {
  sim::DngShot shot;
  shot.mosaic.create(linear.rows * 2, linear.cols * 2, CV_16UC1);
  for (int y = 0; y < shot.mosaic.rows; ++y)
    for (int x = 0; x < shot.mosaic.cols; ++x) {
      const int site = (y % 2) * 2 + x % 2;
      const int bgr = site == 0 ? 2 : site == 3 ? 0 : 1;
      const float* px = linear.ptr<float>(y / 2) + (x / 2) * linear.channels();
      const double v = linear.channels() == 3 ? px[bgr] : px[0];
      shot.mosaic.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(
          std::lround(std::min(kDngBlack + v * (kDngWhite - kDngBlack), kDngWhite)));
    }
  shot.black_level = {kDngBlack, kDngBlack, kDngBlack, kDngBlack};
  shot.white_level = kDngWhite;
  shot.exposure_s = kDngExposure;
  shot.iso = 100;
  shot.f_number = 11;
  shot.taken = std::chrono::system_clock::time_point(std::chrono::seconds(1764780000 + index));
  sim::write_dng(path, shot);
}

// Writes the stack's frames as `ext` files named like RTIBuilder's (absolute
// Windows paths in the .lp), 8-bit ones sRGB-encoded. With `turned`, JPEGs as
// a camera held on its side stores them: turned a quarter anticlockwise, with
// EXIF Orientation 6 (turn clockwise to view).
void write_operator_folder(const ImageStack& stack, const std::filesystem::path& dir, const std::string& ext,
                           bool turned = false) {
  std::filesystem::create_directories(dir);
  std::vector<calibration::LpEntry> lp;
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    cv::Mat linear;
    stack.frames[i].image.convertTo(linear, CV_32F,
                                    stack.frames[i].image.depth() == CV_16U ? 1 / 65535.0 : 1 / 255.0);
    const std::string name = "IMG_" + std::to_string(1000 + i) + ext;
    lp.push_back({"C:\\capture\\jpeg-exports\\" + name, stack.frames[i].light_direction});
    if (ext == ".dng") {
      write_dng_shot(dir / name, linear, i);
      continue;
    }
    cv::Mat out;
    if (ext == ".jpg") {
      cv::Mat encoded = linear.clone();
      encoded.forEach<float>([](float& v, const int*) {
        v = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1 / 2.4f) - 0.055f;
      });
      encoded.convertTo(out, CV_8U, 255.0);
    } else {
      linear.convertTo(out, CV_16U, 65535.0);
    }
    if (turned) cv::rotate(out, out, cv::ROTATE_90_COUNTERCLOCKWISE);
    ASSERT_TRUE(cv::imwrite((dir / name).string(), out, {cv::IMWRITE_JPEG_QUALITY, 98}));
    if (turned) {
      auto image = Exiv2::ImageFactory::open((dir / name).string());
      image->readMetadata();
      image->exifData()["Exif.Image.Orientation"] = std::uint16_t{6};
      image->writeMetadata();
    }
  }
  std::ofstream(dir / "assembly-files.lp") << calibration::format_lp(lp);
}

class ImportRti : public ::testing::TestWithParam<std::string> {};

TEST_P(ImportRti, ImportsAndSolves) {
  const auto dir = testing::scratch_dir();
  auto run = run_lightstage({"simulate", "--scene", "bumps", "--lights", "distant", "--noise", "none",
                             "--width", "48", "--height", "48", "--out", (dir / "stack").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const ImageStack stack = io::load_stack(dir / "stack");
  write_operator_folder(stack, dir / "photos", GetParam());
  run = run_lightstage({"import", "rti", (dir / "photos").string(), "--out", (dir / "imported").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const ImageStack imported = io::load_stack(dir / "imported");
  ASSERT_EQ(imported.frames.size(), stack.frames.size());
  EXPECT_NEAR(imported.frames[3].light_direction.dot(stack.frames[3].light_direction), 1.0, 1e-5);
  run = run_lightstage({"solve", "--input", (dir / "imported").string(), "--out", (dir / "result").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto stats = evaluate_normal_map(dir / "result/normal.png", dir / "stack");
  // Linearised right, a noiseless Lambertian stack solves to within a few
  // degrees (JPEG loses some); an unlinearised sRGB one is off by far more.
  EXPECT_LT(stats.mean, GetParam() == ".jpg" ? 3.0 : 1.0) << GetParam();

  if (GetParam() == ".dng") {
    // The camera's EXIF and the decode reach the manifest; the exposure is the frame's.
    std::ifstream in(dir / "imported/manifest.json");
    const auto manifest = nlohmann::json::parse(in);
    EXPECT_EQ(manifest["import"]["raw_images"], stack.frames.size());
    EXPECT_EQ(manifest["import"]["raw_demosaic"], "half");
    const auto& frame = manifest["frames"][2];
    EXPECT_EQ(frame["source_image"], "IMG_1002.dng");
    EXPECT_NEAR(frame["exposure_us"].get<double>(), kDngExposure * 1e6, 1e-3);
    EXPECT_NEAR(frame["exif"]["exposure_s"].get<double>(), kDngExposure, 1e-9);
    EXPECT_EQ(frame["exif"]["iso"], 100);
    EXPECT_EQ(frame["exif"]["taken"], "2025-12-03T16:40:02.000");
    EXPECT_EQ(frame["raw"]["mosaic"], "RGGB");
    EXPECT_EQ(frame["raw"]["white_level"], kDngWhite);
  }

  // An existing, non-empty --out is refused and left alone.
  run = run_lightstage({"import", "rti", (dir / "photos").string(), "--out", (dir / "imported").string()});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("--out"), std::string::npos) << run.err;

  // Exports of the imported stack open with our readers.
  run = run_lightstage({"export", "--input", (dir / "imported").string(), "--format", "ptm", "--out",
                        (dir / "object.ptm").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(io::read_ptm(dir / "object.ptm").width, 48);
  run = run_lightstage({"export", "--input", (dir / "imported").string(), "--format", "hsh", "--order", "2",
                        "--out", (dir / "object.rti").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(io::read_hsh(dir / "object.rti").basis, RtiBasis::hsh2);
}

INSTANTIATE_TEST_SUITE_P(Formats, ImportRti, ::testing::Values(".jpg", ".tif", ".dng"),
                         [](const auto& p) { return p.param.substr(1); });

// Photographs taken with the camera on its side come in as a viewer shows them.
TEST(ImportRtiOrientation, JpegsAreTurnedUprightByTheirExif) {
  const auto dir = testing::scratch_dir();
  auto run = run_lightstage({"simulate", "--scene", "bumps", "--lights", "distant", "--noise", "none",
                             "--width", "56", "--height", "40", "--out", (dir / "stack").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const ImageStack stack = io::load_stack(dir / "stack");
  write_operator_folder(stack, dir / "photos", ".jpg", /*turned=*/true);
  ASSERT_EQ(
      cv::imread((dir / "photos/IMG_1000.jpg").string(), cv::IMREAD_UNCHANGED | cv::IMREAD_IGNORE_ORIENTATION)
          .size(),
      cv::Size(40, 56));
  run = run_lightstage({"import", "rti", (dir / "photos").string(), "--out", (dir / "imported").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  ASSERT_EQ(io::load_stack(dir / "imported").frames[0].image.size(), cv::Size(56, 40));
  run = run_lightstage({"solve", "--input", (dir / "imported").string(), "--out", (dir / "result").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_LT(evaluate_normal_map(dir / "result/normal.png", dir / "stack").mean, 3.0);
}

TEST(ImportRtiErrors, MissingImageNamesTheLpLine) {
  const auto dir = testing::scratch_dir();
  std::filesystem::create_directories(dir / "photos");
  std::ofstream(dir / "photos/a.lp") << "3\nx.jpg 0 0 1\ny.jpg 0 1 1\nz.jpg 1 0 1\n";
  const auto run =
      run_lightstage({"import", "rti", (dir / "photos").string(), "--out", (dir / "out").string()});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("a.lp:2: image: x.jpg is not in"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace lightstage
