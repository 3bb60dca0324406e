#pragma once
// The web format of CNR-ISTI's relight (what relight.js / OpenLIME display):
// a folder with info.json and coefficient planes as 8-bit images,
// plane_0.jpg, plane_1.jpg, ... (three planes per image, in its R, G, B).
// Layout, term order, quantisation and sources: docs/rti-formats.md.
//   write_relight_web  an RtiImage -> the folder (PTM or HSH; rgb or lrgb)
//   parse_relight_info info.json text -> its fields, checked (outside input)
//   read_relight_web   the folder -> an RtiImage in our term order and units

#include "lightstage/host/io/rti_files.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace lightstage::io {

struct RelightWebOptions {
  std::string colorspace = "rgb";    // rgb: every term per channel; lrgb: one colour + luminance planes
  std::string image_format = "jpg";  // jpg (what relight's own loader reads) | png (lossless)
  int quality = 95;                  // JPEG quality, relight's default
  // Throws InputError naming the field.
  void check() const;
};

// info.json's fields that decoding needs.
struct RelightInfo {
  int width = 0;
  int height = 0;
  std::string type;        // ptm | hsh
  std::string colorspace;  // rgb | lrgb
  std::string format;      // jpg | png (absent in info.json = jpg)
  int nplanes = 0;
  RtiBasis basis = RtiBasis::ptm;   // hsh with 4 or 9 terms -> hsh2 / hsh3
  std::vector<double> scale, bias;  // per plane: a = (byte / 255 − bias) · scale
  int image_count() const { return (nplanes + 2) / 3; }
};

// Writes `dir` (created; must be absent or empty) and returns info.json as
// written. Throws InputError for a bad option or image, Error when a file
// cannot be written.
nlohmann::json write_relight_web(const std::filesystem::path& dir, const RtiImage& image,
                                 const RelightWebOptions& options = {});

// Throws InputError "source: field: ..." for text that is not such an
// info.json, or one we do not decode (types other than ptm / hsh, colour
// spaces other than rgb / lrgb, several materials).
RelightInfo parse_relight_info(const std::string& text, const std::string& source);

// Reads info.json and its planes. Throws InputError naming the file.
RtiImage read_relight_web(const std::filesystem::path& dir);

}  // namespace lightstage::io
