# Finds the OpenCV modules named as COMPONENTS (we use core, imgproc, imgcodecs,
# photo) from Debian's per-module -dev packages, which ship no CMake config of
# their own (only the 150-package libopencv-dev meta package does).
find_path(OpenCVModules_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4)
set(OpenCVModules_COMPONENTS ${OpenCVModules_FIND_COMPONENTS})
if(NOT OpenCVModules_COMPONENTS)
  set(OpenCVModules_COMPONENTS core)
endif()
set(_opencv_required OpenCVModules_INCLUDE_DIR)
foreach(component ${OpenCVModules_COMPONENTS})
  find_library(OpenCVModules_${component}_LIBRARY opencv_${component})
  list(APPEND _opencv_required OpenCVModules_${component}_LIBRARY)
endforeach()
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OpenCVModules REQUIRED_VARS ${_opencv_required})
if(OpenCVModules_FOUND)
  foreach(component ${OpenCVModules_COMPONENTS})
    if(NOT TARGET OpenCV::${component})
      add_library(OpenCV::${component} SHARED IMPORTED)
      set_target_properties(OpenCV::${component} PROPERTIES
        IMPORTED_LOCATION "${OpenCVModules_${component}_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${OpenCVModules_INCLUDE_DIR}"
        INTERFACE_SYSTEM_INCLUDE_DIRECTORIES "${OpenCVModules_INCLUDE_DIR}")
    endif()
  endforeach()
endif()
