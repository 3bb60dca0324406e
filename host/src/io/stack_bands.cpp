#include "lightstage/host/io/stack_bands.hpp"

#include "io/stack_checks.hpp"
#include "io/stack_index.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/io/mask.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/row_reader.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <exception>
#include <functional>
#include <map>
#include <system_error>
#include <utility>
#include <vector>

namespace lightstage::io {
namespace {

namespace fs = std::filesystem;

// Open files beside the frames': the process's own, the outputs being written.
constexpr std::size_t kSpareFiles = 64;

}  // namespace

StackBands::StackBands(const fs::path& dir, const LoadOptions& options) : dir_(dir), options_(options) {
  StackIndex index = read_stack_index(dir, options);
  index_ = std::move(index.stack);
  size_ = {static_cast<int>(index.declared.width), static_cast<int>(index.declared.height)};

  // The first frame gives the type; the others are opened with the first band.
  frames_.resize(index_.frames.size());
  frames_.front() = open_row_reader(dir / index_.frames.front().filename);
  type_ = frames_.front()->type();
  if (frames_.front()->size() != size_)
    fail("{}: image is {}x{}, but its header said {}x{}", frames_.front()->path().string(),
         frames_.front()->size().width, frames_.front()->size().height, size_.width, size_.height);

  const fs::path mask_path = dir / "mask.png";
  if (file_exists(mask_path)) {
    check_declared_size(mask_path, index.declared, "mask");
    index_.mask = read_mask(mask_path);
    if (index_.mask.size() != size_)
      fail("{}: mask is {}x{}, images are {}x{}", mask_path.string(), index_.mask.cols, index_.mask.rows,
           size_.width, size_.height);
  }
  if (options.load_ground_truth) {
    const fs::path normals_path = dir / "Normal_gt.png";
    const fs::path depth_path = dir / "depth_gt.pfm";
    if (file_exists(normals_path)) {
      check_declared_size(normals_path, index.declared, "ground truth");
      normals_ = open_row_reader(normals_path);
    }
    if (file_exists(depth_path)) {
      depth_ = open_row_reader(depth_path);
      if (CV_MAT_CN(depth_->type()) != 1 || depth_->size() != size_)
        fail("{}: depth must be one channel of {}x{}, got {} channel(s) of {}x{}", depth_path.string(),
             size_.width, size_.height, CV_MAT_CN(depth_->type()), depth_->size().width,
             depth_->size().height);
    }
  }
  if (!index.manifest_path.empty()) {
    for (std::size_t i = 0; i < index_.frames.size(); ++i) {
      const std::string& name = index_.frames[i].dark_file;
      if (name.empty() || darks_.count(name) != 0) continue;
      const fs::path path = dir / name;
      if (!file_exists(path))
        fail("{}: frames[{}].dark: '{}' is not in the stack folder", index.manifest_path.string(), i, name);
      check_declared_size(path, index.declared, "dark frame");
      auto dark = open_row_reader(path);
      if (CV_MAT_CN(dark->type()) != CV_MAT_CN(type_))
        fail("{}: dark frame is {}, but the images are {}", path.string(), image_type_text(dark->type()),
             image_type_text(type_));
      darks_.emplace(name, std::move(dark));
    }
  }
}

StackBands::~StackBands() = default;

void StackBands::open_frames() {
  // Every frame's file stays open from band to band: the soft limit on open files (often 1024) is raised
  // as far as the hard one lets it, and a stack that still does not fit is refused, naming the limit.
  const auto needed = static_cast<rlim_t>(frames_.size() + darks_.size() + kSpareFiles);
  rlimit files{};
  if (getrlimit(RLIMIT_NOFILE, &files) == 0 && files.rlim_cur != RLIM_INFINITY && files.rlim_cur < needed) {
    files.rlim_cur = files.rlim_max == RLIM_INFINITY ? needed : std::min(needed, files.rlim_max);
    setrlimit(RLIMIT_NOFILE, &files);
    if (getrlimit(RLIMIT_NOFILE, &files) == 0 && files.rlim_cur != RLIM_INFINITY && files.rlim_cur < needed)
      fail("{}: {} frames to read in bands need {} open files, the system allows {} (ulimit -n)",
           dir_.string(), frames_.size(), needed, files.rlim_cur);
  }
  parallel_chunks(frames_.size(), options_.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      if (!frames_[i]) frames_[i] = open_row_reader(dir_ / index_.frames[i].filename);
  });
  const RowReader& first = *frames_.front();
  for (const auto& frame : frames_) {
    if (frame->size() != size_)
      fail("{}: image is {}x{}, but {} is {}x{}", frame->path().string(), frame->size().width,
           frame->size().height, first.path().filename().string(), size_.width, size_.height);
    if (frame->type() != type_)
      fail("{}: image is {}, but {} is {}", frame->path().string(), image_type_text(frame->type()),
           first.path().filename().string(), image_type_text(type_));
  }
  opened_ = true;
}

ImageStack StackBands::read_band(int y0, int rows) {
  if (!opened_) open_frames();
  ImageStack band;
  band.frames = index_.frames;
  // Every file's rows are a task of their own, handed to the next free thread,
  // the ground truth (the largest file after the frames) first so that no
  // thread waits on it at the end. Errors are raised afterwards in the order
  // load_stack checks the files: the frames', the ground truth's, the darks'.
  const std::size_t count = frames_.size();
  std::vector<std::exception_ptr> errors(count + 2 + darks_.size());
  std::vector<std::function<void()>> files;
  const auto add = [&](std::size_t slot, std::function<void()> read) {
    files.emplace_back([&errors, slot, read = std::move(read)] {
      try {
        read();
      } catch (...) {
        errors[slot] = std::current_exception();
      }
    });
  };
  GroundTruth truth;
  if (normals_)
    add(count, [&] {
      cv::Mat encoded;
      normals_->read(y0, rows, encoded);
      truth.normals = decode_normal_map(encoded, normals_->path().string()).normals;
    });
  if (depth_) add(count + 1, [&] { depth_->read(y0, rows, truth.depth); });
  std::map<std::string, cv::Mat> darks;
  std::size_t dark_slot = count + 2;
  for (auto& [name, reader] : darks_)
    add(dark_slot++, [&, &dark = darks[name], reader = reader.get()] {
      reader->read(y0, rows, dark);
      check_finite_pixels(reader->path(), dark, y0);
    });
  for (std::size_t i = 0; i < count; ++i)
    add(i, [&, i] {
      frames_[i]->read(y0, rows, band.frames[i].image);
      check_finite_pixels(frames_[i]->path(), band.frames[i].image, y0);
    });
  parallel_invoke(files, options_.threads);
  for (const std::exception_ptr& error : errors)
    if (error) std::rethrow_exception(error);
  for (Frame& frame : band.frames)
    if (!frame.dark_file.empty()) frame.dark = darks.at(frame.dark_file);
  if (!index_.mask.empty()) band.mask = index_.mask.rowRange(y0, y0 + rows).clone();
  if (normals_ || depth_) band.ground_truth = std::move(truth);
  rows_read_ += static_cast<std::size_t>(rows);
  return band;
}

}  // namespace lightstage::io
