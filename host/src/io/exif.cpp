#include "lightstage/host/io/exif.hpp"

#include "io/ascii_text.hpp"
#include "lightstage/common/error.hpp"

#include <exiv2/exiv2.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <exception>
#include <mutex>
#include <system_error>

namespace lightstage::io {
namespace {

void initialise_exiv2() {
  static std::once_flag once;
  std::call_once(once, [] {
    Exiv2::LogMsg::setLevel(Exiv2::LogMsg::mute);  // failures reach the caller as InputError
    Exiv2::XmpParser::initialize();                // XMP needs it once; read_exif runs one file at a time
    Exiv2::enableBMFF(true);                       // CR3
  });
}

const Exiv2::Exifdatum* find(const Exiv2::ExifData& exif, const char* key) {
  const auto it = exif.findKey(Exiv2::ExifKey(key));
  return it == exif.end() || it->count() == 0 ? nullptr : &*it;
}

std::optional<double> positive_number(const Exiv2::ExifData& exif, const char* key) {
  const Exiv2::Exifdatum* datum = find(exif, key);
  if (datum == nullptr) return std::nullopt;
  double value = 0;
  if (datum->typeId() == Exiv2::unsignedRational || datum->typeId() == Exiv2::signedRational) {
    const Exiv2::Rational r = datum->toRational();
    if (r.second == 0) return std::nullopt;
    value = static_cast<double>(r.first) / r.second;
  } else {
    value = static_cast<double>(datum->toFloat());
  }
  if (!std::isfinite(value) || value <= 0) return std::nullopt;
  return value;
}

std::string text(const Exiv2::ExifData& exif, const char* key) {
  const Exiv2::Exifdatum* datum = find(exif, key);
  if (datum == nullptr) return {};
  return ascii_text(datum->toString());
}

// "YYYY:MM:DD HH:MM:SS" (+ sub-seconds) as "YYYY-MM-DDTHH:MM:SS[.fff]".
std::optional<std::string> taken(const Exiv2::ExifData& exif) {
  std::string when = text(exif, "Exif.Photo.DateTimeOriginal");
  if (when.size() != 19) return std::nullopt;
  for (std::size_t i = 0; i < when.size(); ++i) {
    const bool digit = std::isdigit(static_cast<unsigned char>(when[i])) != 0;
    const char separator = i == 4 || i == 7 ? ':' : i == 10 ? ' ' : i == 13 || i == 16 ? ':' : '0';
    if (separator == '0' ? !digit : when[i] != separator) return std::nullopt;
  }
  when[4] = '-';
  when[7] = '-';
  when[10] = 'T';
  const std::string subsec = text(exif, "Exif.Photo.SubSecTimeOriginal");
  if (!subsec.empty() && subsec.size() <= 9 &&
      std::all_of(subsec.begin(), subsec.end(), [](unsigned char c) { return std::isdigit(c) != 0; }))
    when += "." + subsec;
  return when;
}

}  // namespace

std::optional<ExifTime> taken_time(const ExifInfo& exif) {
  if (!exif.taken || exif.taken->size() < 19) return std::nullopt;
  const std::string& t = *exif.taken;  // "YYYY-MM-DDTHH:MM:SS[.fff]", digits checked when read
  const auto number = [&](std::size_t at, std::size_t digits) { return std::stoi(t.substr(at, digits)); };
  const std::chrono::year_month_day day{std::chrono::year(number(0, 4)),
                                        std::chrono::month(static_cast<unsigned>(number(5, 2))),
                                        std::chrono::day(static_cast<unsigned>(number(8, 2)))};
  const int hours = number(11, 2), minutes = number(14, 2), seconds = number(17, 2);
  // Years a camera clock can hold and nanoseconds since 1970 can count (int64 ends in 2262).
  if (!day.ok() || day.year() < std::chrono::year(1900) || day.year() > std::chrono::year(2261) ||
      hours > 23 || minutes > 59 || seconds > 60)
    return std::nullopt;
  const auto midnight = std::chrono::sys_days(day).time_since_epoch();
  ExifTime time;
  time.ns = std::chrono::duration_cast<std::chrono::nanoseconds>(midnight).count() +
            ((hours * 60LL + minutes) * 60 + seconds) * 1'000'000'000LL;
  time.resolution_ns = 1'000'000'000;
  if (t.size() > 20) {
    const std::string fraction = t.substr(20);  // 1..9 digits
    for (std::size_t i = 0; i < fraction.size(); ++i) time.resolution_ns /= 10;
    time.ns += std::stoll(fraction) * time.resolution_ns;
  }
  return time;
}

bool ExifInfo::empty() const {
  return make.empty() && model.empty() && !exposure_s && !iso && !f_number && !taken;
}

nlohmann::json ExifInfo::to_json() const {
  nlohmann::json out = nlohmann::json::object();
  if (!make.empty()) out["make"] = make;
  if (!model.empty()) out["model"] = model;
  if (exposure_s) out["exposure_s"] = *exposure_s;
  if (iso) out["iso"] = *iso;
  if (f_number) out["f_number"] = *f_number;
  if (taken) out["taken"] = *taken;
  return out;
}

cv::Mat turn_upright(const cv::Mat& image, int orientation) {
  cv::Mat out;
  switch (orientation) {
    case 2:
      cv::flip(image, out, 1);
      return out;  // mirrored left to right
    case 3:
      cv::flip(image, out, -1);
      return out;  // turned 180 degrees
    case 4:
      cv::flip(image, out, 0);
      return out;  // mirrored top to bottom
    case 5:
      cv::transpose(image, out);
      return out;
    case 6:  // turned 90 degrees clockwise to be upright
      cv::transpose(image, out);
      cv::flip(out, out, 1);
      return out;
    case 7:
      cv::transpose(image, out);
      cv::flip(out, out, -1);
      return out;
    case 8:  // turned 90 degrees anticlockwise to be upright
      cv::transpose(image, out);
      cv::flip(out, out, 0);
      return out;
    default:
      return image;
  }
}

ExifInfo read_exif(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) fail("{}: no such file", path.string());
  initialise_exiv2();
  ExifInfo info;
  try {
    auto image = Exiv2::ImageFactory::open(path.string());
    image->readMetadata();
    const Exiv2::ExifData& exif = image->exifData();
    info.make = text(exif, "Exif.Image.Make");
    info.model = text(exif, "Exif.Image.Model");
    info.exposure_s = positive_number(exif, "Exif.Photo.ExposureTime");
    info.iso = positive_number(exif, "Exif.Photo.ISOSpeedRatings");
    info.f_number = positive_number(exif, "Exif.Photo.FNumber");
    info.taken = taken(exif);
    if (const Exiv2::Exifdatum* datum = find(exif, "Exif.Image.Orientation")) {
#if EXIV2_TEST_VERSION(0, 28, 0)
      const std::int64_t value = datum->toInt64();  // toLong is gone from 0.28
#else
      const long value = datum->toLong();
#endif
      if (value >= 1 && value <= 8) info.orientation = static_cast<int>(value);
    }
  } catch (const std::exception& e) {
    fail("{}: cannot read its EXIF ({})", path.string(), e.what());
  }
  return info;
}

}  // namespace lightstage::io
