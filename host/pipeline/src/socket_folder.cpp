#include "lightstage/pipeline/socket_folder.hpp"

#include "lightstage/common/error.hpp"

#include <string>

#include <stdlib.h>

namespace lightstage::pipeline {

SocketFolder::SocketFolder() {
  std::string pattern = (std::filesystem::temp_directory_path() / "lightstage-dome-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) throw Error("cannot create a socket folder in " + pattern);
  path_ = pattern;
}

SocketFolder::~SocketFolder() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

}  // namespace lightstage::pipeline
