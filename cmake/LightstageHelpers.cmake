# One way to add libraries, programs and tests everywhere in the tree.

# lightstage_library(NAME SOURCES ... DEPS ...): a library (static, or shared
# with LIGHTSTAGE_SHARED_LIBS) whose public headers live in <module>/include;
# installed ones find them under include/ (packaging/library.cmake).
function(lightstage_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(${name} ${LIGHTSTAGE_LIBRARY_TYPE} ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
                                            $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  target_compile_options(${name} PRIVATE ${LIGHTSTAGE_WARNINGS})
  set_target_properties(${name} PROPERTIES LIGHTSTAGE_HEADER_DIR ${CMAKE_CURRENT_SOURCE_DIR}/include
                                           UNITY_BUILD ${LIGHTSTAGE_UNITY_BUILD} UNITY_BUILD_BATCH_SIZE 6)
  lightstage_library_version(${name})
endfunction()

# Shared libraries carry the version in their file name and soname (0.1: no
# stable ABI before 1.0, so every minor version is a new soname). No
# <target>_EXPORTS define: nothing of ours reads it, and the objects then
# compile as the static build's do.
function(lightstage_library_version name)
  if(LIGHTSTAGE_SHARED_LIBS)
    set_target_properties(${name} PROPERTIES VERSION ${PROJECT_VERSION}
                          SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR} DEFINE_SYMBOL "")
  endif()
endfunction()

# lightstage_program(NAME SOURCES ... DEPS ...): an executable in build/bin.
function(lightstage_program name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
  target_compile_options(${name} PRIVATE ${LIGHTSTAGE_WARNINGS})
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bin
                                           UNITY_BUILD ${LIGHTSTAGE_UNITY_BUILD} UNITY_BUILD_BATCH_SIZE 6)
endfunction()

# lightstage_test(NAME SOURCES ... DEPS ... [LABELS ...]): a GoogleTest binary,
# its cases registered one by one with CTest.
function(lightstage_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} lightstage_test_support GTest::gtest GTest::gmock)
  target_compile_options(${name} PRIVATE ${LIGHTSTAGE_WARNINGS})
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/tests)
  gtest_discover_tests(${name}
    TEST_PREFIX "${name}."
    WORKING_DIRECTORY ${CMAKE_BINARY_DIR}
    PROPERTIES LABELS "${ARG_LABELS}" ENVIRONMENT "LIGHTSTAGE_SOURCE_DIR=${PROJECT_SOURCE_DIR}"
    DISCOVERY_TIMEOUT 60)
endfunction()
