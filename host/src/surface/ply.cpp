// PLY meshes: the binary writer and a reader for the three encodings.
#include "lightstage/common/error.hpp"
#include "lightstage/host/surface/mesh.hpp"
#include "util/atomic_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>

namespace lightstage::surface {
namespace {

template <typename T>
void put(std::string& out, T value) {
  if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    std::reverse(bytes, bytes + sizeof(T));
    out.append(bytes, sizeof(T));
  } else {
    out.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
}

enum class Scalar { kI8, kU8, kI16, kU16, kI32, kU32, kF32, kF64 };

std::optional<Scalar> scalar_of(const std::string& name) {
  if (name == "char" || name == "int8") return Scalar::kI8;
  if (name == "uchar" || name == "uint8") return Scalar::kU8;
  if (name == "short" || name == "int16") return Scalar::kI16;
  if (name == "ushort" || name == "uint16") return Scalar::kU16;
  if (name == "int" || name == "int32") return Scalar::kI32;
  if (name == "uint" || name == "uint32") return Scalar::kU32;
  if (name == "float" || name == "float32") return Scalar::kF32;
  if (name == "double" || name == "float64") return Scalar::kF64;
  return std::nullopt;
}

std::size_t size_of(Scalar s) {
  switch (s) {
    case Scalar::kI8:
    case Scalar::kU8:
      return 1;
    case Scalar::kI16:
    case Scalar::kU16:
      return 2;
    case Scalar::kI32:
    case Scalar::kU32:
    case Scalar::kF32:
      return 4;
    case Scalar::kF64:
      return 8;
  }
  return 1;
}

struct Property {
  std::string name;
  Scalar type = Scalar::kF32;
  bool list = false;
  Scalar count_type = Scalar::kU8;
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
};

enum class Encoding { kAscii, kLittle, kBig };

// Reads scalars from the body in the file's encoding.
class Body {
 public:
  Body(const std::string& bytes, std::size_t pos, Encoding encoding, const std::string& source)
      : bytes_(bytes), pos_(pos), encoding_(encoding), source_(source) {}

  double read(Scalar type, const char* what) {
    if (encoding_ == Encoding::kAscii) return read_ascii(type, what);
    const std::size_t n = size_of(type);
    if (bytes_.size() - pos_ < n) fail("{}: PLY data ends early (reading {})", source_, what);
    char raw[8];
    std::memcpy(raw, bytes_.data() + pos_, n);
    pos_ += n;
    const bool swap = (encoding_ == Encoding::kBig) != (std::endian::native == std::endian::big);
    if (swap) std::reverse(raw, raw + n);
    switch (type) {
      case Scalar::kI8:
        return static_cast<double>(static_cast<std::int8_t>(raw[0]));
      case Scalar::kU8:
        return static_cast<double>(static_cast<std::uint8_t>(raw[0]));
      case Scalar::kI16:
        return from<std::int16_t>(raw);
      case Scalar::kU16:
        return from<std::uint16_t>(raw);
      case Scalar::kI32:
        return from<std::int32_t>(raw);
      case Scalar::kU32:
        return from<std::uint32_t>(raw);
      case Scalar::kF32:
        return from<float>(raw);
      case Scalar::kF64:
        return from<double>(raw);
    }
    return 0;
  }

  std::size_t remaining() const { return bytes_.size() - pos_; }

 private:
  template <typename T>
  static double from(const char* raw) {
    T v;
    std::memcpy(&v, raw, sizeof(T));
    return static_cast<double>(v);
  }

  double read_ascii(Scalar type, const char* what) {
    while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
    std::size_t end = pos_;
    while (end < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[end]))) ++end;
    if (end == pos_) fail("{}: PLY data ends early (reading {})", source_, what);
    double v = 0;
    const auto [next, error] = std::from_chars(bytes_.data() + pos_, bytes_.data() + end, v);
    if (error != std::errc() || next != bytes_.data() + end)
      fail("{}: PLY {}: '{}' is not a number", source_, what,
           bytes_.substr(pos_, std::min<std::size_t>(end - pos_, 40)));
    if (type != Scalar::kF32 && type != Scalar::kF64 && v != std::floor(v))
      fail("{}: PLY {}: '{}' is not an integer", source_, what,
           bytes_.substr(pos_, std::min<std::size_t>(end - pos_, 40)));
    pos_ = end;
    return v;
  }

  const std::string& bytes_;
  std::size_t pos_;
  Encoding encoding_;
  const std::string& source_;
};

}  // namespace

