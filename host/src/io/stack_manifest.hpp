#pragma once
// manifest.json of a stack folder: building it when writing, applying it to
// loaded frames when reading, and reading a capture's plan and progress back
// for --resume. The keys are documented in docs/stack-format.md and
// docs/capture.md; every manifest is parsed here and nowhere else.

#include "lightstage/common/image_stack.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::io {

inline constexpr const char* kStackFormat = "lightstage-stack";
inline constexpr int kStackFormatVersion = 1;

// File names of the optional parts actually written (empty = not written).
struct StackFiles {
  std::vector<std::string> frames;
  cv::Size size;  // of every frame
  std::string mask;
  std::string normals;
  std::string depth;
};

// The manifest for `stack` written as `files`, merged with `extra` (see write_stack).
// Throws InputError when `extra` is not an object or collides with a reserved key.
nlohmann::json build_manifest(const ImageStack& stack, const StackFiles& files, const nlohmann::json& extra);

// Reads `path` and fills each frame's led_id, led_position_mm, exposure_us,
// gain, black_level, saturation_level and dark_file (the images themselves are
// loaded by load_stack). Throws InputError naming the file
// and the field for bad JSON, a wrong format or version, a frame count or
// file name that disagrees with filenames.txt, or a value of the wrong type.
void apply_manifest(const std::filesystem::path& path, ImageStack& stack);
// The same for a manifest already read (read_manifest_json).
void apply_manifest(const std::filesystem::path& path, const nlohmann::json& manifest, ImageStack& stack);

// Reads `path`: parsed, an object, of our format and a version this build
// reads. Throws InputError naming the file.
nlohmann::json read_manifest_json(const std::filesystem::path& path);

// The image size the manifest read from `path` declares ("width" and
// "height"), when it declares both; load_stack checks the images' headers
// against it before decoding them. Throws InputError as apply_manifest does.
std::optional<cv::Size> manifest_image_size(const std::filesystem::path& path,
                                            const nlohmann::json& manifest);

// The "capture" section a capture keeps in its manifest (docs/capture.md).
inline constexpr int kCaptureFormatVersion = 1;

struct CaptureDark {
  double exposure_us = 0;
  std::string file;  // in the stack folder
  double mean = 0;
};

// A frame as the manifest lists it (no image, no dark image), and the entry's
// keys that are not Frame fields (frame stamps, bracket details).
struct ManifestFrame {
  Frame frame;
  nlohmann::json extra = nlohmann::json::object();
};

// What a capture's manifest says it planned and took.
struct CaptureManifest {
  std::vector<int> plan_led_ids;
  std::vector<std::size_t> done;      // the plan index of each listed frame, in the order of `frames`
  std::map<int, double> exposure_us;  // per LED id
  std::vector<double> bracket_stops;
  std::map<int, std::vector<double>> bracket_exposure_us;  // per LED id
  std::vector<CaptureDark> darks;
  std::vector<ManifestFrame> frames;
  // What the run was asked for; unset in manifests written before they were recorded.
  std::optional<int> dark_frames;           // capture.dark_frames: frames averaged per dark
  std::optional<bool> fixed_exposure;       // capture.fixed_exposure_us present: null = automatic
  std::optional<double> fixed_exposure_us;  // its value when fixed
};

// Reads a capture's manifest.json: the format and version checks of
// apply_manifest, the capture section (version kCaptureFormatVersion) and the
// listed frames. Every file it names (frames, darks) must be inside the stack
// folder. Throws InputError naming the file and field.
CaptureManifest read_capture_manifest(const std::filesystem::path& path);

}  // namespace lightstage::io
