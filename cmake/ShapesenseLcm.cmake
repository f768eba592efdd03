# Generates C++ from the .lcm types into the build tree at build time; the
# generated code is never committed.

function(shapesense_lcm_library name)
  cmake_parse_arguments(ARG "" "PACKAGE" "TYPES" ${ARGN})
  set(out_dir ${CMAKE_CURRENT_BINARY_DIR}/generated)
  set(headers "")
  foreach(lcm_file ${ARG_TYPES})
    get_filename_component(type_name ${lcm_file} NAME_WE)
    list(APPEND headers ${out_dir}/${ARG_PACKAGE}/${type_name}.hpp)
  endforeach()
  set(sources ${ARG_TYPES})
  list(TRANSFORM sources PREPEND ${CMAKE_CURRENT_SOURCE_DIR}/)
  add_custom_command(
    OUTPUT ${headers}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${out_dir}
    COMMAND ${LCM_GEN} --cpp --cpp-hpath ${out_dir} ${sources}
    DEPENDS ${sources}
    COMMENT "lcm-gen: C++ for ${ARG_PACKAGE} types"
    VERBATIM)
  add_custom_target(${name}_generate DEPENDS ${headers})
  add_library(${name} INTERFACE)
  shapesense_alias(${name})
  add_dependencies(${name} ${name}_generate)
  target_include_directories(${name} SYSTEM INTERFACE ${out_dir})
  target_link_libraries(${name} INTERFACE PkgConfig::LCM)
  # GCC 12 at -O3 reports a false maybe-uninitialized in lcm-gen's fingerprint code,
  # inlined into our sources; the generated code is not ours to change.
  target_compile_options(${name} INTERFACE -Wno-maybe-uninitialized)
  # GCC 12's -fsanitize=vptr breaks LCM 1.3's C++ subscription callback (the
  # handler pointer arrives null); the rest of UBSan stays on for this code.
  if(SHAPESENSE_SANITIZE)
    target_compile_options(${name} INTERFACE -fno-sanitize=vptr)
  endif()
endfunction()
