# Debian packages, one per install component (packaging/CMakeLists.txt):
#   lightstage (host), lightstage-domed (domed), lightstage-sim (sim),
#   lightstage-rigs (rigs, which the three programs depend on) and
#   liblightstage-dev (devel).
# Build them in a build folder with `cmake --build build --target package` or
# `cd build && cpack -G DEB`. Configure that build with -DCMAKE_INSTALL_PREFIX=/usr:
# the programs look for the rigs under the prefix they were configured with.
set(LIGHTSTAGE_PACKAGE_MAINTAINER "Lightstage developers <lightstage@example.org>"
    CACHE STRING "Maintainer field of the Debian packages")
set(LIGHTSTAGE_PACKAGE_PREFIX /usr)
if(NOT CMAKE_INSTALL_PREFIX STREQUAL LIGHTSTAGE_PACKAGE_PREFIX)
  message(STATUS "Packages install to ${LIGHTSTAGE_PACKAGE_PREFIX}, but the programs look for rigs in "
                 "${CMAKE_INSTALL_FULL_DATADIR}/lightstage/rigs: configure with "
                 "-DCMAKE_INSTALL_PREFIX=${LIGHTSTAGE_PACKAGE_PREFIX} for packages to distribute")
endif()

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME lightstage)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "${LIGHTSTAGE_PACKAGE_MAINTAINER}")
set(CPACK_PACKAGING_INSTALL_PREFIX ${LIGHTSTAGE_PACKAGE_PREFIX})
# Packages carry stripped programs (a RelWithDebInfo lightstage is mostly debug info).
set(CPACK_STRIP_FILES ON)
# Packages carry static programs: with shared libraries, dpkg-shlibdeps would
# need our libraries' own package first.
if(LIGHTSTAGE_SHARED_LIBS)
  message(STATUS "Debian packages: from static builds only (LIGHTSTAGE_SHARED_LIBS is ON)")
  return()
endif()
if(LIGHTSTAGE_CONTROLLER_ONLY)
  set(CPACK_COMPONENTS_ALL domed rigs)
else()
  set(CPACK_COMPONENTS_ALL host domed sim rigs devel)
endif()
# A cross build's packages are for the target (dpkg names arm64 what GCC calls
# aarch64); CPack would otherwise take the build machine's dpkg architecture.
# dpkg-shlibdeps reads the target's multiarch libraries by itself.
if(CMAKE_CROSSCOMPILING)
  set(LIGHTSTAGE_DEB_ARCHITECTURES "aarch64=arm64;arm=armhf;x86_64=amd64")
  foreach(pair ${LIGHTSTAGE_DEB_ARCHITECTURES})
    string(REPLACE "=" ";" pair "${pair}")
    list(GET pair 0 processor)
    if(CMAKE_SYSTEM_PROCESSOR STREQUAL processor)
      list(GET pair 1 CPACK_DEBIAN_PACKAGE_ARCHITECTURE)
    endif()
  endforeach()
  if(NOT CPACK_DEBIAN_PACKAGE_ARCHITECTURE)
    message(FATAL_ERROR "No Debian architecture known for CMAKE_SYSTEM_PROCESSOR ${CMAKE_SYSTEM_PROCESSOR}")
  endif()
endif()
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_RELEASE 1)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
# dpkg-shlibdeps writes each package's library dependencies from its programs.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)

# Each CPACK_DEBIAN_<COMPONENT>_DESCRIPTION: the synopsis line, then the long
# description (CPack indents it). No CPACK_PACKAGE_DESCRIPTION_SUMMARY: CPack
# would put it in front of every package's synopsis.
set(rigs_dependency "lightstage-rigs (= ${CPACK_PACKAGE_VERSION}-${CPACK_DEBIAN_PACKAGE_RELEASE})")

