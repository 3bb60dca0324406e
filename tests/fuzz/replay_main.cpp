// Runs a fuzz target without libFuzzer: every file of its corpus and regression
// folders, then seeded mutants of each (bit flips, byte edits, truncations,
// splices). The sanitizer build links each target with this driver, so CI checks
// every parser under ASan and UBSan without a third, clang-only build of the
// tree; `scripts/build.sh fuzz` still builds the coverage-guided fuzzers.
//   <target> [--mutants=N] [--seed=S] [--last-input=FILE] PATH...
// --last-input keeps the input being run in FILE, so the one a sanitizer stopped
// on can be added to regressions/.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <string>
#include <string_view>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);
extern "C" __attribute__((weak)) int LLVMFuzzerInitialize(int* argc, char*** argv);

namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::filesystem::path last_input;

void run(const Bytes& input) {
  if (!last_input.empty()) {
    std::ofstream out(last_input, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(input.data()), static_cast<std::streamsize>(input.size()));
  }
  // A copy of exactly `size` bytes, so ASan sees any read past the end.
  const auto copy = std::make_unique<std::uint8_t[]>(std::max<std::size_t>(input.size(), 1));
  std::copy(input.begin(), input.end(), copy.get());
  LLVMFuzzerTestOneInput(copy.get(), input.size());
}

// The edits libFuzzer's mutators start from, without its coverage feedback.
Bytes mutate(const Bytes& input, const Bytes& other, std::mt19937_64& random) {
  Bytes out = input;
  const auto pick = [&](std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(random);
  };
  const int edits = 1 + static_cast<int>(pick(4));
  for (int e = 0; e < edits; ++e) {
    switch (pick(6)) {
      case 0:  // flip a bit
        if (!out.empty()) out[pick(out.size())] ^= static_cast<std::uint8_t>(1u << pick(8));
        break;
      case 1:  // an interesting byte
        if (!out.empty()) {
          static constexpr std::uint8_t kBytes[] = {0x00, 0x01, 0x7f, 0x80, 0xff, '-', '9', '\n', ' ', '.'};
          out[pick(out.size())] = kBytes[pick(std::size(kBytes))];
        }
        break;
      case 2:  // insert a byte
        out.insert(out.begin() + static_cast<std::ptrdiff_t>(pick(out.size() + 1)),
                   static_cast<std::uint8_t>(pick(256)));
        break;
      case 3:  // erase a run
        if (!out.empty()) {
          const std::size_t at = pick(out.size());
          const std::size_t n = 1 + pick(std::min<std::size_t>(16, out.size() - at));
          out.erase(out.begin() + static_cast<std::ptrdiff_t>(at),
                    out.begin() + static_cast<std::ptrdiff_t>(at + n));
        }
        break;
      case 4:  // truncate
        out.resize(pick(out.size() + 1));
        break;
      default:  // splice the tail of another input
        if (!other.empty()) {
          out.resize(pick(out.size() + 1));
          const std::size_t from = pick(other.size());
          out.insert(out.end(), other.begin() + static_cast<std::ptrdiff_t>(from), other.end());
        }
        break;
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (LLVMFuzzerInitialize != nullptr) LLVMFuzzerInitialize(&argc, &argv);
  int mutants = 64;
  std::uint64_t seed = 1;
  std::vector<std::filesystem::path> files;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg.starts_with("--mutants=")) {
      mutants = std::atoi(argv[i] + 10);
    } else if (arg.starts_with("--seed=")) {
      seed = std::strtoull(argv[i] + 7, nullptr, 10);
    } else if (arg.starts_with("--last-input=")) {
      last_input = argv[i] + 13;
    } else if (std::filesystem::is_directory(arg)) {
      for (const auto& entry : std::filesystem::recursive_directory_iterator(arg))
        if (entry.is_regular_file()) files.push_back(entry.path());
    } else if (std::filesystem::is_regular_file(arg)) {
      files.emplace_back(arg);
    } else {
      std::fprintf(stderr, "%s: no such file or folder: %s\n", argv[0], argv[i]);
      return 2;
    }
  }
  if (files.empty()) {
    std::fprintf(stderr, "usage: %s [--mutants=N] [--seed=S] [--last-input=FILE] CORPUS_PATH...\n", argv[0]);
    return 2;
  }
  std::sort(files.begin(), files.end());  // the same order, hence the same mutants, on every machine

  std::vector<Bytes> inputs;
  inputs.reserve(files.size());
  for (const auto& file : files) inputs.push_back(read_bytes(file));
  std::mt19937_64 random(seed);
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    // Printed before the run, so a crash names the input it came from.
    std::fprintf(stderr, "%s (%zu bytes, %d mutants)\n", files[i].c_str(), inputs[i].size(), mutants);
    run(inputs[i]);
    for (int m = 0; m < mutants; ++m) run(mutate(inputs[i], inputs[(i + 1 + m) % inputs.size()], random));
  }
  std::fprintf(stderr, "replayed %zu inputs and %zu mutants\n", inputs.size(),
               inputs.size() * static_cast<std::size_t>(mutants));
  return 0;
}
