# Build switches. Hardware backends default to AUTO: built when the library is
# found, skipped (with a message) when not, so a machine without any of them builds.
set(LIGHTSTAGE_BACKEND_CHOICES AUTO ON OFF)
foreach(backend GPIOD LIBCAMERA LIBUSB V4L2 GPHOTO2 ARAVIS)
  set(LIGHTSTAGE_WITH_${backend} AUTO CACHE STRING "Build the ${backend} backend (AUTO, ON, OFF)")
  set_property(CACHE LIGHTSTAGE_WITH_${backend} PROPERTY STRINGS ${LIGHTSTAGE_BACKEND_CHOICES})
endforeach()

set(LIGHTSTAGE_WITH_PYTHON AUTO CACHE STRING "Build the Python module (AUTO, ON, OFF; never in sanitizer or fuzz builds)")
set_property(CACHE LIGHTSTAGE_WITH_PYTHON PROPERTY STRINGS ${LIGHTSTAGE_BACKEND_CHOICES})

# The controller board's part only: common/, hw/, firmware/ and their tests, the
# lightstage-domed and lightstage-rigs packages (the arm64 cross build).
option(LIGHTSTAGE_CONTROLLER_ONLY "Build only what runs on the dome controller" OFF)
# Shared libraries instead of static ones (programs, tests and the Python
# module then load them; the installed programs from ../lib/<multiarch>).
option(LIGHTSTAGE_SHARED_LIBS "Build the libraries as shared libraries" OFF)
if(LIGHTSTAGE_SHARED_LIBS)
  set(LIGHTSTAGE_LIBRARY_TYPE SHARED)
  set(CMAKE_INSTALL_RPATH "$ORIGIN/../${CMAKE_INSTALL_LIBDIR}")
else()
  set(LIGHTSTAGE_LIBRARY_TYPE STATIC)
endif()
option(LIGHTSTAGE_BUILD_TESTS "Build the tests" ON)
option(LIGHTSTAGE_BUILD_BENCHMARKS "Build the benchmarks" ON)
option(LIGHTSTAGE_SANITIZE "Build with AddressSanitizer and UndefinedBehaviorSanitizer" OFF)
option(LIGHTSTAGE_FUZZ "Build libFuzzer targets (needs clang)" OFF)
option(LIGHTSTAGE_WERROR "Treat warnings as errors" ON)
# Compiles each library's and program's sources a few at a time in one unit, so
# the heavy headers (Eigen, OpenCV, CLI11, JSON) are parsed once per batch.
# scripts/build.sh turns it on (whole-tree builds); an edit-compile loop, which
# recompiles one file, is faster without it.
option(LIGHTSTAGE_UNITY_BUILD "Batch each library's and program's sources into unity units" OFF)

# lld links in a quarter of GNU ld's time, and a build links over a hundred test
# programs. The cross build keeps its toolchain's linker.
if(NOT CMAKE_CROSSCOMPILING)
  find_program(LIGHTSTAGE_LLD ld.lld)
  if(LIGHTSTAGE_LLD)
    add_link_options(-fuse-ld=lld)
  endif()
endif()

set(LIGHTSTAGE_WARNINGS -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast
    -Wcast-align -Woverloaded-virtual -Wimplicit-fallthrough)
if(LIGHTSTAGE_WERROR)
  list(APPEND LIGHTSTAGE_WARNINGS -Werror)
endif()

if(LIGHTSTAGE_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
  # GCC 12's flow analysis under ASan at -O1 reports libstdc++ internals (std::regex, std::function)
  # as maybe-uninitialized (GCC PR 105562); the release build keeps the warning as an error.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    add_compile_options(-Wno-maybe-uninitialized)
  endif()
endif()
if(LIGHTSTAGE_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "LIGHTSTAGE_FUZZ needs clang (CXX=clang++)")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()
