// report_render_reference RESULT_DIR X Y Z OUT.pfm
// Writes the C++ reference of what the report's viewer shows for the light
// (X, Y, Z): report::relight over the same files (viewer_data.hpp), as a float
// PFM (in colour for a colour result). The browser test compares the canvas with it when `lightstage relight`
// is not built.
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/report/viewer_data.hpp"

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 6) {
    std::cerr << "usage: report_render_reference RESULT_DIR X Y Z OUT.pfm\n";
    return 2;
  }
  try {
    const std::filesystem::path result = argv[1];
    std::vector<std::string> notes;
    lightstage::io::SolveFolderRows folder(result);
    const auto model = lightstage::report::load_surface_model(folder, 1 << 30, notes);
    const lightstage::Vec3 light(std::stod(argv[2]), std::stod(argv[3]), std::stod(argv[4]));
    lightstage::io::write_pfm(argv[5], model.chroma.empty()
                                           ? lightstage::report::relight(model, light)
                                           : lightstage::report::relight_colour(model, light));
  } catch (const std::exception& e) {
    std::cerr << "report_render_reference: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
