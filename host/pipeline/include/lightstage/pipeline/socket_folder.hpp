#pragma once
// A private folder under the temp dir for the simulated dome's unix sockets
// (their paths are short: 108 bytes), removed with this object.

#include <filesystem>

namespace lightstage::pipeline {

class SocketFolder {
 public:
  SocketFolder();  // throws Error when the folder cannot be made
  ~SocketFolder();
  SocketFolder(const SocketFolder&) = delete;
  SocketFolder& operator=(const SocketFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace lightstage::pipeline
