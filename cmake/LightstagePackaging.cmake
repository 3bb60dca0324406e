# Debian packages, one per install component (packaging/CMakeLists.txt):
#   lightstage (host), lightstage-domed (domed), lightstage-sim (sim) and
#   lightstage-rigs (rigs, which the other three depend on).
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
set(CPACK_COMPONENTS_ALL host domed sim rigs)
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
(not enabled), its system user and the USB gadget script
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

set(CPACK_DEBIAN_RIGS_PACKAGE_NAME lightstage-rigs)
set(CPACK_DEBIAN_RIGS_PACKAGE_ARCHITECTURE all)
set(CPACK_DEBIAN_RIGS_DESCRIPTION "light stage rig descriptions
The rig descriptions (YAML: LEDs, lines, camera) that lightstage,
lightstage-domed and lightstage-sim read, in /usr/share/lightstage/rigs.")

include(CPack)
