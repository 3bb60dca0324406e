#pragma once
// A JSON file written so that a reader never sees half of it: a temporary
// sibling, then a rename (batch.json, the tile plan and parts).

#include <nlohmann/json.hpp>

#include <filesystem>

namespace lightstage::pipeline {

// Writes `j` (indented by `indent`) to `path` atomically; throws InputError
// naming `path`, leaving no temporary behind, when it cannot be written.
void write_json_file(const std::filesystem::path& path, const nlohmann::json& j, int indent = 1);

}  // namespace lightstage::pipeline
