#pragma once
// RTI exchange files: PTM 1.2 (LRGB and RGB) and HSH `.rti` (orders 2, 3).
// Layouts and their sources: docs/rti-formats.md. Coefficients are quantised
// to bytes on writing, so a round trip is exact to within one quantisation
// step per coefficient.

#include "lightstage/host/reflectance/rti_basis.hpp"

#include <Eigen/Core>

#include <array>
#include <filesystem>
#include <string>

namespace lightstage::io {

// The largest width or height an RTI file or relight folder may declare.
inline constexpr int kMaxRtiSide = 16'384;

// A fitted RTI in memory: per colour channel (r, g, b) a pixels × terms
// matrix, pixels row-major with row 0 the top of the image.
struct RtiImage {
  RtiBasis basis = RtiBasis::ptm;
  int width = 0;
  int height = 0;
  std::array<Eigen::MatrixXf, 3> channels;
};

// One colour per pixel and one luminance model, channel c ≈ lum · rgb(c)
// (PTM_FORMAT_LRGB, relight's lrgb): rgb is each channel's share at the light
// overhead with the brightest channel at 1, and lum carries the rest. Exact
// where a pixel's chromaticity does not change with the light.
struct LrgbSplit {
  Eigen::MatrixXf lum;   // pixels × terms
  Eigen::MatrixX3f rgb;  // pixels × 3, in [0, 1]
};
LrgbSplit split_lrgb(const RtiImage& image);

enum class PtmFormat { lrgb, rgb };

// PTM_FORMAT_LRGB stores one luminance polynomial and a colour per pixel: the
// channels are taken as L(l) · rgb, with rgb the pixel's colour at the light
// overhead (exact when a pixel's chromaticity does not change with the light).
std::string format_ptm(const RtiImage& image, PtmFormat format);
void write_ptm(const std::filesystem::path& path, const RtiImage& image, PtmFormat format);
// Throws InputError "source: field: ..." for a bad header or short data.
RtiImage parse_ptm(const std::string& bytes, const std::string& source);
RtiImage read_ptm(const std::filesystem::path& path);

std::string format_hsh(const RtiImage& image);
void write_hsh(const std::filesystem::path& path, const RtiImage& image);
RtiImage parse_hsh(const std::string& bytes, const std::string& source);
RtiImage read_hsh(const std::filesystem::path& path);

}  // namespace lightstage::io
