# Strict warnings (as errors) for the project's own targets only; sanitizers
# for the whole build when SHAPESENSE_SANITIZE is on.

add_library(shapesense_warnings INTERFACE)
add_library(shapesense::warnings ALIAS shapesense_warnings)
target_compile_options(shapesense_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast
  -Wcast-align -Woverloaded-virtual -Wnull-dereference -Wimplicit-fallthrough
  -Werror)

if(SHAPESENSE_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()

# shapesense_alias(NAME): shapesense::X for the target shapesense_X. Targets
# link each other by these names: a misspelt one is a configure error, not a
# plain "-lshapesense_x" that fails at link time, if ever.
function(shapesense_alias name)
  string(REGEX REPLACE "^shapesense_" "" short ${name})
  add_library(shapesense::${short} ALIAS ${name})
endfunction()

# shapesense_record_scope(NAME SOURCES DEPS): notes a target of the tree
# (not of tests/) with its folder, sources and the project targets it links,
# for shapesense_write_scopes. Every include path starts at the project root,
# so the compiler cannot hold a target to its dependencies; tests/layout's
# target_scope_test does, from this record.
function(shapesense_record_scope name sources deps)
  file(RELATIVE_PATH folder ${PROJECT_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR})
  if(folder MATCHES "^tests(/|$)")
    return()
  endif()
  set(targets "")
  foreach(dep IN LISTS deps)
    if(dep MATCHES "^shapesense::(.+)$")
      list(APPEND targets "shapesense_${CMAKE_MATCH_1}")
    endif()
  endforeach()
  set(files "")
  foreach(source IN LISTS sources)
    list(APPEND files "${folder}/${source}")
  endforeach()
  list(JOIN targets "," targets)
  list(JOIN files "," files)
  set_property(GLOBAL APPEND PROPERTY SHAPESENSE_SCOPES "${name}|${folder}|${targets}|${files}")
endfunction()

# shapesense_write_scopes(FILE): one line per recorded target,
# "name|folder|dep,dep|source,source", read by target_scope_test.
function(shapesense_write_scopes file)
  get_property(scopes GLOBAL PROPERTY SHAPESENSE_SCOPES)
  list(JOIN scopes "\n" text)
  file(WRITE ${file} "${text}\n")
endfunction()

# shapesense_library(NAME SOURCES ... DEPS ...): one library target per folder.
function(shapesense_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(${name} ${ARG_SOURCES})
  shapesense_alias(${name})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS} PRIVATE shapesense::warnings ${ARG_PRIVATE_DEPS})
  shapesense_record_scope(${name} "${ARG_SOURCES}" "${ARG_DEPS};${ARG_PRIVATE_DEPS}")
endfunction()

# shapesense_executable(NAME SOURCES ... DEPS ...): every program lands in
# <build>/bin, so a launcher (the demo) finds the services beside itself.
function(shapesense_executable name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/bin)
  target_link_libraries(${name} PRIVATE shapesense::warnings ${ARG_DEPS})
  shapesense_record_scope(${name} "${ARG_SOURCES}" "${ARG_DEPS}")
  # The shipped programs (not the benches under tests/) make the `programs`
  # target: what the demo runs, built without the tests.
  set(tests_dir "${PROJECT_SOURCE_DIR}/tests")
  cmake_path(IS_PREFIX tests_dir "${CMAKE_CURRENT_SOURCE_DIR}" NORMALIZE under_tests)
  if(NOT under_tests)
    set_property(GLOBAL APPEND PROPERTY SHAPESENSE_PROGRAMS ${name})
  endif()
endfunction()

# shapesense_test(NAME SOURCES ... DEPS ... [LABELS ...]): one gtest executable,
# registered with CTest test by test.
function(shapesense_test name)
  cmake_parse_arguments(ARG "" "TIMEOUT" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE shapesense::warnings GTest::gtest GTest::gtest_main GTest::gmock ${ARG_DEPS})
  target_compile_definitions(${name} PRIVATE SHAPESENSE_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 600)
  endif()
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT ${ARG_TIMEOUT} LABELS "${ARG_LABELS}")
endfunction()
