#pragma once
// Stack folders on disk: the DiLiGenT layout plus our manifest.json. Every
// file and every manifest key is described in docs/stack-format.md.
//
//   filenames.txt          image order, one file name per line (required)
//   <images>               8/16-bit PNG (grey or RGB), float PFM, TIFF or camera RAW, same size and type
//   light_directions.txt   "x y z" per image, object -> light (required)
//   light_intensities.txt  "r g b" per image (optional: all 1)
//   mask.png               object where the mask equals its maximum (optional: all pixels)
//   Normal_gt.png          ground-truth normals, normal-map encoding (optional)
//   depth_gt.pfm           ground-truth depth (optional)
//   dark_<exposure>us.png  averaged dark frames, named per frame by the manifest's "dark" (optional)
//   manifest.json          per-frame LED id, exposure, gain, levels, dark + rig/scene (optional)

#include "lightstage/common/image_stack.hpp"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>

namespace lightstage::io {

// What load_stack reads at most, checked before any image is decoded
// (docs/stack-format.md): images listed in filenames.txt, and pixels on either
// side of an image as its header declares them.
inline constexpr std::size_t kMaxStackImages = 10'000;
inline constexpr std::int64_t kMaxImageSide = 16'384;

struct LoadOptions {
  // Fewer listed images than this is an error (the Lambertian solver needs 3).
  int min_images = 3;
  // Read Normal_gt.png / depth_gt.pfm when present.
  bool load_ground_truth = true;
  // Read manifest.json when present (per-frame LED id, exposure, levels).
  bool read_manifest = true;
  // Decode the frames and their dark frames; false gives the frames without
  // pixels (names, lights, manifest fields), with the mask and ground truth,
  // for a reader that needs no frame pixels (a report without per-light
  // statistics of a stack too large for memory).
  bool frame_pixels = true;
  // Threads decoding images; 0 = hardware concurrency.
  int threads = 0;

  // Throws InputError naming the broken field and value.
  void check() const;
};

// Loads a stack folder. Light directions are normalised. Throws InputError,
// one line naming the file (and line or field), for: a missing folder or
// required file, a listed image that is missing or not an image, images of
// different size or type, fewer than min_images images, direction or
// intensity files with the wrong number of lines or malformed numbers, a
// zero-length direction, a non-positive intensity, a mask, ground truth,
// dark frame or manifest that does not fit the images, more than
// kMaxStackImages images or one listed twice, an image that is not PNG, PFM, TIFF or camera RAW
// or declares a side over kMaxImageSide (both checked from the headers before
// decoding), a float image holding NaN or infinity. Dark frames named by
// the manifest are read once each and shared by the frames naming them.
ImageStack load_stack(const std::filesystem::path& dir, const LoadOptions& options = {});

// What a stack folder declares before any pixel is decoded, with load_stack's
// checks up to there: enough to size its decoding.
struct StackOutline {
  cv::Size size;               // every image's
  std::size_t images = 0;      // frames listed
  int pixel_bytes = 0;         // a frame's pixel decoded, from its header; 0 = not said (TIFF, RAW)
  std::size_t dark_files = 0;  // distinct dark frames named by the manifest
};
StackOutline read_stack_outline(const std::filesystem::path& dir, const LoadOptions& options = {});

// Writes `stack` into `dir` (created if needed) in the same layout. Frames are
// written in their own type (8/16-bit PNG, float PFM) under Frame::filename
// (default "001.png", ... / "001.pfm"); the mask, Normal_gt.png and
// depth_gt.pfm are written when present, and with `write_images` each
// Frame::dark under its Frame::dark_file (once per name); manifest.json last. Keys of
// `extra_manifest` (an object: rig, scene, sensor, ...) are added at the top
// level; an "extra_manifest.frames" array of objects, one per frame, is merged
// into the frame entries. Every file is written atomically, and the index
// (filenames.txt, the light files, manifest.json) only once all of it is on
// disk, so a failed write leaves the previous index whole. With
// `write_images` false the frame images are taken to be on disk already (a
// capture or a simulation writes each as it lands) and only the other files
// are rewritten: the frames need their file names but not their pixels, so a
// stack larger than memory is indexed without being held.
void write_stack(const std::filesystem::path& dir, const ImageStack& stack,
                 const nlohmann::json& extra_manifest = nlohmann::json::object(), bool write_images = true);

// The index of a stack that has no frames yet (a capture before its first
// one): empty filenames.txt and light files with `manifest`, written as
// write_stack writes its index.
void write_empty_stack(const std::filesystem::path& dir, const nlohmann::json& manifest);

}  // namespace lightstage::io
