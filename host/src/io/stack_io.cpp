#include "lightstage/host/io/stack_io.hpp"

#include "io/image_header.hpp"
#include "io/stack_checks.hpp"
#include "io/stack_index.hpp"
#include "io/stack_manifest.hpp"
#include "io/text_table.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/common/printable.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/mask.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "util/atomic_file.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace lightstage::io {
namespace {

namespace fs = std::filesystem;

std::string size_text(const cv::Mat& image) { return fmt::format("{}x{}", image.cols, image.rows); }

std::string type_text(const cv::Mat& image) { return image_type_text(image.type()); }

std::string default_frame_name(std::size_t index, const cv::Mat& image) {
  return fmt::format("{:03}.{}", index + 1, image.depth() == CV_32F ? "pfm" : "png");
}

std::string vec3_lines(const std::vector<Frame>& frames, bool directions) {
  std::string text;
  for (const auto& frame : frames) {
    const Vec3& v = directions ? frame.light_direction : frame.light_intensity;
    text += fmt::format("{:.9g} {:.9g} {:.9g}\n", v.x(), v.y(), v.z());
  }
  return text;
}

// The dark frames the manifest names, each read once and shared by its frames.
void load_darks(const fs::path& dir, const fs::path& manifest_path, const ImageHeader& frames,
                ImageStack& stack) {
  std::map<std::string, cv::Mat> darks;
  const cv::Mat& first = stack.frames.front().image;
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    Frame& frame = stack.frames[i];
    if (frame.dark_file.empty()) continue;
    auto it = darks.find(frame.dark_file);
    if (it == darks.end()) {
      const fs::path path = dir / frame.dark_file;
      if (!file_exists(path)) {
        fail("{}: frames[{}].dark: '{}' is not in the stack folder", manifest_path.string(), i,
             frame.dark_file);
      }
      check_declared_size(path, frames, "dark frame");
      cv::Mat dark = read_image(path);
      check_finite_pixels(path, dark);
      if (dark.size() != first.size() || dark.channels() != first.channels()) {
        fail("{}: dark frame is {} {}, but the images are {} {}", path.string(), size_text(dark),
             type_text(dark), size_text(first), type_text(first));
      }
      it = darks.emplace(frame.dark_file, std::move(dark)).first;
    }
    frame.dark = it->second;
  }
}

// The dark frames the stack's frames name, by file name, each once; checked
// before write_stack writes anything.
std::map<std::string, cv::Mat> darks_to_write(const fs::path& dir, const ImageStack& stack) {
  std::map<std::string, cv::Mat> darks;
  const cv::Mat& first = stack.frames.front().image;
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    const Frame& frame = stack.frames[i];
    if (frame.dark.empty() && frame.dark_file.empty()) continue;
    if (frame.dark_file.empty()) fail("{}: frame {} has a dark frame but no dark_file name", dir.string(), i);
    if (frame.dark.empty()) {
      fail("{}: frame {} names dark '{}' but carries no dark image to write", dir.string(), i,
           frame.dark_file);
    }
    const bool is_float = frame.dark.depth() == CV_32F;
    if (frame.dark_file.find('/') != std::string::npos ||
        fs::path(frame.dark_file).extension() != (is_float ? ".pfm" : ".png")) {
      fail("{}: frame {} dark file name '{}' must be a plain file name ending in {}", dir.string(), i,
           frame.dark_file, is_float ? ".pfm" : ".png");
    }
    if (frame.dark.size() != first.size() || frame.dark.channels() != first.channels()) {
      fail("{}: frame {} dark is {} {}, the images are {} {}", dir.string(), i, size_text(frame.dark),
           type_text(frame.dark), size_text(first), type_text(first));
    }
    const auto [it, added] = darks.emplace(frame.dark_file, frame.dark);
    const cv::Mat& known = it->second;
    if (!added && known.data != frame.dark.data &&
        (known.type() != frame.dark.type() || cv::norm(known, frame.dark, cv::NORM_INF) != 0)) {
      fail("{}: frames name dark '{}' for two different images", dir.string(), frame.dark_file);
    }
  }
  return darks;
}

// The index files (names, lights, manifest) must agree with each other: all
// are written to temporaries first and renamed only when every one is on
// disk, so a failed write (a full disk) leaves the previous index whole.
void write_index_files(const fs::path& dir, const std::vector<std::pair<std::string, std::string>>& files) {
  std::vector<std::pair<fs::path, fs::path>> staged;  // (temporary, target)
  const auto discard = [&] {
    std::error_code ignored;
    for (const auto& [temporary, target] : staged) fs::remove(temporary, ignored);
  };
  try {
    for (const auto& [name, text] : files)
      staged.emplace_back(util::write_temporary(dir / name, text), dir / name);
  } catch (...) {
    discard();
    throw;
  }
  for (std::size_t i = 0; i < staged.size(); ++i) {
    try {
      util::commit_temporary(staged[i].first, staged[i].second);
    } catch (...) {
      staged.erase(staged.begin(), staged.begin() + static_cast<std::ptrdiff_t>(i + 1));
      discard();
      throw;
    }
  }
}

}  // namespace

