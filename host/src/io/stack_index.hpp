#pragma once
// What a stack folder says before any pixel of it is decoded, shared by
// load_stack and the band reader (lightstage/host/io/stack_bands.hpp).

#include "io/image_header.hpp"
#include "lightstage/common/image_stack.hpp"
#include "lightstage/host/io/stack_io.hpp"

#include <filesystem>

namespace lightstage::io {

struct StackIndex {
  // Frames with their names, lights and manifest fields (dark_file too), without images or darks.
  ImageStack stack;
  ImageHeader declared;                 // the size every frame's header declares
  std::filesystem::path manifest_path;  // empty when no manifest was read
};

// filenames.txt, the light files and manifest.json, with every check
// load_stack makes before decoding (stack_checks.hpp). Throws InputError as
// load_stack does.
StackIndex read_stack_index(const std::filesystem::path& dir, const LoadOptions& options);

}  // namespace lightstage::io
