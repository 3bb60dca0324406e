#include "lightstage/host/io/output_folder.hpp"

#include "lightstage/common/error.hpp"

#include <algorithm>
#include <system_error>

namespace fs = std::filesystem;

namespace lightstage::io {
namespace {

// The path with symbolic links of its existing part resolved and "." / ".." removed.
fs::path resolved(const fs::path& path) {
  std::error_code error;
  fs::path absolute = fs::absolute(path, error);
  if (error) absolute = path;
  fs::path canonical = fs::weakly_canonical(absolute, error);
  if (error) canonical = absolute.lexically_normal();
  // "dir/" and "dir" are the same folder.
  if (!canonical.has_filename() && canonical.has_parent_path() && canonical != canonical.root_path())
    canonical = canonical.parent_path();
  return canonical;
}

bool is_within(const fs::path& inner, const fs::path& outer) {
  const auto [outer_end, inner_at] = std::mismatch(outer.begin(), outer.end(), inner.begin(), inner.end());
  return outer_end == outer.end();
}

}  // namespace

void require_empty_folder(const fs::path& out, std::string_view flag, std::string_view hint) {
  std::error_code error;
  const fs::file_status status = fs::status(out, error);
  if (!fs::exists(status)) return;
  if (!fs::is_directory(status)) fail("{} {}: exists and is not a folder ({})", flag, out.string(), hint);
  if (!fs::is_empty(out, error) || error)
    fail("{} {}: the folder exists and is not empty ({})", flag, out.string(), hint);
}

void require_separate_output(const fs::path& out, const std::vector<fs::path>& inputs) {
  const fs::path target = resolved(out);
  for (const fs::path& input : inputs) {
    if (input.empty()) continue;
    const fs::path source = resolved(input);
    if (target == source)
      fail("--out {}: is the input folder {}; writing there would overwrite its files (choose another --out)",
           out.string(), input.string());
    if (is_within(target, source))
      fail("--out {}: is inside the input folder {}; write the results beside it, not into it", out.string(),
           input.string());
  }
}

}  // namespace lightstage::io
