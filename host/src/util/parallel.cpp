#include "util/parallel.hpp"

#include <algorithm>
#include <exception>
#include <thread>
#include <vector>

namespace lightstage::util {

int resolve_threads(int requested) {
  if (requested > 0) return requested;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

std::size_t parallel_chunks(std::size_t count, int threads,
                            const std::function<void(std::size_t, std::size_t, std::size_t)>& body) {
  const std::size_t chunks = std::max<std::size_t>(
      1, std::min<std::size_t>(static_cast<std::size_t>(resolve_threads(threads)), count));
  std::vector<std::exception_ptr> errors(chunks);
  auto run = [&](std::size_t chunk) {
    const std::size_t begin = count * chunk / chunks;
    const std::size_t end = count * (chunk + 1) / chunks;
    try {
      body(chunk, begin, end);
    } catch (...) {
      errors[chunk] = std::current_exception();
    }
  };
  std::vector<std::thread> workers;
  workers.reserve(chunks - 1);
  for (std::size_t chunk = 1; chunk < chunks; ++chunk) workers.emplace_back(run, chunk);
  run(0);
  for (auto& worker : workers) worker.join();
  for (const auto& error : errors) {
    if (error) std::rethrow_exception(error);
  }
  return chunks;
}

}  // namespace lightstage::util
