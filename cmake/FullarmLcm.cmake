# LCM (Debian liblcm-dev, liblcm-bin), which ships no CMake package: the library, its headers
# and lcm-gen, found by hand.
#
# fullarm_lcm_types(<target> TYPES <name>... SOURCE_DIR <dir>)
#   Runs `lcm-gen -x --cpp-std c++11` on <dir>/<name>.lcm at build time, one C++ header per type
#   into <build>/lcm_generated/<package>/<name>.hpp, and makes the INTERFACE target <target>
#   carrying that include folder and the LCM library (installed and exported with fullarm).
find_program(FULLARM_LCM_GEN lcm-gen REQUIRED DOC "lcm-gen (Debian liblcm-bin)")
find_path(FULLARM_LCM_INCLUDE_DIR lcm/lcm-cpp.hpp REQUIRED DOC "LCM headers (Debian liblcm-dev)")
find_library(FULLARM_LCM_LIBRARY lcm REQUIRED DOC "LCM library (Debian liblcm-dev)")
# Optional: the log tests replay a run log through the real lcm-logplayer when it is present.
find_program(FULLARM_LCM_LOGPLAYER lcm-logplayer DOC "lcm-logplayer (Debian liblcm-bin)")

function(fullarm_lcm_types target)
  cmake_parse_arguments(ARG "" "SOURCE_DIR;PACKAGE" "TYPES" ${ARGN})
  set(out_dir ${CMAKE_CURRENT_BINARY_DIR}/lcm_generated)
  set(lcm_files)
  set(headers)
  foreach(type IN LISTS ARG_TYPES)
    list(APPEND lcm_files ${ARG_SOURCE_DIR}/${type}.lcm)
    list(APPEND headers ${out_dir}/${ARG_PACKAGE}/${type}.hpp)
  endforeach()
  add_custom_command(
    OUTPUT ${headers}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${out_dir}
    COMMAND ${FULLARM_LCM_GEN} -x --cpp-std c++11 --cpp-hpath ${out_dir} ${lcm_files}
    DEPENDS ${lcm_files}
    COMMENT "lcm-gen: ${ARG_PACKAGE} C++ types"
    VERBATIM)
  add_custom_target(${target}_generate DEPENDS ${headers})
  add_library(${target} INTERFACE)
  add_dependencies(${target} ${target}_generate)
  # The generated headers are included as system headers: their code is LCM's style, not ours.
  target_include_directories(${target} SYSTEM INTERFACE
    $<BUILD_INTERFACE:${out_dir}>
    $<BUILD_INTERFACE:${FULLARM_LCM_INCLUDE_DIR}>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(${target} INTERFACE ${FULLARM_LCM_LIBRARY})
  install(TARGETS ${target} EXPORT fullarmTargets)
  install(DIRECTORY ${out_dir}/${ARG_PACKAGE} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()
