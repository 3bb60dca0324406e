# The report writer (host/src/report): its sources, and the viewer's web
# files (web/*.js, web/report.css) embedded into the binary at build time as a
# generated header, so a report needs nothing beside the program.
# Included from host/CMakeLists.txt after lightstage_library(lightstage_host).

set(LIGHTSTAGE_REPORT_WEB_FILES
  # ES modules, in dependency order: the embedder strips import lines and
  # export keywords and concatenates them into one inline module script.
  ${CMAKE_CURRENT_SOURCE_DIR}/src/report/web/shading.js
  ${CMAKE_CURRENT_SOURCE_DIR}/src/report/web/hemisphere.js
  ${CMAKE_CURRENT_SOURCE_DIR}/src/report/web/viewer.js)
set(LIGHTSTAGE_REPORT_CSS ${CMAKE_CURRENT_SOURCE_DIR}/src/report/web/report.css)
set(LIGHTSTAGE_REPORT_GENERATED ${CMAKE_CURRENT_BINARY_DIR}/generated/report_web_assets.hpp)

add_custom_command(
  OUTPUT ${LIGHTSTAGE_REPORT_GENERATED}
  COMMAND ${CMAKE_COMMAND} -DOUT=${LIGHTSTAGE_REPORT_GENERATED} "-DSCRIPTS=${LIGHTSTAGE_REPORT_WEB_FILES}"
          -DCSS=${LIGHTSTAGE_REPORT_CSS} -P ${CMAKE_CURRENT_SOURCE_DIR}/src/report/embed_web.cmake
  DEPENDS ${LIGHTSTAGE_REPORT_WEB_FILES} ${LIGHTSTAGE_REPORT_CSS} ${CMAKE_CURRENT_SOURCE_DIR}/src/report/embed_web.cmake
  COMMENT "Embedding the report viewer's JavaScript and CSS"
  VERBATIM)

target_sources(lightstage_host PRIVATE
  src/report/html.cpp
  src/report/maps.cpp
  src/report/overview.cpp
  src/report/deep_zoom.cpp  # Deep Zoom pyramids of pictures too large for a page
  src/report/result_maps.cpp
  src/report/svg.cpp
  src/report/light_statistics.cpp
  src/report/viewer_data.cpp
  src/report/report.cpp
  ${LIGHTSTAGE_REPORT_GENERATED})
target_include_directories(lightstage_host PRIVATE ${CMAKE_CURRENT_BINARY_DIR}/generated)
target_link_libraries(lightstage_host PRIVATE ZLIB::ZLIB)
