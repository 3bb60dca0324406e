#pragma once
// The decode floor: the time it takes to decode every frame of a stack on
// `threads` cores (a frame per core at a time, each dropped once decoded, so
// any stack fits), the least any solve of it can take. Speed figures of a
// solve are given as a ratio to it, measured in the same run
// (`lightstage bench decode`, scripts/bench-large-stack.py).

#include <nlohmann/json.hpp>

#include <cstddef>
#include <filesystem>

namespace lightstage::pipeline {

struct DecodeFloor {
  double seconds = 0;
  std::size_t frames = 0;
  std::size_t decoded_bytes = 0;  // every frame's pixels as decoded
  int threads = 0;

  nlohmann::json to_json() const;
};

// Throws InputError as load_stack does for a broken stack.
DecodeFloor measure_decode_floor(const std::filesystem::path& stack, int threads = 0);

}  // namespace lightstage::pipeline
