#include "json_file.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/temporary_path.hpp"

#include <fstream>
#include <system_error>

namespace lightstage::pipeline {

void write_json_file(const std::filesystem::path& path, const nlohmann::json& j, int indent) {
  const std::filesystem::path temporary = temporary_sibling(path);
  {
    std::ofstream stream(temporary);
    stream << j.dump(indent) << "\n";
    if (!stream.flush()) {
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      fail("{}: cannot write it", path.string());
    }
  }
  std::filesystem::rename(temporary, path);
}

}  // namespace lightstage::pipeline
