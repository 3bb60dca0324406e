#include "lightstage/sim/dng_writer.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/temporary_path.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <tiffio.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <memory>
#include <system_error>
#include <utility>
#include <vector>

// How the tags are handed to libtiff (4.5): TIFFSetField is variadic and reads
// each tag's arguments in the form its field table registers, which the DNG
// specification does not fix. For the tags written here:
//   - DNGVersion, DNGBackwardVersion: BYTE[4], a uint8_t* without a count;
//   - CFARepeatPatternDim, BlackLevelRepeatDim: SHORT[2], a uint16_t* without a count;
//   - CFAPattern, CFAPlaneColor: BYTE[n], an int count then a uint8_t*;
//   - BlackLevel, AsShotNeutral (RATIONAL), ColorMatrix1 (SRATIONAL): an int
//     count then a float* (libtiff stores these as float, not double);
//   - WhiteLevel: LONG[n], an int count then a uint32_t*;
//   - CFALayout, CalibrationIlluminant1, Orientation: SHORT, an int;
//   - EXIFIFD: IFD8, a uint64_t;
//   - EXIF ExposureTime, FNumber: RATIONAL, a double (varargs promote float);
//   - EXIF ISOSpeedRatings: SHORT[n], an int count then a uint16_t*.
// A mismatch is not diagnosed: it writes garbage. The tests read every one back.

namespace lightstage::sim {
namespace {

constexpr std::size_t kStripBytes = 64 * 1024;  // rows per strip: ~64 KiB of data
constexpr double kMaxIso = 65535;               // ISOSpeedRatings is a SHORT

// --- Checking the shot ---------------------------------------------------------------

void check_shot(const std::filesystem::path& path, const DngShot& shot) {
  const std::string name = path.string();
  if (shot.mosaic.type() != CV_16UC1) {
    fail("{}: cannot write a DNG: the mosaic is {}, not CV_16UC1 (one 16-bit channel)", name,
         cv::typeToString(shot.mosaic.type()));
  }
  if (shot.mosaic.dims != 2 || shot.mosaic.cols <= 0 || shot.mosaic.rows <= 0 || shot.mosaic.cols % 2 != 0 ||
      shot.mosaic.rows % 2 != 0) {
    fail(
        "{}: cannot write a DNG: the mosaic is {}x{}; its width and height must be even and non-zero (whole "
        "2x2 CFA cells)",
        name, shot.mosaic.cols, shot.mosaic.rows);
  }
  const std::string pattern(shot.cfa.begin(), shot.cfa.end());
  for (const char letter : shot.cfa) {
    if (letter != 'R' && letter != 'G' && letter != 'B') {
      fail("{}: cannot write a DNG: CFA letter '{}' in \"{}\" is not R, G or B", name, letter, pattern);
    }
  }
  if (std::count(pattern.begin(), pattern.end(), 'R') != 1 ||
      std::count(pattern.begin(), pattern.end(), 'G') != 2) {
    fail("{}: cannot write a DNG: CFA pattern \"{}\" must have exactly one R, two G and one B", name,
         pattern);
  }
  if (!(shot.white_level >= 1 && shot.white_level <= 65535)) {
    fail("{}: cannot write a DNG: white level {} is outside 1..65535 DN", name, shot.white_level);
  }
  for (std::size_t site = 0; site < shot.black_level.size(); ++site) {
    const double black = shot.black_level[site];
    if (!(black >= 0 && black < shot.white_level)) {
      fail(
          "{}: cannot write a DNG: black level {} of CFA site {} ('{}') must be >= 0 and below the white "
          "level {}",
          name, black, site, shot.cfa[site], shot.white_level);
    }
  }
  const auto check_optional = [&](const char* field, double value) {
    if (!(std::isfinite(value) && value >= 0)) {
      fail("{}: cannot write a DNG: {} {} must be finite and >= 0 (0 = unknown)", name, field, value);
    }
  };
  check_optional("exposure_s", shot.exposure_s);
  check_optional("iso", shot.iso);
  check_optional("f_number", shot.f_number);
}

// --- Files ---------------------------------------------------------------------------

// Removes the temporary file (once created) on every path out unless the
// rename happened.
class TemporaryFile {
 public:
  explicit TemporaryFile(std::filesystem::path path) : path_(std::move(path)) {}
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  ~TemporaryFile() {
    if (!committed_) {
      std::error_code ignored;
      std::filesystem::remove(path_, ignored);
    }
  }
  const std::filesystem::path& path() const { return path_; }
  void committed() { committed_ = true; }

