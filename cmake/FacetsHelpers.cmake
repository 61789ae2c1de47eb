# Two helpers keep every folder's CMakeLists a few lines long (COLMAP style).
#
# facets_add_library(NAME SRCS a.cc b.cc DEPS x y)
#   A static library facets_NAME; headers are included as "module/file.h" from the
#   project root.
# facets_add_test(NAME SRCS a_test.cc DEPS x y)
#   A GoogleTest executable registered with CTest (one CTest entry per test case).
#   FACETS_SHARED_DATA_DIR: the real data sets beside the repository (../shared/data),
#   overridden at run time by the environment variable FACETS_SHARED_DATA
#   (io/shared_data_for_testing.h).

function(facets_add_library name)
  cmake_parse_arguments(ARG "" "" "SRCS;DEPS" ${ARGN})
  add_library(facets_${name} STATIC ${ARG_SRCS})
  target_include_directories(facets_${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(facets_${name} PUBLIC ${ARG_DEPS})
  target_compile_options(facets_${name} PRIVATE ${FACETS_WARNINGS})
endfunction()

function(facets_add_test name)
  cmake_parse_arguments(ARG "" "" "SRCS;DEPS" ${ARGN})
  if(NOT FACETS_BUILD_TESTS)
    return()
  endif()
  add_executable(${name} ${ARG_SRCS})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main)
  target_compile_options(${name} PRIVATE ${FACETS_WARNINGS})
  target_compile_definitions(${name} PRIVATE
    FACETS_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    FACETS_SHARED_DATA_DIR="${PROJECT_SOURCE_DIR}/../shared/data")
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60
    PROPERTIES ENVIRONMENT "FACETS_SOURCE_DIR=${PROJECT_SOURCE_DIR}")
endfunction()

# facets_add_bench(NAME SRCS tests/bench/x_bench.cc DEPS x y)
#   A benchmark executable (never run by CTest: tests do not time anything).
function(facets_add_bench name)
  cmake_parse_arguments(ARG "" "" "SRCS;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SRCS})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
  target_compile_options(${name} PRIVATE ${FACETS_WARNINGS})
endfunction()
