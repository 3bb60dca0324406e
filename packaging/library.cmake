# The host library for other programs: headers, libraries, an exported CMake
# package (find_package(Lightstage) → Lightstage::pipeline, Lightstage::host, ...)
# and a pkg-config file (lightstage.pc), in install component devel (Debian
# package liblightstage-dev); with LIGHTSTAGE_SHARED_LIBS the shared libraries
# themselves in component libs. Included from packaging/CMakeLists.txt, after
# every library is defined.

# In link order: each needs only those after it.
set(LIGHTSTAGE_EXPORTED_LIBRARIES
    lightstage_station lightstage_pipeline lightstage_host lightstage_sim_camera_client lightstage_sim lightstage_firmware
    lightstage_hw lightstage_sim_gpio lightstage_protocol lightstage_protocol_messages lightstage_common)
set(exported)  # those this build has (a controller-only build has no host)
foreach(library ${LIGHTSTAGE_EXPORTED_LIBRARIES})
  if(TARGET ${library})
    list(APPEND exported ${library})
  endif()
endforeach()
set(LIGHTSTAGE_EXPORTED_LIBRARIES ${exported})

set(config_dir ${CMAKE_INSTALL_LIBDIR}/cmake/Lightstage)
foreach(library ${LIGHTSTAGE_EXPORTED_LIBRARIES})
  string(REGEX REPLACE "^lightstage_" "" export_name ${library})
  set_target_properties(${library} PROPERTIES EXPORT_NAME ${export_name})
  install(TARGETS ${library} EXPORT LightstageTargets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT devel
          LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT libs NAMELINK_COMPONENT devel)
  # A stripped install (cpack, `cmake --install --strip`) drops the archives'
  # debug information too (most of a RelWithDebInfo archive), keeping their symbols.
  if(NOT LIGHTSTAGE_SHARED_LIBS AND CMAKE_STRIP)
    install(CODE "if(CMAKE_INSTALL_DO_STRIP)
        execute_process(COMMAND \"${CMAKE_STRIP}\" --strip-debug
          \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_LIBDIR}/$<TARGET_FILE_NAME:${library}>\"
          COMMAND_ERROR_IS_FATAL ANY)
      endif()" COMPONENT devel)
  endif()
  foreach(property LIGHTSTAGE_HEADER_DIR LIGHTSTAGE_GENERATED_HEADER_DIR)
    get_target_property(headers ${library} ${property})
    if(headers)
      install(DIRECTORY ${headers}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT devel
              FILES_MATCHING PATTERN "*.hpp" PATTERN "*.h")
    endif()
  endforeach()
endforeach()
install(EXPORT LightstageTargets NAMESPACE Lightstage:: DESTINATION ${config_dir} COMPONENT devel)

include(CMakePackageConfigHelpers)
# The dependencies the config file finds again for the consumer: what this
# build found (backends, the host's libraries).
set(LIGHTSTAGE_CONFIG_HOST OFF)
if(TARGET lightstage_host)
  set(LIGHTSTAGE_CONFIG_HOST ON)
endif()
configure_package_config_file(${CMAKE_CURRENT_SOURCE_DIR}/LightstageConfig.cmake.in
                              ${CMAKE_CURRENT_BINARY_DIR}/LightstageConfig.cmake INSTALL_DESTINATION ${config_dir})
# 0.x: a minor version may break the interface, so only the same minor matches.
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/LightstageConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/LightstageConfig.cmake
              ${CMAKE_CURRENT_BINARY_DIR}/LightstageConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/FindOpenCVModules.cmake
        DESTINATION ${config_dir} COMPONENT devel)

# lightstage.pc: the prefix relative to the file itself, so that a tree
# installed with `cmake --install --prefix` or unpacked elsewhere still works.
set(pc_dir ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
file(RELATIVE_PATH pc_to_prefix /prefix/${pc_dir} /prefix)
set(pc_requires eigen3 fmt spdlog yaml-cpp protobuf zlib)
if(LIGHTSTAGE_CONFIG_HOST)
  list(APPEND pc_requires nlohmann_json OpenEXR libpng16 libjpeg libtiff-4 "libraw_r >= 0.20" "exiv2 >= 0.27.4"
       "cpp-httplib >= 0.11")
endif()
foreach(backend GPIOD LIBCAMERA ARAVIS GPHOTO2 LIBUSB)
  if(LIGHTSTAGE_HAVE_${backend})
    string(REPLACE ">=" " >= " module "${LIGHTSTAGE_${backend}_MODULE}")  # pkg-config's spelling
    list(APPEND pc_requires ${module})
  endif()
endforeach()
set(pc_libs)
foreach(library ${LIGHTSTAGE_EXPORTED_LIBRARIES})
  list(APPEND pc_libs "-l$<TARGET_FILE_BASE_NAME:${library}>")
endforeach()
foreach(component ${LIGHTSTAGE_OPENCV_COMPONENTS})
  list(APPEND pc_libs -lopencv_${component})
endforeach()
list(APPEND pc_libs -pthread)
list(JOIN pc_requires ", " LIGHTSTAGE_PC_REQUIRES)
list(JOIN pc_libs " " LIGHTSTAGE_PC_LIBS)
configure_file(${CMAKE_CURRENT_SOURCE_DIR}/lightstage.pc.in ${CMAKE_CURRENT_BINARY_DIR}/lightstage.pc.in.configured @ONLY)
file(GENERATE OUTPUT ${CMAKE_CURRENT_BINARY_DIR}/lightstage.pc INPUT ${CMAKE_CURRENT_BINARY_DIR}/lightstage.pc.in.configured)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/lightstage.pc DESTINATION ${pc_dir} COMPONENT devel)