void LoadOptions::check() const {
  if (min_images < 1) fail("LoadOptions.min_images: must be at least 1, got {}", min_images);
  if (threads < 0) fail("LoadOptions.threads: must be 0 (automatic) or positive, got {}", threads);
}

StackIndex read_stack_index(const fs::path& dir, const LoadOptions& options) {
  options.check();
  std::error_code error;
  if (!fs::exists(dir, error)) fail("{}: no such stack folder", dir.string());
  if (!fs::is_directory(dir, error)) fail("{}: not a folder (a stack is a folder)", dir.string());

  const fs::path names_path = dir / "filenames.txt";
  const auto names = read_text_lines(names_path);
  check_listed_names(names_path, names);
  for (const auto& name : names) {
    const fs::path relative(name.text);
    if (relative.is_absolute() ||
        std::any_of(relative.begin(), relative.end(), [](const fs::path& part) { return part == ".."; })) {
      fail("{}:{}: '{}' must name a file inside the stack folder", names_path.string(), name.number,
           printable(name.text));
    }
  }
  if (static_cast<int>(names.size()) < options.min_images) {
    fail("{}: {} image(s) listed, at least {} needed", names_path.string(), names.size(), options.min_images);
  }

  const fs::path directions_path = dir / "light_directions.txt";
  const auto directions = read_vec3_rows(directions_path);
  if (directions.size() != names.size()) {
    fail("{}: {} direction line(s), but filenames.txt lists {} images", directions_path.string(),
         directions.size(), names.size());
  }
  for (const auto& row : directions) {
    if (row.value.norm() < 1e-9)
      fail("{}:{}: zero-length light direction", directions_path.string(), row.number);
  }

  const fs::path intensities_path = dir / "light_intensities.txt";
  std::vector<Vec3Row> intensities;
  if (file_exists(intensities_path)) {
    intensities = read_vec3_rows(intensities_path);
    if (intensities.size() != names.size()) {
      fail("{}: {} intensity line(s), but filenames.txt lists {} images", intensities_path.string(),
           intensities.size(), names.size());
    }
    for (const auto& row : intensities) {
      if ((row.value.array() <= 0).any()) {
        fail("{}:{}: light intensities must be positive, got '{} {} {}'", intensities_path.string(),
             row.number, row.value.x(), row.value.y(), row.value.z());
      }
    }
  }

  ImageStack stack;
  stack.frames.resize(names.size());
  for (std::size_t i = 0; i < names.size(); ++i) {
    Frame& frame = stack.frames[i];
    frame.filename = names[i].text;
    frame.light_direction = directions[i].value.normalized();
    if (!intensities.empty()) frame.light_intensity = intensities[i].value;
  }
  const fs::path manifest_path = dir / "manifest.json";
  const bool use_manifest = options.read_manifest && file_exists(manifest_path);
  std::vector<std::string> files;
  for (const auto& frame : stack.frames) files.push_back(frame.filename);
  const nlohmann::json manifest = use_manifest ? read_manifest_json(manifest_path) : nlohmann::json();
  StackIndex index;
  index.declared = check_frame_headers(
      dir, files, use_manifest ? manifest_image_size(manifest_path, manifest) : std::nullopt, manifest_path);
  if (use_manifest) {
    apply_manifest(manifest_path, manifest, stack);
    index.manifest_path = manifest_path;
  }
  index.stack = std::move(stack);
  return index;
}

StackOutline read_stack_outline(const fs::path& dir, const LoadOptions& options) {
  const StackIndex index = read_stack_index(dir, options);
  StackOutline outline;
  outline.size = {static_cast<int>(index.declared.width), static_cast<int>(index.declared.height)};
  outline.images = index.stack.frames.size();
  outline.pixel_bytes = index.declared.pixel_bytes;
  std::set<std::string> darks;
  for (const Frame& frame : index.stack.frames)
    if (!frame.dark_file.empty()) darks.insert(frame.dark_file);
  outline.dark_files = darks.size();
  return outline;
}

