# Shared build settings for every mrpt_wifi target.

function(mrpt_wifi_set_warnings target)
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wshadow -Wnon-virtual-dtor)
endfunction()

# Test programs are glue around the optimised libraries: at -O1 they compile a third faster
# (CI's 30 minutes) and run as fast. Benchmarks and fuzzers keep the build type's flags.
function(mrpt_wifi_optimize_as_test_code target)
    target_compile_options(${target} PRIVATE $<$<CONFIG:Release,RelWithDebInfo>:-O1>)
endfunction()

# The first GoogleTest program precompiles MRPT_WIFI_TEST_PRECOMPILED_HEADERS (the headers every
# suite parses, about half of a test file's compile time) and the others reuse it. All suites
# share their flags and definitions, as reuse requires (some add macros of their libraries, e.g.
# glog's, which the precompiled headers don't use: GCC and Clang accept that).
function(mrpt_wifi_use_test_precompiled_headers target)
    if(NOT CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang" OR NOT MRPT_WIFI_TEST_PRECOMPILED_HEADERS)
        return()
    endif()
    get_property(owner GLOBAL PROPERTY MRPT_WIFI_TEST_PCH_OWNER)
    if(owner)
        target_precompile_headers(${target} REUSE_FROM ${owner})
    else()
        target_precompile_headers(${target} PRIVATE ${MRPT_WIFI_TEST_PRECOMPILED_HEADERS})
        set_property(GLOBAL PROPERTY MRPT_WIFI_TEST_PCH_OWNER ${target})
    endif()
endfunction()

# mrpt_wifi_add_library(NAME SOURCES ... [PUBLIC_LINK ...] [PRIVATE_LINK ...])
# A shared library with public headers in <folder>/include, installed with them.
function(mrpt_wifi_add_library name)
    cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_LINK;PRIVATE_LINK" ${ARGN})
    add_library(${name} SHARED ${ARG_SOURCES})
    target_include_directories(${name} PUBLIC
        $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
        $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
    target_link_libraries(${name} PUBLIC ${ARG_PUBLIC_LINK} PRIVATE ${ARG_PRIVATE_LINK})
    set_target_properties(${name} PROPERTIES VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR})
    mrpt_wifi_set_warnings(${name})
    install(TARGETS ${name} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
    install(DIRECTORY include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()

# mrpt_wifi_add_app(NAME SOURCES ... LINK ...): a command-line program, installed to bin/.
function(mrpt_wifi_add_app name)
    cmake_parse_arguments(ARG "" "" "SOURCES;LINK" ${ARGN})
    add_executable(${name} ${ARG_SOURCES})
    target_link_libraries(${name} PRIVATE ${ARG_LINK})
    mrpt_wifi_set_warnings(${name})
    install(TARGETS ${name} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endfunction()

# mrpt_wifi_add_gtest(NAME SOURCES ... LINK ... [LABELS ...]): a GoogleTest program registered
# with ctest. Tests find ../shared through MRPT_WIFI_SHARED_DIR and built programs through
# MRPT_WIFI_BIN_DIR / MRPT_WIFI_LIB_DIR.
function(mrpt_wifi_add_gtest name)
    cmake_parse_arguments(ARG "" "" "SOURCES;LINK;LABELS" ${ARGN})
    add_executable(${name} ${ARG_SOURCES})
    target_link_libraries(${name} PRIVATE ${ARG_LINK} mrpt_wifi_test_support GTest::gtest GTest::gtest_main)
    target_compile_definitions(${name} PRIVATE
        MRPT_WIFI_SHARED_DIR="${MRPT_WIFI_SHARED_DIR}"
        MRPT_WIFI_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
        MRPT_WIFI_BIN_DIR="${CMAKE_RUNTIME_OUTPUT_DIRECTORY}"
        MRPT_WIFI_LIB_DIR="${CMAKE_LIBRARY_OUTPUT_DIRECTORY}")
    mrpt_wifi_set_warnings(${name})
    mrpt_wifi_optimize_as_test_code(${name})
    mrpt_wifi_use_test_precompiled_headers(${name})
    gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES LABELS "${ARG_LABELS}")
endfunction()

# mrpt_wifi_add_benchmark(NAME SOURCES ... LINK ...): a Google Benchmark program (not a test).
function(mrpt_wifi_add_benchmark name)
    cmake_parse_arguments(ARG "" "" "SOURCES;LINK" ${ARGN})
    if(NOT MRPT_WIFI_BUILD_BENCHMARKS)
        return()
    endif()
    add_executable(${name} ${ARG_SOURCES})
    target_link_libraries(${name} PRIVATE ${ARG_LINK} benchmark::benchmark)
    # Benchmarks on real recordings find ../shared as the tests do.
    target_compile_definitions(${name} PRIVATE
        MRPT_WIFI_SHARED_DIR="${MRPT_WIFI_SHARED_DIR}"
        MRPT_WIFI_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
        MRPT_WIFI_BIN_DIR="${CMAKE_RUNTIME_OUTPUT_DIRECTORY}"
        MRPT_WIFI_LIB_DIR="${CMAKE_LIBRARY_OUTPUT_DIRECTORY}")
    mrpt_wifi_set_warnings(${name})
endfunction()