set(CPACK_DEBIAN_HOST_PACKAGE_NAME lightstage)
set(CPACK_DEBIAN_HOST_PACKAGE_DEPENDS "${rigs_dependency}")
set(CPACK_DEBIAN_HOST_PACKAGE_RECOMMENDS "lightstage-sim, lightstage-domed")  # `lightstage demo` runs both
set(CPACK_DEBIAN_HOST_DESCRIPTION "photometric stereo on a light stage: the host program
lightstage simulates or captures image stacks under a dome of LEDs and turns
them into surface normals, albedo, depth, meshes, relit images and HTML
reports. With lightstage-sim and lightstage-domed, `lightstage demo` runs the
whole pipeline on a simulated dome. Includes the udev rules that let users
reach a dome controller over USB or serial, bash completion and the documents.")

set(CPACK_DEBIAN_DOMED_PACKAGE_NAME lightstage-domed)
set(CPACK_DEBIAN_DOMED_PACKAGE_DEPENDS "${rigs_dependency}")
set(CPACK_DEBIAN_DOMED_DESCRIPTION "light stage dome controller: LED sequencer and camera trigger
lightstage-domed runs on the dome's controller board: it drives the LEDs and
the camera trigger through GPIO, runs uploaded sequences on absolute
deadlines and enforces the rig's safety limits. Includes a systemd unit
(not enabled), its system user, the udev rule that gives the unit's gpio
group the GPIO character devices, and the USB gadget script
(/usr/libexec/lightstage/lightstage-gadget.sh).")
set(LIGHTSTAGE_SYSUSERS_FILE ${LIGHTSTAGE_PACKAGE_PREFIX}/lib/sysusers.d/lightstage.conf)
set(domed_scripts ${CMAKE_BINARY_DIR}/packaging/debian/lightstage-domed)
configure_file(${PROJECT_SOURCE_DIR}/packaging/debian/lightstage-domed.postinst.in ${domed_scripts}/postinst @ONLY)
set(CPACK_DEBIAN_DOMED_PACKAGE_CONTROL_EXTRA ${domed_scripts}/postinst)

set(CPACK_DEBIAN_SIM_PACKAGE_NAME lightstage-sim)
set(CPACK_DEBIAN_SIM_PACKAGE_DEPENDS "${rigs_dependency}")
set(CPACK_DEBIAN_SIM_DESCRIPTION "simulated light stage dome: virtual gpiochip and camera
lightstage-sim stands in for a dome's hardware: a virtual gpiochip with the
rig's lines for lightstage-domed, an emulated camera strobe, fault injection
and a virtual camera that renders a scene under the LEDs that are on.")

# The -dev package's dependencies: the -dev packages of what the libraries link
# (cmake/LightstageDependencies.cmake), which its CMake package and
# pkg-config file find again.
set(devel_depends libeigen3-dev libyaml-cpp-dev libfmt-dev libspdlog-dev libprotobuf-dev zlib1g-dev
    nlohmann-json3-dev libopenexr-dev libraw-dev libpng-dev libjpeg-dev libtiff-dev libexiv2-dev libcpp-httplib-dev)
foreach(component ${LIGHTSTAGE_OPENCV_COMPONENTS})
  list(APPEND devel_depends libopencv-${component}-dev)
endforeach()
foreach(pair "GPIOD;libgpiod-dev" "LIBCAMERA;libcamera-dev" "ARAVIS;libaravis-dev" "GPHOTO2;libgphoto2-dev"
        "LIBUSB;libusb-1.0-0-dev")
  list(GET pair 0 backend)
  list(GET pair 1 package)
  if(LIGHTSTAGE_HAVE_${backend})
    list(APPEND devel_depends ${package})
  endif()
endforeach()
list(JOIN devel_depends ", " devel_depends)
set(CPACK_DEBIAN_DEVEL_PACKAGE_NAME liblightstage-dev)
set(CPACK_DEBIAN_DEVEL_PACKAGE_SECTION libdevel)
set(CPACK_DEBIAN_DEVEL_PACKAGE_DEPENDS "${devel_depends}, pkg-config")
set(CPACK_DEBIAN_DEVEL_DESCRIPTION "photometric stereo on a light stage: the host library (development)
The library behind lightstage, for programs of one's own: image stacks,
light calibration, the photometric-stereo solvers and their registry,
surfaces, relighting. Static libraries, headers, a CMake package
(find_package(Lightstage), targets Lightstage::pipeline, Lightstage::host, ...)
and a pkg-config file (lightstage).")

set(CPACK_DEBIAN_RIGS_PACKAGE_NAME lightstage-rigs)
set(CPACK_DEBIAN_RIGS_PACKAGE_ARCHITECTURE all)
set(CPACK_DEBIAN_RIGS_DESCRIPTION "light stage rig descriptions
The rig descriptions (YAML: LEDs, lines, camera) that lightstage,
lightstage-domed and lightstage-sim read, in /usr/share/lightstage/rigs.")

include(CPack)
