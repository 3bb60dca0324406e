// Wavefront OBJ meshes (written only: PLY is the format we read).
#include "lightstage/common/error.hpp"
#include "lightstage/host/surface/mesh.hpp"
#include "util/atomic_file.hpp"

#include <fmt/format.h>

namespace lightstage::surface {

void write_obj(const std::filesystem::path& path, const Mesh& mesh) {
  const bool normals = mesh.normals.size() == mesh.vertices.size() && !mesh.vertices.empty();
  const bool colours = mesh.colours.size() == mesh.vertices.size() && !mesh.vertices.empty();
  std::string out = "# lightstage surface\n";
  out.reserve(mesh.vertices.size() * 80 + mesh.triangles.size() * 40);
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const auto& v = mesh.vertices[i];
    if (colours) {
      const auto& c = mesh.colours[i];
      fmt::format_to(std::back_inserter(out), "v {} {} {} {:.4f} {:.4f} {:.4f}\n", v.x(), v.y(), v.z(),
                     c[0] / 255.0, c[1] / 255.0, c[2] / 255.0);
    } else {
      fmt::format_to(std::back_inserter(out), "v {} {} {}\n", v.x(), v.y(), v.z());
    }
  }
  if (normals)
    for (const auto& n : mesh.normals)
      fmt::format_to(std::back_inserter(out), "vn {} {} {}\n", n.x(), n.y(), n.z());
  for (const auto& t : mesh.triangles) {
    // OBJ indices start at 1.
    if (normals)
      fmt::format_to(std::back_inserter(out), "f {0}//{0} {1}//{1} {2}//{2}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    else
      fmt::format_to(std::back_inserter(out), "f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
  }
  util::write_text_atomic(path, out);
}

}  // namespace lightstage::surface
