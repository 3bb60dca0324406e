# Every dependency comes from a Debian 12 package; scripts/install-deps.sh installs them.
# What the controller's part (common/, hw/, firmware/) needs.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(yaml-cpp REQUIRED)
find_package(CLI11 REQUIRED)
find_package(fmt REQUIRED)
find_package(spdlog REQUIRED)
find_package(Threads REQUIRED)
find_package(PkgConfig)
if(LIGHTSTAGE_CONTROLLER_ONLY)
  set(LIGHTSTAGE_OPENCV_COMPONENTS core)
else()
  # Not imgcodecs (tests/CMakeLists.txt finds it for the tests that make or
  # check image files): it loads some 80 more libraries through GDAL, so the
  # programs read and write images with libpng, libjpeg, libtiff and OpenEXR.
  set(LIGHTSTAGE_OPENCV_COMPONENTS photo imgproc core)  # in link order
endif()
find_package(OpenCVModules REQUIRED COMPONENTS ${LIGHTSTAGE_OPENCV_COMPONENTS})
if(NOT LIGHTSTAGE_CONTROLLER_ONLY)
  find_package(nlohmann_json 3.10 REQUIRED)
  # EXR images through OpenEXR itself (libopenexr-dev; OpenEXR 3.1 on Debian 12).
  find_package(OpenEXR 3.1 CONFIG REQUIRED)
  # Camera files: RAW through LibRaw (its thread-safe libraw_r), TIFF and DNG
  # through libtiff, EXIF through exiv2.
  find_package(TIFF 4.5 REQUIRED)
  # PNG rows a band at a time (io/row_reader.hpp): libpng itself, not OpenCV's whole-image decoder.
  find_package(PNG 1.6 REQUIRED)
  # Camera JPEGs and JPEG tiles, planes: libjpeg-turbo (its BGR colour space).
  find_package(JPEG 62 REQUIRED)
  pkg_check_modules(LIBRAW REQUIRED IMPORTED_TARGET libraw_r>=0.20)
  # Its pkg-config file adds -I.../libraw and -fopenmp to every compile of the
  # library that links it; <libraw/libraw.h> needs neither.
  set_target_properties(PkgConfig::LIBRAW PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "" INTERFACE_COMPILE_OPTIONS "")
  pkg_check_modules(EXIV2 REQUIRED IMPORTED_TARGET exiv2>=0.27.4)
  # The operator's station (host/station): Debian's cpp-httplib, a compiled library with its own defines.
  pkg_check_modules(HTTPLIB REQUIRED IMPORTED_TARGET cpp-httplib>=0.11)
endif()

# Optional hardware backends: AUTO builds what is found.
function(lightstage_optional_backend var found_var description)
  if(LIGHTSTAGE_WITH_${var} STREQUAL "OFF")
    set(LIGHTSTAGE_HAVE_${var} OFF PARENT_SCOPE)
    message(STATUS "Lightstage: ${description} backend switched off")
  elseif(${found_var})
    set(LIGHTSTAGE_HAVE_${var} ON PARENT_SCOPE)
    message(STATUS "Lightstage: ${description} backend enabled")
  elseif(LIGHTSTAGE_WITH_${var} STREQUAL "ON")
    message(FATAL_ERROR "Lightstage: ${description} backend requested but not found")
  else()
    set(LIGHTSTAGE_HAVE_${var} OFF PARENT_SCOPE)
    message(STATUS "Lightstage: ${description} backend not found, skipped")
  endif()
endfunction()

