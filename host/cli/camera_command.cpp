// `lightstage camera`: how a camera maps light to numbers — calibrate its
// response from an exposure bracket, and check how linear it is.
#include "commands.hpp"

#include "lightstage/common/rig.hpp"
#include "lightstage/host/capture/capture_session.hpp"
#include "lightstage/host/capture/file_camera.hpp"
#include "lightstage/host/capture/response_curve.hpp"
#include "lightstage/host/controller/controller_client.hpp"
#include "lightstage/hw/cameras.hpp"
#include "lightstage/sim/camera/sim_camera.hpp"

#include <fmt/format.h>

#include <memory>

namespace lightstage::cli {
namespace {

struct BracketArgs {
  std::string rig = default_rig_path().string();
  std::string controller;
  std::string camera;
  int led = -1;
  std::vector<double> exposures;
  std::string response;
  std::string out;
  bool json = false;
  CaptureOptions options;
};

void add_bracket_options(CLI::App* sub, BracketArgs& args, const char* default_bracket) {
  sub->add_option("--rig", args.rig, "rig description (YAML)")->capture_default_str();
  sub->add_option("--controller", args.controller, "controller URI")->required();
  sub->add_option("--camera", args.camera, "camera URI")->required();
  sub->add_option("--led", args.led, "the LED lighting the still scene (default: the rig's first)");
  sub->add_option("--exposures-us", args.exposures, fmt::format("the bracket (default: {})", default_bracket))
      ->delimiter(',');
  sub->add_option("--loop", args.options.loop, "open, closed or auto")->capture_default_str();
}

// The bracket: frames of one LED at each exposure (given, or `default_bracket` of the rig camera's).
std::vector<cv::Mat> take_bracket(BracketArgs& args, std::vector<double>& exposures, int& bits,
                                  std::vector<double> (*default_bracket)(double reference_us)) {
  const Rig rig = load_rig(args.rig);
  if (args.led < 0) args.led = rig.leds.front().id;
  exposures = args.exposures;
  if (exposures.empty()) exposures = default_bracket(rig.camera.exposure_us);
  hw::register_hw_cameras();
  sim::register_sim_camera();
  register_file_cameras();
  auto camera = camera::open_camera_uri(args.camera);
  auto controller = connect_controller(args.controller);
  const auto images = capture_bracket(rig, *controller, *camera, args.led, exposures, args.options);
  bits = images.front().depth() == CV_8U ? 8 : 16;
  return images;
}

}  // namespace

void add_camera(CLI::App& app) {
  CLI::App* camera = app.add_subcommand(
      "camera",
      "Calibrate a camera's response and check its linearity (from an exposure bracket).\n"
      "The bracket is of a still scene lit by one LED. Solvers need radiance-linear images: raw sensors\n"
      "are; cameras with a tone curve need their inverse response, which `capture --response` then\n"
      "applies to every frame.\n"
      "Subcommands: response (writes the inverse response as JSON), linearity (prints how linear the\n"
      "camera is, with --response after linearisation). Both drive the dome through --controller and\n"
      "take the bracket through --camera (docs/capture.md).\n"
      "Example: lightstage camera response --controller unix:/tmp/domed.sock --camera v4l2:/dev/video0 "
      "--out response.json");
  camera->require_subcommand(1);

  auto response = std::make_shared<BracketArgs>();
  CLI::App* calibrate = camera->add_subcommand(
      "response",
      "Fit the camera's inverse response (Debevec-Malik, OpenCV photo) to an exposure bracket and write it\n"
      "as JSON (--out), for `capture --response`; prints the linearity after linearisation.\n"
      "Example: lightstage camera response --controller unix:/tmp/domed.sock --camera sim:/tmp/cam.sock "
      "--out response.json");
  add_bracket_options(calibrate, *response, "8 exposures doubling from 1/16 of the rig camera's");
  calibrate->add_option("--out", response->out, "response file to write")->required();
  calibrate->callback([response] {
    std::vector<double> exposures;
    int bits = 16;
    const auto images = take_bracket(*response, exposures, bits, response_bracket_us);
    const InverseResponse curve = calibrate_response(images, exposures, bits);
    curve.save(response->out);
    // Linearity over the middle three exposures, where most pixels are well exposed in all of them.
    const std::size_t mid = images.size() / 2;
    const std::vector<cv::Mat> middle(images.begin() + static_cast<std::ptrdiff_t>(mid - 1),
                                      images.begin() + static_cast<std::ptrdiff_t>(mid + 2));
    const std::vector<double> middle_exposures(exposures.begin() + static_cast<std::ptrdiff_t>(mid - 1),
                                               exposures.begin() + static_cast<std::ptrdiff_t>(mid + 2));
    fmt::print("{}: inverse response of {} knots from {} exposures\n", response->out, curve.knots().size(),
               exposures.size());
    try {
      const LinearityReport after = check_linearity(middle, middle_exposures, curve);
      fmt::print("after it, exposures {}-{} us are linear within {:.2f}% ({} pixels)\n",
                 middle_exposures.front(), middle_exposures.back(), 100 * after.max_deviation,
                 after.pixels_used);
    } catch (const InputError& e) {
      fmt::print("(no linearity figure: {})\n", e.what());
    }
  });

  auto linearity = std::make_shared<BracketArgs>();
  CLI::App* check = camera->add_subcommand(
      "linearity",
      "How linear the camera is (with --response: after linearisation): prints radiance/exposure per\n"
      "exposure of the bracket, relative to the median, for pixels well inside the range in every frame.\n"
      "Example: lightstage camera linearity --controller unix:/tmp/domed.sock --camera sim:/tmp/cam.sock");
  add_bracket_options(check, *linearity, "5 exposures half a stop apart from 1/2 to 2x the rig camera's");
  check->add_option("--response", linearity->response, "inverse response to apply first");
  check->add_flag("--json", linearity->json, "print the report as JSON");
  check->callback([linearity] {
    std::vector<double> exposures;
    int bits = 16;
    const auto images = take_bracket(*linearity, exposures, bits, linearity_bracket_us);
    const InverseResponse curve = linearity->response.empty() ? InverseResponse::identity(bits)
                                                              : InverseResponse::load(linearity->response);
    const LinearityReport report = check_linearity(images, exposures, curve);
    if (linearity->json) {
      fmt::print("{}\n", report.to_json().dump(2));
      return;
    }
    for (std::size_t i = 0; i < exposures.size(); ++i) {
      fmt::print("exposure {:>10.1f} us  radiance/exposure {:7.4f} of the median\n", exposures[i],
                 report.relative_ratio[i]);
    }
    fmt::print("linear within {:.2f}% over {} pixels\n", 100 * report.max_deviation, report.pixels_used);
  });
}

}  // namespace lightstage::cli