void write_ply(const std::filesystem::path& path, const Mesh& mesh) {
  const bool normals = mesh.normals.size() == mesh.vertices.size() && !mesh.vertices.empty();
  const bool colours = mesh.colours.size() == mesh.vertices.size() && !mesh.vertices.empty();
  std::string out = fmt::format(
      "ply\nformat binary_little_endian 1.0\ncomment lightstage surface\n"
      "element vertex {}\nproperty float x\nproperty float y\nproperty float z\n",
      mesh.vertices.size());
  if (normals) out += "property float nx\nproperty float ny\nproperty float nz\n";
  if (colours) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out += fmt::format("element face {}\nproperty list uchar int vertex_indices\nend_header\n",
                     mesh.triangles.size());
  out.reserve(out.size() + mesh.vertices.size() * 27 + mesh.triangles.size() * 13);
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) put(out, mesh.vertices[i][k]);
    if (normals)
      for (int k = 0; k < 3; ++k) put(out, mesh.normals[i][k]);
    if (colours)
      for (int k = 0; k < 3; ++k) put(out, mesh.colours[i][static_cast<std::size_t>(k)]);
  }
  for (const auto& t : mesh.triangles) {
    put(out, static_cast<std::uint8_t>(3));
    for (const std::int32_t i : t) put(out, i);
  }
  const auto tmp = temporary_sibling(path);
  {
    std::ofstream file(tmp, std::ios::binary | std::ios::trunc);
    file.write(out.data(), static_cast<std::streamsize>(out.size()));
    if (!file) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      fail("{}: cannot write the PLY mesh", path.string());
    }
  }
  util::commit_temporary(tmp, path);
}

