// The capture's stack writer: frames, darks and manifest written as they come,
// and read back for --resume (through io/stack_manifest).
#include "lightstage/host/capture/stack_writer.hpp"

#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/io/write_fault.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <fstream>

namespace lightstage {
namespace {

namespace fs = std::filesystem;
using testing::error_of;

Rig three_led_rig() {
  Rig rig;
  rig.name = "writer-test";
  for (const int id : {4, 5, 6}) {
    Led led;
    led.id = id;
    led.position_mm = Vec3(100.0 * id, 50, 300);
    led.relative_intensity = 0.5 + 0.1 * id;
    led.limits.max_on_us = 2'000'000;
    rig.leds.push_back(led);
  }
  rig.camera.exposure_us = 1000;
  rig.camera.gain = 1;
  return rig;
}

Take take(std::size_t exposure, double exposure_us, double value, double gain = 2) {
  Take t;
  t.exposure = exposure;
  t.taken.frame.bit_depth = 12;
  t.taken.frame.exposure_us = exposure_us;
  t.taken.frame.analogue_gain = gain;
  t.taken.frame.sequence = static_cast<std::uint64_t>(value);
  t.taken.frame.image = cv::Mat(4, 5, CV_16UC1, cv::Scalar(value));
  t.taken.step.set_trigger_ns(123);
  return t;
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

void write_json(const fs::path& path, const nlohmann::json& json) { std::ofstream(path) << json.dump(2); }

const CaptureSetup kSetup{2, false, true, {"fake:cam", "fake", "test"}, "fw 1", "writer-test", std::nullopt};

// What a --resume run asks for: automatic exposure, `stops`, `dark_frames` per dark.
CaptureOptions asked(std::vector<double> stops = {}, int dark_frames = 2) {
  CaptureOptions options;
  options.bracket_stops = std::move(stops);
  options.dark_frames = dark_frames;
  return options;
}

// LEDs 4 and 6 at 2000 us, 5 at 500 us; darks of 2 frames.
CapturePlan single_plan() { return make_plan({4, 5, 6}, {{4, 2000}, {5, 500}, {6, 2000}}, {}, {}, 2); }

TEST(CaptureStackWriter, TheFolderIsALoadableStackAfterEveryFrame) {
  const Rig rig = three_led_rig();
  const fs::path dir = testing::scratch_dir();
  CaptureStackWriter writer(rig, dir, nullptr);
  const CapturePlan plan = single_plan();
  writer.set_plan(plan, kSetup);
  writer.write_index(false);
  // The plan is kept before any frame is taken.
  EXPECT_EQ(read_json(dir / "manifest.json").at("capture").at("plan_led_ids"), (std::vector<int>{4, 5, 6}));

  EXPECT_FALSE(writer.has_dark(0));
  writer.add_dark(0, {cv::Mat(4, 5, CV_16UC1, cv::Scalar(10)), cv::Mat(4, 5, CV_16UC1, cv::Scalar(20))});
  EXPECT_TRUE(writer.has_dark(0));
  EXPECT_TRUE(fs::exists(dir / "dark_500us.png"));
  writer.write_index(false);

  writer.add_frame(1, take(0, 500, 300));
  writer.write_index(false);
  io::LoadOptions load;
  load.min_images = 1;
  ImageStack stack = io::load_stack(dir, load);
  ASSERT_EQ(stack.frames.size(), 1u);
  const Frame& frame = stack.frames[0];
  EXPECT_EQ(frame.filename, "002.png");
  EXPECT_EQ(frame.led_id, 5);
  EXPECT_DOUBLE_EQ(frame.exposure_us, 500);
  EXPECT_DOUBLE_EQ(frame.gain, 2);
  EXPECT_EQ(frame.dark_file, "dark_500us.png");
  EXPECT_DOUBLE_EQ(frame.black_level, 15);
  EXPECT_EQ(frame.dark.at<std::uint16_t>(0, 0), 15);
  // Relative intensity times exposure and gain relative to the rig camera's.
  EXPECT_NEAR(frame.light_intensity.x(), 1.0 * 0.5 * 2, 1e-12);
  EXPECT_EQ(writer.done(), (std::vector<bool>{false, true, false}));

  writer.add_frame(0, take(1, 2000, 900));  // no dark at 2000 us: black level 0
  writer.write_index(true);
  stack = io::load_stack(dir, load);
  ASSERT_EQ(stack.frames.size(), 2u);
  EXPECT_EQ(stack.frames[0].filename, "001.png");
  EXPECT_TRUE(stack.frames[0].dark_file.empty());
  EXPECT_DOUBLE_EQ(stack.frames[0].black_level, 0);
  const nlohmann::json manifest = read_json(dir / "manifest.json");
  const nlohmann::json& c = manifest.at("capture");
  EXPECT_TRUE(c.at("complete").get<bool>());
  EXPECT_EQ(c.at("done"), (std::vector<int>{0, 1}));
  EXPECT_DOUBLE_EQ(c.at("exposure_us").at("5").get<double>(), 500);
  EXPECT_EQ(c.at("darks").at("500").at("file"), "dark_500us.png");
  EXPECT_EQ(c.at("trigger"), "hardware");
  EXPECT_EQ(c.at("camera").at("uri"), "fake:cam");
  EXPECT_EQ(manifest.at("frames").at(0).at("trigger_ns"), 123);
}

// One frame and its dark written with the index, as an interrupted capture leaves a stack.
void write_one_frame_stack(const Rig& rig, const fs::path& dir) {
  CaptureStackWriter writer(rig, dir, nullptr);
  writer.set_plan(single_plan(), kSetup);
  writer.add_dark(0, {cv::Mat(4, 5, CV_16UC1, cv::Scalar(8))});
  writer.add_frame(1, take(0, 500, 300));
  writer.write_index(false);
}

// The disk fills up while the index is rewritten (the manifest is the largest
// file, so it fails first): the folder keeps its previous, agreeing index.
TEST(CaptureStackWriter, AFullDiskLeavesTheLastIndexWholeAndSaysSo) {
  const Rig rig = three_led_rig();
  const fs::path dir = testing::scratch_dir();
  write_one_frame_stack(rig, dir);
  CaptureStackWriter writer(rig, dir, nullptr);
  writer.resume({4, 5, 6}, asked());
  writer.set_plan(single_plan(), kSetup);
  writer.add_frame(0, take(1, 2000, 900));
  std::string message;
  {
    const io::ScopedWriteFault full(
        [](const fs::path& target) { return target.filename() == "manifest.json" ? ENOSPC : 0; });
    try {
      writer.write_index(false);
      ADD_FAILURE() << "a full disk went unnoticed";
    } catch (const InputError& e) {
      ADD_FAILURE() << "a full disk is not bad input: " << e.what();
    } catch (const Error& e) {
      message = e.what();
    }
  }
  EXPECT_NE(message.find("manifest.json"), std::string::npos) << message;
  EXPECT_NE(message.find("no space left"), std::string::npos) << message;
  EXPECT_NE(message.find("ENOSPC"), std::string::npos) << message;
  io::LoadOptions load;
  load.min_images = 1;
  const ImageStack stack = io::load_stack(dir, load);  // loads: names, lights and manifest agree
  ASSERT_EQ(stack.frames.size(), 1u);
  EXPECT_EQ(stack.frames[0].filename, "002.png");
  for (const auto& entry : fs::directory_iterator(dir))
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();

  // A frame image that does not fit fails the same way, before the index names it.
  const io::ScopedWriteFault full(
      [](const fs::path& target) { return target.extension() == ".png" ? ENOSPC : 0; });
  try {
    writer.add_frame(2, take(1, 2000, 700));
    ADD_FAILURE() << "a full disk went unnoticed";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("003.png: cannot write: no space left"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(writer.done(), (std::vector<bool>{true, true, false}));  // frame 3 is not counted as taken
}

TEST(CaptureStackWriter, ResumeKeepsTheFramesDarksAndExposuresOfTheManifest) {
  const Rig rig = three_led_rig();
  const fs::path dir = testing::scratch_dir();
  write_one_frame_stack(rig, dir);
  nlohmann::json before = read_json(dir / "manifest.json");

  CaptureStackWriter writer(rig, dir, nullptr);
  const PreviousPlan previous = writer.resume({4, 5, 6}, asked());
  EXPECT_EQ(previous.exposure_us, (std::map<int, double>{{4, 2000}, {5, 500}, {6, 2000}}));
  EXPECT_TRUE(previous.bracket_exposure_us.empty());
  EXPECT_EQ(writer.frame_count(), 1u);
  const CapturePlan plan = make_plan({4, 5, 6}, previous.exposure_us, {}, {}, 2);
  writer.set_plan(plan, kSetup);
  EXPECT_EQ(writer.done(), (std::vector<bool>{false, true, false}));
  EXPECT_TRUE(writer.has_dark(0));
  EXPECT_FALSE(writer.has_dark(1));
  writer.write_index(false);
  nlohmann::json after = read_json(dir / "manifest.json");
  for (nlohmann::json* m : {&before, &after}) {
    m->erase("created");
    m->at("capture").erase("updated");
  }
  EXPECT_EQ(after, before);

  // A frame taken now names the dark taken before the interruption.
  writer.add_frame(2, take(1, 2000, 700));
  writer.add_frame(0, take(1, 2000, 700));
  writer.write_index(true);
  EXPECT_EQ(read_json(dir / "manifest.json").at("capture").at("done"), (std::vector<int>{0, 1, 2}));
}

TEST(CaptureStackWriter, ResumeRefusesAnotherPlan) {
  const Rig rig = three_led_rig();
  const fs::path dir = testing::scratch_dir();
  {
    CaptureStackWriter writer(rig, dir, nullptr);
    writer.set_plan(single_plan(), kSetup);
    writer.write_index(false);
  }
  CaptureStackWriter writer(rig, dir, nullptr);
  EXPECT_NE(error_of([&] {
              writer.resume({4, 5}, asked());
            }).find("planned for other LEDs (3 of them) than this run (2)"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              writer.resume({4, 5, 6}, asked({0, -3}));
            }).find("planned with bracket stops [], this run asks for [0,-3]"),
            std::string::npos);
  // No manifest: nothing to resume.
  CaptureStackWriter fresh(rig, dir / "elsewhere", nullptr);
  EXPECT_TRUE(fresh.resume({4, 5, 6}, asked()).exposure_us.empty());
}

TEST(CaptureStackWriter, ResumeRefusesAnotherExposureOrDarkCount) {
  const Rig rig = three_led_rig();
  const fs::path dir = testing::scratch_dir();
  const auto plan_in = [&](const fs::path& folder, const CapturePlan& plan, const CaptureSetup& setup) {
    fs::create_directories(folder);
    CaptureStackWriter writer(rig, folder, nullptr);
    writer.set_plan(plan, setup);
    writer.write_index(false);
  };
  plan_in(dir / "auto", single_plan(), kSetup);  // automatic exposure, 2 dark frames
  CaptureSetup fixed = kSetup;
  fixed.fixed_exposure_us = 1000;
  plan_in(dir / "fixed", make_plan({4, 5, 6}, {{4, 1000}, {5, 1000}, {6, 1000}}, {}, {}, 2), fixed);
  const auto refusal = [&](const fs::path& folder, const CaptureOptions& options) {
    CaptureStackWriter writer(rig, folder, nullptr);
    return error_of([&] { writer.resume({4, 5, 6}, options); });
  };
  CaptureOptions options = asked();
  options.exposure_us = 1000;
  EXPECT_NE(refusal(dir / "auto", options)
                .find("planned with automatic exposure, this run asks for --exposure-us 1000"),
            std::string::npos);
  options.exposure_us = 2000;
  EXPECT_NE(refusal(dir / "fixed", options)
                .find("planned with --exposure-us 1000, this run asks for --exposure-us 2000"),
            std::string::npos);
  EXPECT_NE(refusal(dir / "fixed", asked())
                .find("planned with --exposure-us 1000, this run asks for automatic exposure"),
            std::string::npos);
  EXPECT_NE(refusal(dir / "auto", asked({}, 4)).find("planned with --dark-frames 2, this run asks for 4"),
            std::string::npos);
  options.exposure_us = 1000;
  EXPECT_EQ(refusal(dir / "fixed", options), "(no InputError)");
  EXPECT_EQ(refusal(dir / "auto", asked()), "(no InputError)");

  // A manifest from before the choice was recorded: the planned exposures themselves must fit.
  nlohmann::json manifest = read_json(dir / "auto" / "manifest.json");
  manifest["capture"].erase("fixed_exposure_us");
  manifest["capture"].erase("dark_frames");
  write_json(dir / "auto" / "manifest.json", manifest);
  options.exposure_us = 2000;
  EXPECT_NE(refusal(dir / "auto", options)
                .find("LED 5 was planned at 500 us, this run asks for --exposure-us 2000"),
            std::string::npos);
}

TEST(CaptureStackWriter, TheIndexIsOnDiskBeforeTheFirstFrame) {
  const Rig rig = three_led_rig();
  const fs::path dir = testing::scratch_dir();
  CaptureStackWriter writer(rig, dir, nullptr);
  writer.set_plan(single_plan(), kSetup);
  writer.write_index(false);
  // A stack with no frames yet: an empty index, not a folder without one.
  for (const char* name : {"filenames.txt", "light_directions.txt", "light_intensities.txt"}) {
    ASSERT_TRUE(fs::exists(dir / name)) << name;
    EXPECT_EQ(fs::file_size(dir / name), 0u) << name;
  }
  EXPECT_EQ(read_json(dir / "manifest.json").at("capture").at("done"), nlohmann::json::array());
}

TEST(CaptureStackWriter, ResumeReadsNoFileOutsideTheStackFolder) {
  const Rig rig = three_led_rig();
  const fs::path dir = testing::scratch_dir();
  write_one_frame_stack(rig, dir);
  const nlohmann::json good = read_json(dir / "manifest.json");
  const auto refused = [&](const std::function<void(nlohmann::json&)>& edit) {
    nlohmann::json bad = good;
    edit(bad);
    write_json(dir / "manifest.json", bad);
    CaptureStackWriter writer(rig, dir, nullptr);
    return error_of([&] { writer.resume({4, 5, 6}, asked()); });
  };
  EXPECT_NE(refused([](nlohmann::json& m) {
              m["frames"][0]["dark"] = "../dark_500us.png";
            }).find("frames[0].dark: '../dark_500us.png' must name a file inside the stack folder"),
            std::string::npos);
  EXPECT_NE(refused([](nlohmann::json& m) {
              m["capture"]["darks"]["500"]["file"] = "/etc/passwd";
            }).find("capture.darks.500.file: '/etc/passwd' must name a file inside the stack folder"),
            std::string::npos);
  EXPECT_NE(refused([](nlohmann::json& m) {
              m["frames"][0]["file"] = "../002.png";
            }).find("frames[0].file: '../002.png' must name a file inside the stack folder"),
            std::string::npos);
  EXPECT_NE(refused([](nlohmann::json& m) {
              m["capture"]["done"][0] = 7;
            }).find("capture.done[0] = 7 is past the plan"),
            std::string::npos);
  EXPECT_NE(refused([](nlohmann::json& m) {
              m["frames"][0]["led_id"] = 6;
            }).find("frames[0] is LED 6, but the plan has LED 5 there"),
            std::string::npos);
  EXPECT_NE(
      refused([](nlohmann::json& m) { m["capture"]["version"] = 2; }).find("capture.version 2 is not 1"),
      std::string::npos);
  EXPECT_NE(refused([](nlohmann::json& m) { m.erase("capture"); }).find("not a capture"), std::string::npos);
  EXPECT_NE(refused([](nlohmann::json& m) {
              m["capture"]["exposure_us"]["x"] = 1;
            }).find("capture.exposure_us.x: the key 'x' is not an LED id"),
            std::string::npos);
}

TEST(CaptureStackWriter, ABracketIsMergedIntoOneFloatFramePerExposureSecond) {
  const Rig rig = three_led_rig();
  const fs::path dir = testing::scratch_dir();
  CaptureStackWriter writer(rig, dir, nullptr);
  const CapturePlan plan = make_plan({4}, {{4, 1000}}, {{4, {250, 1000}}}, {-2, 0}, 0);
  writer.set_plan(plan, kSetup);
  // 400 DN at 250 us and 1600 DN at 1000 us: 1.6e6 DN per exposure-second, in the 16-bit type's full scale.
  writer.add_hdr_frame(0, {take(0, 250, 400, 1), take(1, 1000, 1600, 1)});
  writer.write_index(true);
  io::LoadOptions load;
  load.min_images = 1;
  const ImageStack stack = io::load_stack(dir, load);
  ASSERT_EQ(stack.frames.size(), 1u);
  EXPECT_EQ(stack.frames[0].filename, "001.pfm");
  EXPECT_DOUBLE_EQ(stack.frames[0].exposure_us, 1e6);
  EXPECT_NEAR(stack.frames[0].image.at<float>(0, 0) * 65535.0, 1.6e6, 1.0);
  const nlohmann::json manifest = read_json(dir / "manifest.json");
  EXPECT_EQ(manifest.at("frames").at(0).at("bracket_exposures_us"), (std::vector<double>{250, 1000}));
  EXPECT_EQ(manifest.at("capture").at("bracket_exposure_us").at("4"), (std::vector<double>{250, 1000}));
  EXPECT_EQ(manifest.at("capture").at("bracket_stops"), (std::vector<double>{-2, 0}));

  // Resumed, the merged frame is kept.
  CaptureStackWriter again(rig, dir, nullptr);
  const PreviousPlan previous = again.resume({4}, asked({-2, 0}, 0));
  EXPECT_EQ(previous.bracket_exposure_us.at(4), (std::vector<double>{250, 1000}));
  EXPECT_EQ(again.frame_count(), 1u);
}

}  // namespace
}  // namespace lightstage
