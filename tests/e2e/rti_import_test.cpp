// `lightstage import rti` and `export` end to end: a simulated stack is
// written as a dome operator would have it (JPEG or 16-bit TIFF plus an .lp),
// imported, solved, and its normals compared with the simulator's.
#include "lightstage/host/calibration/lp_file.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/io/rti_files.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <fstream>

namespace lightstage {
namespace {

using testing::run_lightstage;

// Writes the stack's frames as `ext` files named like RTIBuilder's (absolute
// Windows paths in the .lp), 8-bit ones sRGB-encoded.
void write_operator_folder(const ImageStack& stack, const std::filesystem::path& dir,
                           const std::string& ext) {
  std::filesystem::create_directories(dir);
  std::vector<calibration::LpEntry> lp;
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    cv::Mat linear;
    stack.frames[i].image.convertTo(linear, CV_32F,
                                    stack.frames[i].image.depth() == CV_16U ? 1 / 65535.0 : 1 / 255.0);
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
    const std::string name = "IMG_" + std::to_string(1000 + i) + ext;
    ASSERT_TRUE(cv::imwrite((dir / name).string(), out, {cv::IMWRITE_JPEG_QUALITY, 98}));
    lp.push_back({"C:\\capture\\jpeg-exports\\" + name, stack.frames[i].light_direction});
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

INSTANTIATE_TEST_SUITE_P(Formats, ImportRti, ::testing::Values(".jpg", ".tif"),
                         [](const auto& p) { return p.param.substr(1); });

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