Mesh parse_ply(const std::string& bytes, const std::string& source) {
  // Header: lines up to "end_header".
  std::size_t pos = 0;
  auto next_line = [&]() -> std::optional<std::string> {
    if (pos >= bytes.size()) return std::nullopt;
    const std::size_t nl = bytes.find('\n', pos);
    const std::size_t end = nl == std::string::npos ? bytes.size() : nl;
    std::string line = bytes.substr(pos, end - pos);
    pos = nl == std::string::npos ? bytes.size() : nl + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return line;
  };
  const auto magic = next_line();
  if (!magic || *magic != "ply") fail("{}: not a PLY file (no 'ply' on the first line)", source);
  std::optional<Encoding> encoding;
  std::vector<Element> elements;
  bool ended = false;
  for (int line_no = 2; !ended; ++line_no) {
    const auto line = next_line();
    if (!line) fail("{}: PLY header has no 'end_header'", source);
    if (line_no > 10000) fail("{}: PLY header is too long", source);
    std::istringstream words(*line);
    std::string keyword;
    words >> keyword;
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") {
      ended = true;
    } else if (keyword == "format") {
      std::string name, version;
      words >> name >> version;
      if (name == "ascii")
        encoding = Encoding::kAscii;
      else if (name == "binary_little_endian")
        encoding = Encoding::kLittle;
      else if (name == "binary_big_endian")
        encoding = Encoding::kBig;
      else
        fail("{}: PLY header line {}: unknown format '{}'", source, line_no, name.substr(0, 40));
      if (version != "1.0")
        fail("{}: PLY header line {}: unsupported version '{}'", source, line_no, version.substr(0, 40));
    } else if (keyword == "element") {
      Element e;
      std::string count;
      words >> e.name >> count;
      std::uint64_t n = 0;
      const auto [next, error] = std::from_chars(count.data(), count.data() + count.size(), n);
      if (e.name.empty() || error != std::errc() || next != count.data() + count.size())
        fail("{}: PLY header line {}: expected 'element NAME COUNT'", source, line_no);
      e.count = n;
      elements.push_back(std::move(e));
    } else if (keyword == "property") {
      if (elements.empty()) fail("{}: PLY header line {}: property before any element", source, line_no);
      Property p;
      std::string type;
      words >> type;
      if (type == "list") {
        std::string count_type, item_type;
        words >> count_type >> item_type >> p.name;
        const auto ct = scalar_of(count_type), it = scalar_of(item_type);
        if (!ct || !it || p.name.empty())
          fail("{}: PLY header line {}: expected 'property list COUNT_TYPE ITEM_TYPE NAME'", source, line_no);
        if (*ct == Scalar::kF32 || *ct == Scalar::kF64)
          fail("{}: PLY header line {}: a list count must be an integer type", source, line_no);
        p.list = true;
        p.count_type = *ct;
        p.type = *it;
      } else {
        const auto t = scalar_of(type);
        words >> p.name;
        if (!t || p.name.empty())
          fail("{}: PLY header line {}: expected 'property TYPE NAME'", source, line_no);
        p.type = *t;
      }
      elements.back().properties.push_back(p);
    } else {
      fail("{}: PLY header line {}: unknown keyword '{}'", source, line_no, keyword.substr(0, 40));
    }
  }
  if (!encoding) fail("{}: PLY header has no 'format' line", source);
  const Element* vertex_element = nullptr;
  for (const auto& e : elements)
    if (e.name == "vertex") vertex_element = &e;
  if (!vertex_element) fail("{}: PLY has no 'vertex' element", source);
  auto find = [](const Element& e, const char* name) -> int {
    for (std::size_t i = 0; i < e.properties.size(); ++i)
      if (e.properties[i].name == name && !e.properties[i].list) return static_cast<int>(i);
    return -1;
  };
  const int ix = find(*vertex_element, "x"), iy = find(*vertex_element, "y"), iz = find(*vertex_element, "z");
  if (ix < 0 || iy < 0 || iz < 0) fail("{}: PLY vertex element lacks x, y or z", source);
  const int inx = find(*vertex_element, "nx"), iny = find(*vertex_element, "ny"),
            inz = find(*vertex_element, "nz");
  const int ir = find(*vertex_element, "red"), ig = find(*vertex_element, "green"),
            ib = find(*vertex_element, "blue");
  const bool has_normals = inx >= 0 && iny >= 0 && inz >= 0;
  const bool has_colours = ir >= 0 && ig >= 0 && ib >= 0;

  Body body(bytes, pos, *encoding, source);
  Mesh mesh;
  std::vector<double> values;
  for (const Element& e : elements) {
    // Every item takes at least one byte (binary) or two characters (ASCII):
    // a count beyond that cannot be honest, and must not drive allocations.
    if (e.properties.empty()) continue;  // items without properties take no bytes: nothing to read
    if (e.count > body.remaining())
      fail("{}: PLY element '{}' claims {} items but the file is too short", source, e.name.substr(0, 40),
           e.count);
    const bool is_vertex = &e == vertex_element;
    const bool is_face = e.name == "face";
    if (is_vertex) mesh.vertices.reserve(e.count);
    for (std::uint64_t item = 0; item < e.count; ++item) {
      values.assign(e.properties.size(), 0.0);
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        const Property& p = e.properties[k];
        if (!p.list) {
          values[k] = body.read(p.type, "value");
          continue;
        }
        const double count = body.read(p.count_type, "list count");
        if (count < 0 || count > 1e6)
          fail("{}: PLY {} {}: bad list length {}", source, e.name.substr(0, 40), item, count);
        std::vector<std::int64_t> list;
        for (int j = 0; j < static_cast<int>(count); ++j) {
          const double v = body.read(p.type, "list item");
          list.push_back(std::isfinite(v) ? static_cast<std::int64_t>(std::clamp(v, -1e18, 1e18)) : -1);
        }
        if (is_face && (p.name == "vertex_indices" || p.name == "vertex_index")) {
          if (list.size() < 3)
            fail("{}: PLY face {} has {} vertices (needs 3 or more)", source, item, list.size());
          for (const std::int64_t v : list)
            if (v < 0 || static_cast<std::uint64_t>(v) >= vertex_element->count)
              fail("{}: PLY face {} refers to vertex {} of {}", source, item, v, vertex_element->count);
          for (std::size_t j = 1; j + 1 < list.size(); ++j)
            mesh.triangles.push_back({static_cast<std::int32_t>(list[0]), static_cast<std::int32_t>(list[j]),
                                      static_cast<std::int32_t>(list[j + 1])});
        }
      }
      if (is_vertex) {
        const Eigen::Vector3d p(values[static_cast<std::size_t>(ix)], values[static_cast<std::size_t>(iy)],
                                values[static_cast<std::size_t>(iz)]);
        if (!p.allFinite()) fail("{}: PLY vertex {} is not finite", source, item);
        mesh.vertices.push_back(p.cast<float>());
        if (has_normals)
          mesh.normals.emplace_back(static_cast<float>(values[static_cast<std::size_t>(inx)]),
                                    static_cast<float>(values[static_cast<std::size_t>(iny)]),
                                    static_cast<float>(values[static_cast<std::size_t>(inz)]));
        if (has_colours) {
          auto byte = [&](int i) {
            const double v = values[static_cast<std::size_t>(i)];
            return static_cast<std::uint8_t>(std::isfinite(v) ? std::clamp(v, 0.0, 255.0) : 0.0);
          };
          mesh.colours.push_back({byte(ir), byte(ig), byte(ib)});
        }
      }
    }
  }
  return mesh;
}

Mesh read_ply(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("{}: cannot open the PLY file", path.string());
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return parse_ply(bytes.str(), path.string());
}

}  // namespace lightstage::surface
