#include "band_spill.hpp"

#include "lightstage/common/error.hpp"

#include <fmt/format.h>

#include <unistd.h>
#include <array>
#include <cstdint>
#include <system_error>

namespace lightstage::pipeline::bands {
namespace {

// The maps in file order (const or not).
template <typename Result>
auto maps_of(Result& band) {
  return std::array{&band.normals,    &band.albedo, &band.residual,     &band.solved,
                    &band.confidence, &band.chroma, &band.coefficients, &band.choice};
}

}  // namespace

BandSpill::BandSpill(const std::filesystem::path& dir)
    : path_(dir / fmt::format(".bands-{}.spill", ::getpid())) {
  file_.open(path_, std::ios::binary | std::ios::in | std::ios::out | std::ios::trunc);
  if (!file_) throw Error(fmt::format("{}: cannot create the solve's band spill file", path_.string()));
}

BandSpill::~BandSpill() {
  file_.close();
  std::error_code ignored;
  std::filesystem::remove(path_, ignored);
}

void BandSpill::write(const SolveResult& band, int rows) {
  if (!writing_) throw Error(fmt::format("{}: bands written after reading began", path_.string()));
  const auto put = [&](std::int32_t value) {
    file_.write(reinterpret_cast<const char*>(&value), sizeof value);
  };
  put(rows);
  for (const cv::Mat* map : maps_of(band)) {
    put(map->rows);
    put(map->cols);
    put(map->type());
    const auto row_bytes = static_cast<std::streamsize>(map->cols * map->elemSize());
    for (int y = 0; y < map->rows; ++y) file_.write(map->ptr<char>(y), row_bytes);
  }
  if (!file_)
    throw Error(fmt::format("{}: cannot write the solve's band spill file (disk full?)", path_.string()));
}

void BandSpill::rewind() {
  file_.flush();
  file_.clear();
  file_.seekg(0);
  writing_ = false;
  if (!file_) throw Error(fmt::format("{}: cannot read the solve's band spill file back", path_.string()));
}

SolveResult BandSpill::read(int& rows) {
  if (writing_) rewind();
  const auto get = [&]() {
    std::int32_t value = 0;
    file_.read(reinterpret_cast<char*>(&value), sizeof value);
    return value;
  };
  SolveResult band;
  rows = get();
  for (cv::Mat* map : maps_of(band)) {
    const int map_rows = get(), cols = get(), type = get();
    if (!file_) break;
    if (map_rows == 0) continue;
    map->create(map_rows, cols, type);
    file_.read(map->ptr<char>(), static_cast<std::streamsize>(map->total() * map->elemSize()));
  }
  if (!file_) throw Error(fmt::format("{}: the solve's band spill file ends early", path_.string()));
  return band;
}

}  // namespace lightstage::pipeline::bands