ImageStack load_stack(const fs::path& dir, const LoadOptions& options) {
  StackIndex index = read_stack_index(dir, options);
  ImageStack& stack = index.stack;
  const ImageHeader& declared = index.declared;
  const std::size_t count = stack.frames.size();
  const cv::Size declared_size(static_cast<int>(declared.width), static_cast<int>(declared.height));
  const fs::path first_path = dir / stack.frames.front().filename;
  // The ground truth's normals (the largest file after the frames) decode beside them, first so that no
  // thread waits on it at the end; errors are raised afterwards in the order the files are checked.
  const fs::path normals_path = dir / "Normal_gt.png";
  const bool truth_beside = options.frame_pixels && options.load_ground_truth && file_exists(normals_path);
  std::optional<DecodedNormals> truth_normals;
  std::vector<std::exception_ptr> errors(count + 1);  // the frames', then the ground truth's
  if (options.frame_pixels) {
    const int first = truth_beside ? -1 : 0;
    parallel_for(static_cast<int>(count) - first, options.threads, [&](int item) {
      const int i = item + first;
      const std::size_t slot = i < 0 ? count : static_cast<std::size_t>(i);
      try {
        if (i < 0) {
          check_declared_size(normals_path, declared, "ground truth");  // before decoding it
          truth_normals = read_normal_map(normals_path);
          return;
        }
        const fs::path path = dir / stack.frames[slot].filename;
        stack.frames[slot].image = read_image(path);
        check_finite_pixels(path, stack.frames[slot].image);
      } catch (...) {
        errors[slot] = std::current_exception();
      }
    });
    for (std::size_t i = 0; i < count; ++i)
      if (errors[i]) std::rethrow_exception(errors[i]);
    const cv::Mat& image0 = stack.frames.front().image;
    for (const auto& frame : stack.frames) {
      const fs::path path = dir / frame.filename;
      if (frame.image.size() != image0.size()) {
        fail("{}: image is {}, but {} is {}", path.string(), size_text(frame.image),
             first_path.filename().string(), size_text(image0));
      }
      if (frame.image.type() != image0.type()) {
        fail("{}: image is {}, but {} is {}", path.string(), type_text(frame.image),
             first_path.filename().string(), type_text(image0));
      }
    }
  }
  // Without frame pixels, the size every header declared stands for the images'.
  const cv::Mat first = options.frame_pixels ? stack.frames.front().image : cv::Mat(declared_size, CV_8UC1);

  const fs::path mask_path = dir / "mask.png";
  if (file_exists(mask_path)) {
    check_declared_size(mask_path, declared, "mask");
    stack.mask = read_mask(mask_path);
    if (stack.mask.size() != first.size()) {
      fail("{}: mask is {}, images are {} (e.g. {})", mask_path.string(), size_text(stack.mask),
           size_text(first), first_path.filename().string());
    }
  }

  if (options.load_ground_truth) {
    const fs::path depth_path = dir / "depth_gt.pfm";
    GroundTruth truth;
    if (file_exists(normals_path)) {
      check_declared_size(normals_path, declared, "ground truth");
      if (errors[count]) std::rethrow_exception(errors[count]);
      auto decoded = truth_normals ? std::move(*truth_normals) : read_normal_map(normals_path);
      if (decoded.normals.size() != first.size()) {
        fail("{}: ground truth is {}, images are {}", normals_path.string(), size_text(decoded.normals),
             size_text(first));
      }
      truth.normals = decoded.normals;
    }
    if (file_exists(depth_path)) {
      truth.depth = read_pfm(depth_path);
      if (truth.depth.channels() != 1 || truth.depth.size() != first.size()) {
        fail("{}: depth must be one channel of {}, got {} channel(s) of {}", depth_path.string(),
             size_text(first), truth.depth.channels(), size_text(truth.depth));
      }
    }
    if (!truth.normals.empty() || !truth.depth.empty()) stack.ground_truth = std::move(truth);
  }

  if (!index.manifest_path.empty() && options.frame_pixels)
    load_darks(dir, index.manifest_path, declared, stack);
  return std::move(index.stack);
}