 private:
  std::filesystem::path path_;
  bool committed_ = false;
};

// The file under libtiff: its own I/O procedures over a file descriptor, so
// that a failed write or close keeps its errno for the message (libtiff's own
// says only "Write error at scanline n"), and libtiff's error messages, kept
// for the exception rather than printed by the process-wide handler.
struct TiffFile {
  int fd = -1;
  int io_error = 0;        // errno of the first failed read, write, seek or close
  std::string tiff_error;  // libtiff's first error message
};

void keep_io_error(TiffFile& file) {
  if (file.io_error == 0) file.io_error = errno != 0 ? errno : EIO;
}

tmsize_t read_proc(thandle_t handle, void* data, tmsize_t size) {
  auto& file = *static_cast<TiffFile*>(handle);
  tmsize_t done = 0;
  while (done < size) {
    const ssize_t n = ::read(file.fd, static_cast<char*>(data) + done, static_cast<std::size_t>(size - done));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) keep_io_error(file);
    if (n <= 0) return n < 0 ? -1 : done;
    done += n;
  }
  return done;
}

tmsize_t write_proc(thandle_t handle, void* data, tmsize_t size) {
  auto& file = *static_cast<TiffFile*>(handle);
  tmsize_t done = 0;
  while (done < size) {
    const ssize_t n =
        ::write(file.fd, static_cast<const char*>(data) + done, static_cast<std::size_t>(size - done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      keep_io_error(file);
      return -1;
    }
    done += n;
  }
  return done;
}

toff_t seek_proc(thandle_t handle, toff_t offset, int whence) {
  auto& file = *static_cast<TiffFile*>(handle);
  const off_t position = ::lseek(file.fd, static_cast<off_t>(offset), whence);
  if (position < 0) {
    keep_io_error(file);
    return static_cast<toff_t>(-1);
  }
  return static_cast<toff_t>(position);
}

int close_proc(thandle_t handle) {
  auto& file = *static_cast<TiffFile*>(handle);
  const int result = ::close(file.fd);
  if (result != 0) keep_io_error(file);
  file.fd = -1;
  return result;
}

toff_t size_proc(thandle_t handle) {
  struct stat status {};
  if (::fstat(static_cast<TiffFile*>(handle)->fd, &status) != 0) return 0;
  return static_cast<toff_t>(status.st_size);
}

int map_proc(thandle_t /*handle*/, void** /*base*/, toff_t* /*size*/) { return 0; }  // never mapped
void unmap_proc(thandle_t /*handle*/, void* /*base*/, toff_t /*size*/) {}

int keep_tiff_error(TIFF* /*tiff*/, void* user_data, const char* module, const char* format, va_list args) {
  auto& file = *static_cast<TiffFile*>(user_data);
  if (file.tiff_error.empty()) {
    std::array<char, 512> text{};
    std::vsnprintf(text.data(), text.size(), format, args);
    file.tiff_error =
        module != nullptr ? fmt::format("{}: {}", module, text.data()) : std::string(text.data());
    if (file.tiff_error.empty()) file.tiff_error = "libtiff reported an error";
  }
  return 1;  // handled: not passed on to the process-wide handler
}

int ignore_tiff_warning(TIFF* /*tiff*/, void* /*user_data*/, const char* /*module*/, const char* /*format*/,
                        va_list /*args*/) {
  return 1;
}

// What went wrong, for "<path>: cannot write: <what>".
std::string failure(const TiffFile& file) {
  if (file.io_error != 0) return std::strerror(file.io_error);
  return file.tiff_error.empty() ? "libtiff failed" : file.tiff_error;
}

struct TiffCloser {
  void operator()(TIFF* tiff) const { TIFFClose(tiff); }
};
using TiffHandle = std::unique_ptr<TIFF, TiffCloser>;

// Creates `temporary` (which must not exist yet) and opens it for writing
// through `file`, which must outlive the handle; throws naming `target`,
// leaving nothing behind.
TiffHandle create_tiff(const std::filesystem::path& temporary, const std::filesystem::path& target,
                       TiffFile& file) {
  file.fd = ::open(temporary.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (file.fd < 0) {
    fail("{}: cannot write: cannot create a file in this folder ({})", target.string(), std::strerror(errno));
  }
  std::unique_ptr<TIFFOpenOptions, void (*)(TIFFOpenOptions*)> options(TIFFOpenOptionsAlloc(),
                                                                       &TIFFOpenOptionsFree);
  TIFF* tiff = nullptr;
  if (options) {
    TIFFOpenOptionsSetErrorHandlerExtR(options.get(), &keep_tiff_error, &file);
    TIFFOpenOptionsSetWarningHandlerExtR(options.get(), &ignore_tiff_warning, nullptr);
    // "l": little-endian, as DNG files customarily are; "m": never memory-mapped.
    tiff = TIFFClientOpenExt(temporary.c_str(), "wlm", &file, &read_proc, &write_proc, &seek_proc,
                             &close_proc, &size_proc, &map_proc, &unmap_proc, options.get());
  }
  if (tiff == nullptr) {
    ::close(file.fd);
    file.fd = -1;
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    fail("{}: cannot write: {}", target.string(), options ? failure(file) : "out of memory");
  }
  return TiffHandle(tiff);
}

// --- Tags ----------------------------------------------------------------------------

std::uint8_t cfa_code(char letter) {
  switch (letter) {
    case 'R':
      return 0;
    case 'G':
      return 1;
    default:
      return 2;  // 'B' (checked)
  }
}

// "YYYY:MM:DD HH:MM:SS" (UTC) and the milliseconds as 3 digits.
std::pair<std::string, std::string> exif_time(std::chrono::system_clock::time_point taken) {
  const auto seconds = std::chrono::floor<std::chrono::seconds>(taken);
  const auto millis = std::chrono::duration_cast<std::chrono::milliseconds>(taken - seconds).count();
  const std::time_t time = std::chrono::system_clock::to_time_t(seconds);
  std::tm utc{};
  gmtime_r(&time, &utc);
  return {fmt::format("{:04d}:{:02d}:{:02d} {:02d}:{:02d}:{:02d}", utc.tm_year + 1900, utc.tm_mon + 1,
                      utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec),
          fmt::format("{:03d}", millis)};
}

bool has_exif(const DngShot& shot) {
  return shot.exposure_s > 0 || shot.iso > 0 || shot.f_number > 0 || shot.taken.has_value();
}

// Writes the EXIF IFD (the known fields only) ahead of the image and stores
// its offset in `offset`, then makes an empty image directory current for
// IFD 0. First, because the other order needs IFD 0 written twice (with a
// placeholder, then again with the offset after TIFFSetDirectory(0)), and
// libtiff 4.5.0 rewrote it in place over the EXIF IFD that followed it.
bool write_exif_ifd(TIFF* tiff, const DngShot& shot, std::uint64_t& offset) {
  if (TIFFCreateEXIFDirectory(tiff) != 0) return false;
  bool ok = true;
  if (shot.exposure_s > 0) ok = ok && TIFFSetField(tiff, EXIFTAG_EXPOSURETIME, shot.exposure_s) == 1;
  if (shot.f_number > 0) ok = ok && TIFFSetField(tiff, EXIFTAG_FNUMBER, shot.f_number) == 1;
  if (shot.iso > 0) {
    const auto iso = static_cast<std::uint16_t>(std::clamp(std::round(shot.iso), 1.0, kMaxIso));
    ok = ok && TIFFSetField(tiff, EXIFTAG_ISOSPEEDRATINGS, 1, &iso) == 1;
  }
  if (shot.taken) {
    const auto [date_time, sub_seconds] = exif_time(*shot.taken);
    ok = ok && TIFFSetField(tiff, EXIFTAG_DATETIMEORIGINAL, date_time.c_str()) == 1;
    ok = ok && TIFFSetField(tiff, EXIFTAG_SUBSECTIMEORIGINAL, sub_seconds.c_str()) == 1;
  }
  ok = ok && TIFFWriteCustomDirectory(tiff, &offset) == 1;
  // Back to an ordinary (image) directory for IFD 0.
  TIFFFreeDirectory(tiff);
  TIFFCreateDirectory(tiff);
  return ok;
}

bool set_image_tags(TIFF* tiff, const DngShot& shot, std::uint64_t exif_offset) {
  const auto width = static_cast<std::uint32_t>(shot.mosaic.cols);
  const auto height = static_cast<std::uint32_t>(shot.mosaic.rows);
  const std::size_t row_bytes = std::size_t{width} * sizeof(std::uint16_t);
  const auto rows_per_strip =
      static_cast<std::uint32_t>(std::clamp<std::size_t>(kStripBytes / row_bytes, 1, std::size_t{height}));
  const std::string unique_model =
      shot.make.empty() ? shot.model : (shot.model.empty() ? shot.make : shot.make + " " + shot.model);

  static constexpr std::uint8_t kDngVersion[4] = {1, 4, 0, 0};
  static constexpr std::uint8_t kDngBackwardVersion[4] = {1, 1, 0, 0};
  static constexpr std::uint16_t kRepeatDim[2] = {2, 2};
  static constexpr std::uint8_t kPlaneColor[3] = {0, 1, 2};  // R, G, B
  static constexpr float kIdentity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  static constexpr float kNeutral[3] = {1, 1, 1};
  constexpr int kD65 = 21;
  constexpr int kRectangularLayout = 1;
  std::uint8_t pattern[4];
  float black[4];
  for (std::size_t site = 0; site < 4; ++site) {
    pattern[site] = cfa_code(shot.cfa[site]);
    black[site] = static_cast<float>(shot.black_level[site]);
  }
  const auto white = static_cast<std::uint32_t>(std::lround(shot.white_level));

  // Arrays go through the varargs as pointers; libtiff copies them.
  bool ok = true;
  const auto set = [&](std::uint32_t tag, auto... args) { ok = ok && TIFFSetField(tiff, tag, args...) == 1; };
  set(TIFFTAG_SUBFILETYPE, std::uint32_t{0});
  set(TIFFTAG_IMAGEWIDTH, width);
  set(TIFFTAG_IMAGELENGTH, height);
  set(TIFFTAG_BITSPERSAMPLE, 16);
  set(TIFFTAG_SAMPLESPERPIXEL, 1);
  set(TIFFTAG_COMPRESSION, COMPRESSION_NONE);
  set(TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_CFA);
  set(TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  set(TIFFTAG_ROWSPERSTRIP, rows_per_strip);
  set(TIFFTAG_ORIENTATION, ORIENTATION_TOPLEFT);
  set(TIFFTAG_MAKE, shot.make.c_str());
  set(TIFFTAG_MODEL, shot.model.c_str());
  set(TIFFTAG_DNGVERSION, kDngVersion);
  set(TIFFTAG_DNGBACKWARDVERSION, kDngBackwardVersion);
  set(TIFFTAG_UNIQUECAMERAMODEL, unique_model.c_str());
  set(TIFFTAG_CFAREPEATPATTERNDIM, kRepeatDim);
  set(TIFFTAG_CFAPATTERN, 4, pattern);
  set(TIFFTAG_CFAPLANECOLOR, 3, kPlaneColor);
  set(TIFFTAG_CFALAYOUT, kRectangularLayout);
  set(TIFFTAG_BLACKLEVELREPEATDIM, kRepeatDim);
  set(TIFFTAG_BLACKLEVEL, 4, black);
  set(TIFFTAG_WHITELEVEL, 1, &white);
  set(TIFFTAG_COLORMATRIX1, 9, kIdentity);
  set(TIFFTAG_CALIBRATIONILLUMINANT1, kD65);
  set(TIFFTAG_ASSHOTNEUTRAL, 3, kNeutral);
  if (exif_offset != 0) set(TIFFTAG_EXIFIFD, exif_offset);
  return ok;
}

bool write_pixels(TIFF* tiff, const cv::Mat& mosaic) {
  // A copy per row: TIFFWriteScanline may modify the buffer it is given.
  std::vector<std::uint16_t> row(static_cast<std::size_t>(mosaic.cols));
  for (int y = 0; y < mosaic.rows; ++y) {
    const auto* source = mosaic.ptr<std::uint16_t>(y);
    std::copy(source, source + mosaic.cols, row.begin());
    if (TIFFWriteScanline(tiff, row.data(), static_cast<std::uint32_t>(y), 0) != 1) return false;
  }
  return true;
}

}  // namespace

void write_dng(const std::filesystem::path& path, const DngShot& shot) {
  check_shot(path, shot);
  const std::filesystem::path temporary_path = temporary_sibling(path);
  TiffFile file;
  TiffHandle tiff = create_tiff(temporary_path, path, file);
  TemporaryFile temporary(temporary_path);
  std::uint64_t exif_offset = 0;
  const bool ok = (!has_exif(shot) || write_exif_ifd(tiff.get(), shot, exif_offset)) &&
                  set_image_tags(tiff.get(), shot, exif_offset) && write_pixels(tiff.get(), shot.mosaic) &&
                  TIFFWriteDirectory(tiff.get()) == 1;
  // Closing writes nothing more (the directory is written) but can still fail.
  tiff.reset();
  if (!ok || file.io_error != 0 || !file.tiff_error.empty()) {
    fail("{}: cannot write: {}", path.string(), failure(file));
  }
  std::error_code error;
  std::filesystem::rename(temporary.path(), path, error);
  if (error) fail("{}: cannot write: {}", path.string(), error.message());
  temporary.committed();
}

}  // namespace lightstage::sim