# The pkg-config modules (also what packaging/library.cmake's consumers need).
set(LIGHTSTAGE_GPIOD_MODULE libgpiodcxx>=1.6)
set(LIGHTSTAGE_LIBCAMERA_MODULE libcamera)
set(LIGHTSTAGE_LIBUSB_MODULE libusb-1.0)
# Camera backends of the host only: the arm64 controller build finds no arm64
# .pc files for them (install-deps.sh installs none) and skips them.
set(LIGHTSTAGE_GPHOTO2_MODULE libgphoto2>=2.5.10)  # gp_camera_get_single_config
set(LIGHTSTAGE_ARAVIS_MODULE aravis-0.8)
if(PkgConfig_FOUND)
  pkg_check_modules(LIBGPIOD IMPORTED_TARGET ${LIGHTSTAGE_GPIOD_MODULE})
  pkg_check_modules(LIBCAMERA IMPORTED_TARGET ${LIGHTSTAGE_LIBCAMERA_MODULE})
  pkg_check_modules(LIBUSB IMPORTED_TARGET ${LIGHTSTAGE_LIBUSB_MODULE})
  pkg_check_modules(GPHOTO2 IMPORTED_TARGET ${LIGHTSTAGE_GPHOTO2_MODULE})
  pkg_check_modules(ARAVIS IMPORTED_TARGET ${LIGHTSTAGE_ARAVIS_MODULE})
endif()
include(CheckIncludeFileCXX)
check_include_file_cxx(linux/videodev2.h HAVE_VIDEODEV2_H)

lightstage_optional_backend(GPIOD LIBGPIOD_FOUND "libgpiod")
lightstage_optional_backend(LIBCAMERA LIBCAMERA_FOUND "libcamera")
lightstage_optional_backend(LIBUSB LIBUSB_FOUND "libusb")
lightstage_optional_backend(GPHOTO2 GPHOTO2_FOUND "libgphoto2")
lightstage_optional_backend(ARAVIS ARAVIS_FOUND "aravis")
lightstage_optional_backend(V4L2 HAVE_VIDEODEV2_H "V4L2")

if(LIGHTSTAGE_BUILD_TESTS OR LIGHTSTAGE_BUILD_BENCHMARKS)
  find_package(GTest REQUIRED)
  include(GoogleTest)
endif()
if(LIGHTSTAGE_BUILD_BENCHMARKS AND NOT LIGHTSTAGE_CONTROLLER_ONLY)
  find_package(benchmark REQUIRED)
endif()

# The wire protocol: protobuf messages (libprotobuf-dev, protobuf-compiler) and zlib's CRC-32.
find_package(Protobuf 3.12 REQUIRED)
find_package(ZLIB REQUIRED)

# The Python module (host/python): pybind11 and a Python whose numpy it can
# import. Not in sanitizer or fuzz builds: an instrumented module cannot load
# into an uninstrumented interpreter.
set(LIGHTSTAGE_HAVE_PYTHON OFF)
if(NOT LIGHTSTAGE_WITH_PYTHON STREQUAL "OFF" AND NOT LIGHTSTAGE_SANITIZE AND NOT LIGHTSTAGE_FUZZ
   AND NOT LIGHTSTAGE_CONTROLLER_ONLY)
  if(NOT Python3_EXECUTABLE)
    # The first python3 on PATH can be a private one without numpy (e.g. pyenv's);
    # Debian's own interpreter is where python3-numpy installs.
    find_program(LIGHTSTAGE_PATH_PYTHON NAMES python3)
    if(LIGHTSTAGE_PATH_PYTHON)
      execute_process(COMMAND ${LIGHTSTAGE_PATH_PYTHON} -c "import numpy" RESULT_VARIABLE _no_numpy
                      OUTPUT_QUIET ERROR_QUIET)
    endif()
    if((NOT LIGHTSTAGE_PATH_PYTHON OR _no_numpy) AND EXISTS /usr/bin/python3)
      set(Python3_EXECUTABLE /usr/bin/python3 CACHE FILEPATH "Python for the lightstage module")
    endif()
  endif()
  find_package(Python3 3.9 COMPONENTS Interpreter Development.Module NumPy)
  if(Python3_FOUND)
    find_package(pybind11 2.6 CONFIG)
  endif()
endif()
if(NOT LIGHTSTAGE_CONTROLLER_ONLY)
  lightstage_optional_backend(PYTHON pybind11_FOUND "Python module (pybind11, numpy)")
endif()
