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

# The zoom page's OpenSeadragon (npm, web/zoom/package-lock.json), installed into the build tree.
find_program(LIGHTSTAGE_NPM npm)
if(NOT LIGHTSTAGE_NPM)
  message(FATAL_ERROR "The report's zoom page embeds OpenSeadragon from npm: run scripts/install-deps.sh")
endif()
set(LIGHTSTAGE_REPORT_ZOOM_WEB ${CMAKE_CURRENT_SOURCE_DIR}/src/report/web/zoom)
set(LIGHTSTAGE_REPORT_ZOOM_BUILD ${CMAKE_CURRENT_BINARY_DIR}/report-zoom)
add_custom_command(OUTPUT ${LIGHTSTAGE_REPORT_ZOOM_BUILD}/npm_ci.stamp
  COMMAND ${PROJECT_SOURCE_DIR}/cmake/npm_ci.sh ${LIGHTSTAGE_REPORT_ZOOM_WEB} ${LIGHTSTAGE_REPORT_ZOOM_BUILD}
  COMMAND ${CMAKE_COMMAND} -E touch ${LIGHTSTAGE_REPORT_ZOOM_BUILD}/npm_ci.stamp
  DEPENDS ${LIGHTSTAGE_REPORT_ZOOM_WEB}/package.json ${LIGHTSTAGE_REPORT_ZOOM_WEB}/package-lock.json
          ${PROJECT_SOURCE_DIR}/cmake/npm_ci.sh
  COMMENT "Installing the report zoom page's npm packages"
  VERBATIM)
set(LIGHTSTAGE_REPORT_ZOOM_SCRIPTS
  ${LIGHTSTAGE_REPORT_ZOOM_BUILD}/node_modules/openseadragon/build/openseadragon/openseadragon.min.js
  ${CMAKE_CURRENT_SOURCE_DIR}/src/report/web/zoom.js)
set(LIGHTSTAGE_REPORT_ZOOM_LICENSES ${LIGHTSTAGE_REPORT_ZOOM_BUILD}/node_modules/openseadragon/LICENSE.txt)

add_custom_command(
  OUTPUT ${LIGHTSTAGE_REPORT_GENERATED}
  COMMAND ${CMAKE_COMMAND} -DOUT=${LIGHTSTAGE_REPORT_GENERATED} "-DSCRIPTS=${LIGHTSTAGE_REPORT_WEB_FILES}"
          -DCSS=${LIGHTSTAGE_REPORT_CSS} "-DZOOM_SCRIPTS=${LIGHTSTAGE_REPORT_ZOOM_SCRIPTS}"
          "-DZOOM_LICENSES=${LIGHTSTAGE_REPORT_ZOOM_LICENSES}"
          -P ${CMAKE_CURRENT_SOURCE_DIR}/src/report/embed_web.cmake
  DEPENDS ${LIGHTSTAGE_REPORT_WEB_FILES} ${LIGHTSTAGE_REPORT_CSS} ${CMAKE_CURRENT_SOURCE_DIR}/src/report/embed_web.cmake
          ${LIGHTSTAGE_REPORT_ZOOM_BUILD}/npm_ci.stamp ${CMAKE_CURRENT_SOURCE_DIR}/src/report/web/zoom.js
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