void write_stack(const fs::path& dir, const ImageStack& stack, const nlohmann::json& extra_manifest,
                 bool write_images) {
  if (stack.frames.empty()) fail("{}: cannot write a stack without frames", dir.string());
  StackFiles files;
  if (!write_images) {
    // The images are on disk (a capture or a simulation wrote each as it came): their pixels need not be
    // held, and the first file's header gives the size the mask must have.
    for (std::size_t i = 0; i < stack.frames.size(); ++i) {
      const std::string& name = stack.frames[i].filename;
      if (name.empty() || name.find('/') != std::string::npos || name.find('\n') != std::string::npos)
        fail("{}: frame {} file name '{}' must be a plain file name", dir.string(), i, name);
      files.frames.push_back(name);
    }
    const ImageHeader header = read_image_header(dir / files.frames.front());
    const cv::Size size(static_cast<int>(header.width), static_cast<int>(header.height));
    files.size = size;
    if (!stack.mask.empty() && (stack.mask.type() != CV_8UC1 || stack.mask.size() != size))
      fail("{}: mask must be CV_8UC1 of {}x{}, got type {} of {}", dir.string(), size.width, size.height,
           stack.mask.type(), size_text(stack.mask));
  }
  const cv::Mat& first = stack.frames.front().image;
  if (write_images) files.size = first.size();
  for (std::size_t i = 0; write_images && i < stack.frames.size(); ++i) {
    const Frame& frame = stack.frames[i];
    if (frame.image.empty()) fail("{}: frame {} has no image", dir.string(), i);
    if (frame.image.size() != first.size() || frame.image.type() != first.type()) {
      fail("{}: frame {} is {} {}, frame 0 is {} {}", dir.string(), i, size_text(frame.image),
           type_text(frame.image), size_text(first), type_text(first));
    }
    std::string name = frame.filename.empty() ? default_frame_name(i, frame.image) : frame.filename;
    if (name.find('/') != std::string::npos || name.find('\n') != std::string::npos) {
      fail("{}: frame {} file name '{}' must be a plain file name", dir.string(), i, name);
    }
    const bool is_float = frame.image.depth() == CV_32F;
    if (is_float != (fs::path(name).extension() == ".pfm") ||
        (!is_float && fs::path(name).extension() != ".png")) {
      fail("{}: frame {} file name '{}' does not fit a {} image (use .png for 8/16-bit, .pfm for float)",
           dir.string(), i, name, type_text(frame.image));
    }
    files.frames.push_back(std::move(name));
  }
  if (write_images && !stack.mask.empty() &&
      (stack.mask.type() != CV_8UC1 || stack.mask.size() != first.size())) {
    fail("{}: mask must be CV_8UC1 of {}, got type {} of {}", dir.string(), size_text(first),
         stack.mask.type(), size_text(stack.mask));
  }
  // Checked before anything is written, so a bad extra_manifest leaves no half stack.
  files.mask = stack.mask.empty() ? "" : "mask.png";
  if (stack.ground_truth) {
    if (!stack.ground_truth->normals.empty()) files.normals = "Normal_gt.png";
    if (!stack.ground_truth->depth.empty()) files.depth = "depth_gt.pfm";
  }
  const nlohmann::json manifest = build_manifest(stack, files, extra_manifest);
  const std::map<std::string, cv::Mat> darks =
      write_images ? darks_to_write(dir, stack) : std::map<std::string, cv::Mat>{};

  std::error_code error;
  fs::create_directories(dir, error);
  if (error) fail("{}: cannot create folder: {}", dir.string(), error.message());

  parallel_chunks(write_images ? stack.frames.size() : 0, 0,
                  [&](std::size_t, std::size_t begin, std::size_t end) {
                    for (std::size_t i = begin; i < end; ++i) {
                      const fs::path path = dir / files.frames[i];
                      if (stack.frames[i].image.depth() == CV_32F) {
                        write_pfm(path, stack.frames[i].image);
                      } else {
                        write_png(path, stack.frames[i].image);
                      }
                    }
                  });
  for (const auto& [file, dark] : darks) {
    if (dark.depth() == CV_32F) {
      write_pfm(dir / file, dark);
    } else {
      write_png(dir / file, dark);
    }
  }
  if (!files.mask.empty()) {
    cv::Mat binary;
    cv::compare(stack.mask, 0, binary, cv::CMP_GT);
    write_png(dir / files.mask, binary);
  }
  if (!files.normals.empty()) write_normal_map(dir / files.normals, stack.ground_truth->normals, stack.mask);
  if (!files.depth.empty()) write_pfm(dir / files.depth, stack.ground_truth->depth);
  std::string names;
  for (const auto& name : files.frames) names += name + "\n";
  write_index_files(dir, {{"filenames.txt", names},
                          {"light_directions.txt", vec3_lines(stack.frames, true)},
                          {"light_intensities.txt", vec3_lines(stack.frames, false)},
                          {"manifest.json", manifest.dump(2) + "\n"}});
}

void write_empty_stack(const fs::path& dir, const nlohmann::json& manifest) {
  write_index_files(dir, {{"filenames.txt", ""},
                          {"light_directions.txt", ""},
                          {"light_intensities.txt", ""},
                          {"manifest.json", manifest.dump(2) + "\n"}});
}

}  // namespace lightstage::io
