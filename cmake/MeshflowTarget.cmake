# meshflow_library(<folder> SOURCES ... [LINKS ...]): the target meshflow_<folder>, alias
# meshflow::<folder>, C++20, includes from the repository root.
function(meshflow_library folder)
  cmake_parse_arguments(ARG "" "" "SOURCES" ${ARGN})
  add_library(meshflow_${folder} STATIC ${ARG_SOURCES})
  add_library(meshflow::${folder} ALIAS meshflow_${folder})
  target_compile_features(meshflow_${folder} PUBLIC cxx_std_20)
  target_include_directories(meshflow_${folder} PUBLIC ${PROJECT_SOURCE_DIR})
  meshflow_warnings(meshflow_${folder})
endfunction()

function(meshflow_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wno-unused-parameter)
  if(MESHFLOW_WARNINGS_AS_ERRORS)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# meshflow_tests(<folder> SOURCES ... LINKS ...): one GoogleTest binary per layer,
# meshflow_<folder>_tests, labelled <folder> for `ctest -L <folder>`.
function(meshflow_tests folder)
  cmake_parse_arguments(ARG "" "" "SOURCES;LINKS;LABELS" ${ARGN})
  set(name meshflow_${folder}_tests)
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LINKS} GTest::gtest GTest::gtest_main)
  target_compile_definitions(${name} PRIVATE
    MESHFLOW_SHARED_MESHES="${MESHFLOW_SHARED_MESHES}"
    MESHFLOW_BINARY="$<TARGET_FILE:meshflow>")
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR})
  meshflow_warnings(${name})
  gtest_discover_tests(${name} PROPERTIES LABELS "${folder};${ARG_LABELS}" DISCOVERY_TIMEOUT 60)
endfunction()
