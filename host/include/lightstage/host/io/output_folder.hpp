#pragma once
// Checks on where a command writes, made before anything is read or written,
// so no command overwrites data it did not make: a folder that already holds
// something (a capture, a simulated stack) and a folder the command reads from.

#include <filesystem>
#include <string_view>
#include <vector>

namespace lightstage::io {

// Throws InputError naming `out` and `flag` when `out` exists and is not an
// empty folder; `hint` says how to go on (e.g. "use --resume ... or another --out").
void require_empty_folder(const std::filesystem::path& out, std::string_view flag, std::string_view hint);

// Throws InputError naming both folders when `out` is one of `inputs` or lies
// inside one of them (symbolic links and relative parts resolved, whether or
// not `out` exists yet): writing there would replace or mix with the input's files.
void require_separate_output(const std::filesystem::path& out,
                             const std::vector<std::filesystem::path>& inputs);

}  // namespace lightstage::io
