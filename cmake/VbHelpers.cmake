# SPDX-License-Identifier: Apache-2.0
# Small helpers so every folder declares its library, tests and binaries the same way
# (after COLMAP's cmake/CMakeHelper.cmake). Sources are listed explicitly; no GLOB.
include_guard(GLOBAL)

# vb_add_library(NAME SRCS a.cc b.cc PUBLIC_LINK x PRIVATE_LINK y)
function(vb_add_library name)
  cmake_parse_arguments(ARG "" "" "SRCS;PUBLIC_LINK;PRIVATE_LINK" ${ARGN})
  add_library(${name} STATIC ${ARG_SRCS})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PUBLIC ${ARG_PUBLIC_LINK} PRIVATE ${ARG_PRIVATE_LINK})
  target_compile_options(${name} PRIVATE ${VB_WARNINGS})
endfunction()

# vb_add_executable(NAME SRCS main.cc LINK libs...)
function(vb_add_executable name)
  cmake_parse_arguments(ARG "" "" "SRCS;LINK" ${ARGN})
  add_executable(${name} ${ARG_SRCS})
  target_link_libraries(${name} PRIVATE ${ARG_LINK})
  target_compile_options(${name} PRIVATE ${VB_WARNINGS})
endfunction()

# vb_add_test(NAME SRCS x_test.cc LINK libs... [LABELS l...] [RESOURCE_LOCK r])
# Builds one GoogleTest binary and registers each of its tests with CTest. Tests that share a
# RESOURCE_LOCK (e.g. fixed loopback addresses) never run at the same time under ctest -j.
function(vb_add_test name)
  cmake_parse_arguments(ARG "" "RESOURCE_LOCK" "SRCS;LINK;LABELS" ${ARGN})
  if(NOT BUILD_TESTING)
    return()
  endif()
  add_executable(${name} ${ARG_SRCS})
  target_link_libraries(${name} PRIVATE ${ARG_LINK} GTest::gmock GTest::gtest_main)
  target_compile_options(${name} PRIVATE ${VB_WARNINGS})
  target_compile_definitions(${name} PRIVATE VB_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
                                             VB_BINARY_DIR="${PROJECT_BINARY_DIR}")
  set(properties LABELS "${ARG_LABELS}")
  if(ARG_RESOURCE_LOCK)
    list(APPEND properties RESOURCE_LOCK ${ARG_RESOURCE_LOCK})
  endif()
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES ${properties})
endfunction()

# vb_add_benchmark(NAME SRCS x_bench.cc LINK libs...): a Google Benchmark binary, run on demand.
function(vb_add_benchmark name)
  cmake_parse_arguments(ARG "" "" "SRCS;LINK" ${ARGN})
  add_executable(${name} ${ARG_SRCS})
  target_link_libraries(${name} PRIVATE ${ARG_LINK} benchmark::benchmark)
  target_compile_options(${name} PRIVATE ${VB_WARNINGS})
endfunction()
