# Two helpers keep every folder's CMakeLists a few lines long (COLMAP style).
#
# facets_add_library(NAME SRCS a.cc b.cc DEPS x y)
#   A static library facets_NAME; headers are included as "module/file.h" from the
#   project root.
# facets_add_test(NAME SRCS a_test.cc DEPS x y [LABEL unit|e2e] [TIMEOUT seconds])
#   A GoogleTest executable registered with CTest (one CTest entry per test case), each
#   entry labelled `unit` or `e2e` (`ctest -L unit` runs the fast ones first).
#   LABEL: e2e for the tests defined in tests/, unit for the module tests beside their
#   sources unless given (a module test that renders a scene and reconstructs is e2e).
#   TIMEOUT: seconds per test case, 120 for unit and 900 for e2e unless given; five times
#   that in the sanitized build (FACETS_FUZZ).
#   The target facets_unit_tests builds every `unit` executable (and nothing else):
#   scripts/sanitizers.sh builds it with ASan and UBSan and runs `ctest -L unit`.
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
  cmake_parse_arguments(ARG "" "LABEL;TIMEOUT" "SRCS;DEPS" ${ARGN})
  if(NOT FACETS_BUILD_TESTS)
    return()
  endif()
  if(NOT ARG_LABEL)
    if(CMAKE_CURRENT_SOURCE_DIR STREQUAL "${PROJECT_SOURCE_DIR}/tests")
      set(ARG_LABEL e2e)
    else()
      set(ARG_LABEL unit)
    endif()
  endif()
  if(NOT ARG_LABEL MATCHES "^(unit|e2e)$")
    message(FATAL_ERROR "facets_add_test(${name}): LABEL must be unit or e2e, not ${ARG_LABEL}")
  endif()
  if(NOT ARG_TIMEOUT)
    if(ARG_LABEL STREQUAL "unit")
      set(ARG_TIMEOUT 120)
    else()
      set(ARG_TIMEOUT 900)
    endif()
  endif()
  if(FACETS_FUZZ)
    # Sanitized objects run 3-30x slower (CastPixels' brute-force check: 2.3 -> 75 CPU s).
    math(EXPR ARG_TIMEOUT "${ARG_TIMEOUT} * 5")
  endif()
  add_executable(${name} ${ARG_SRCS})
  if(ARG_LABEL STREQUAL "unit")
    if(NOT TARGET facets_unit_tests)
      add_custom_target(facets_unit_tests)
    endif()
    add_dependencies(facets_unit_tests ${name})
  endif()
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main)
  target_compile_options(${name} PRIVATE ${FACETS_WARNINGS})
  target_compile_definitions(${name} PRIVATE
    FACETS_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    FACETS_RENDER_CACHE_DIR="${PROJECT_BINARY_DIR}/render-cache"
    FACETS_SHARED_DATA_DIR="${PROJECT_SOURCE_DIR}/../shared/data")
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60
    PROPERTIES ENVIRONMENT "FACETS_SOURCE_DIR=${PROJECT_SOURCE_DIR}"
               LABELS ${ARG_LABEL} TIMEOUT ${ARG_TIMEOUT})
endfunction()

# facets_test_runs_cli(TEST_TARGET): the test runs the `facets` executable (FACETS_CLI
# holds its path) and is built after it.
function(facets_test_runs_cli name)
  if(TARGET ${name})
    target_compile_definitions(${name} PRIVATE FACETS_CLI="$<TARGET_FILE:facets>")
    add_dependencies(${name} facets)
  endif()
endfunction()

# facets_add_bench(NAME SRCS tests/bench/x_bench.cc DEPS x y)
#   A benchmark executable (never run by CTest: tests do not time anything).
function(facets_add_bench name)
  cmake_parse_arguments(ARG "" "" "SRCS;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SRCS})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
  target_compile_options(${name} PRIVATE ${FACETS_WARNINGS})
endfunction()
