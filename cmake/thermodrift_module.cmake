# One static library per folder of src/ (io, features, models, ...), so a module
# builds and tests on its own; `thermodrift` links them all.
function(thermodrift_module name)
  cmake_parse_arguments(ARG "" "" "DEPS" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${name}/*.cpp)
  if(NOT sources)  # a header-only module
    add_library(thermodrift_${name} INTERFACE)
    target_include_directories(thermodrift_${name} INTERFACE ${PROJECT_SOURCE_DIR}/include)
    target_link_libraries(thermodrift_${name} INTERFACE Eigen3::Eigen fmt::fmt
                          nlohmann_json::nlohmann_json Threads::Threads ${ARG_DEPS})
    return()
  endif()
  add_library(thermodrift_${name} STATIC ${sources})
  target_include_directories(thermodrift_${name} PUBLIC ${PROJECT_SOURCE_DIR}/include
                                                 PRIVATE ${PROJECT_SOURCE_DIR}/src)
  target_compile_options(thermodrift_${name} PRIVATE -Wall -Wextra -Wpedantic)
  target_link_libraries(thermodrift_${name} PUBLIC Eigen3::Eigen fmt::fmt
                        nlohmann_json::nlohmann_json Threads::Threads ${ARG_DEPS})
endfunction()

# A GoogleTest executable from every *_test.cpp in a folder, registered with CTest.
function(thermodrift_test_folder name folder)
  cmake_parse_arguments(ARG "" "COST" "DEPS;LABELS" ${ARGN})
  # COST: ctest starts the costlier folders first, so a long test does not run alone at
  # the end of a parallel run (a fresh clone has no timing data of its own).
  if(NOT ARG_COST)
    set(ARG_COST 0)
  endif()
  file(GLOB sources CONFIGURE_DEPENDS ${folder}/*_test.cpp)
  if(NOT sources)
    return()
  endif()
  add_executable(${name} ${sources})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main)
  target_compile_definitions(${name} PRIVATE
    THERMODRIFT_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    THERMODRIFT_SHARED_DATA="${THERMODRIFT_SHARED_DATA}"
    THERMODRIFT_BINARY="$<TARGET_FILE:thermodrift_cli>")
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES LABELS "${ARG_LABELS}" COST ${ARG_COST})
endfunction()
