# SPDX-License-Identifier: Apache-2.0
# Every third-party dependency, found once. All come from Debian bookworm packages
# installed by deploy/setup.sh.
include_guard(GLOBAL)
find_package(Threads REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(absl REQUIRED)
find_package(GTest REQUIRED)
find_package(benchmark REQUIRED)
find_package(Ceres REQUIRED)
find_package(PkgConfig REQUIRED)

# OpenCV: Debian's per-module -dev packages ship headers and libraries but no CMake
# config (that comes with the much larger libopencv-dev), so declare the modules here.
find_path(VB_OPENCV_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4 REQUIRED)
foreach(module core imgproc imgcodecs calib3d)
  find_library(VB_OPENCV_${module}_LIBRARY opencv_${module} REQUIRED)
  add_library(vb_opencv_${module} INTERFACE IMPORTED)
  set_target_properties(vb_opencv_${module} PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES ${VB_OPENCV_INCLUDE_DIR}
    INTERFACE_LINK_LIBRARIES ${VB_OPENCV_${module}_LIBRARY})
endforeach()

pkg_check_modules(ARAVIS REQUIRED IMPORTED_TARGET aravis-0.8)

# Planning: OMPL (RRT-Connect) and FCL (the collision-checking baseline). Debian's OMPL config
# sets variables rather than an imported target, and its OMPL_LIBRARIES names Boost's -dev
# symlinks that libompl-dev does not install; libompl.so resolves those itself.
find_package(ompl REQUIRED)
find_library(VB_OMPL_LIBRARY ompl HINTS ${OMPL_LIBRARY_DIRS} REQUIRED)
add_library(vb_ompl INTERFACE IMPORTED)
set_target_properties(vb_ompl PROPERTIES
  INTERFACE_INCLUDE_DIRECTORIES "${OMPL_INCLUDE_DIRS}"
  INTERFACE_LINK_LIBRARIES "${VB_OMPL_LIBRARY}")
find_package(fcl REQUIRED)
