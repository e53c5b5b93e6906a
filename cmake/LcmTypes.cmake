# hystloop_lcm_types(TARGET <name> PACKAGE <pkg> FILES <a.lcm>... [JAR <jar name>] [WIRE_LAYOUTS])
#
# Generates code for LCM message definitions at build time, into the build tree only:
#  - C++ headers (lcm-gen --cpp) in <binary dir>/cpp/<pkg>/<type>.hpp, exposed through the
#    INTERFACE library <name> (alias hystloop::<name without hystloop_>), so code writes
#    #include "<pkg>/<type>.hpp". The include directory is SYSTEM: the generated code uses
#    C-style casts that our warning policy would refuse.
#  - with JAR and HYSTLOOP_BUILD_JAVA on: Java sources (lcm-gen --java) compiled against
#    lcm.jar into <binary dir>/<jar name>.jar, so that lcm-spy decodes every channel
#    (CLASSPATH=<jar>:/usr/share/java/lcm.jar lcm-spy). The jar's target is <name>_jar;
#    its path is in that target's JAR_FILE property.
#  - with WIRE_LAYOUTS: each type's wire layout for common/lcm/wire_layout.{hpp,cpp}, made by
#    cmake/lcm_wire_layouts.py from the same .lcm files into <binary dir>/cpp/<pkg>/:
#    wire_layout_decls.inc, wire_layout_defs.inc and wire_layout_samples.hpp (for tests). A type
#    the walker cannot check stops the build with the file, line and reason.
# Each output depends on its .lcm file (and on lcm-gen), so editing a type regenerates it.
find_program(LCM_GEN_EXECUTABLE lcm-gen REQUIRED DOC "LCM type generator (package liblcm-bin / lcm)")

function(hystloop_lcm_types)
  cmake_parse_arguments(ARG "WIRE_LAYOUTS" "TARGET;PACKAGE;JAR" "FILES" ${ARGN})
  if(NOT ARG_TARGET OR NOT ARG_PACKAGE OR NOT ARG_FILES)
    message(FATAL_ERROR "hystloop_lcm_types: TARGET, PACKAGE and FILES are required")
  endif()

  set(_cpp_dir ${CMAKE_CURRENT_BINARY_DIR}/cpp)
  set(_java_dir ${CMAKE_CURRENT_BINARY_DIR}/java)
  set(_headers)
  set(_java_sources)
  foreach(_lcm IN LISTS ARG_FILES)
    get_filename_component(_lcm ${_lcm} ABSOLUTE)
    get_filename_component(_type ${_lcm} NAME_WE)
    # The output paths are derived from the package: refuse a file whose package differs,
    # rather than generating somewhere nothing looks.
    file(STRINGS ${_lcm} _package_line REGEX "^[ \t]*package[ \t]+[A-Za-z0-9_.]+")
    string(REGEX MATCH "package[ \t]+([A-Za-z0-9_.]+)" _unused "${_package_line}")
    if(NOT CMAKE_MATCH_1 STREQUAL ARG_PACKAGE)
      message(FATAL_ERROR "${_lcm}: expected 'package ${ARG_PACKAGE};' (found '${CMAKE_MATCH_1}')")
    endif()

    set(_hpp ${_cpp_dir}/${ARG_PACKAGE}/${_type}.hpp)
    add_custom_command(
      OUTPUT ${_hpp}
      COMMAND ${LCM_GEN_EXECUTABLE} --cpp --cpp-std c++11 --cpp-hpath ${_cpp_dir} ${_lcm}
      DEPENDS ${_lcm} ${LCM_GEN_EXECUTABLE}
      COMMENT "lcm-gen --cpp ${ARG_PACKAGE}/${_type}"
      VERBATIM)
    list(APPEND _headers ${_hpp})

    if(ARG_JAR AND HYSTLOOP_BUILD_JAVA)
      set(_java ${_java_dir}/${ARG_PACKAGE}/${_type}.java)
      add_custom_command(
        OUTPUT ${_java}
        COMMAND ${LCM_GEN_EXECUTABLE} --java --jpath ${_java_dir} ${_lcm}
        DEPENDS ${_lcm} ${LCM_GEN_EXECUTABLE}
        COMMENT "lcm-gen --java ${ARG_PACKAGE}/${_type}"
        VERBATIM)
      list(APPEND _java_sources ${_java})
    endif()
  endforeach()

  if(ARG_WIRE_LAYOUTS)
    find_package(Python3 3.8 REQUIRED COMPONENTS Interpreter)
    set(_generator ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/lcm_wire_layouts.py)
    set(_layouts_dir ${_cpp_dir}/${ARG_PACKAGE})
    set(_lcm_paths)
    foreach(_lcm IN LISTS ARG_FILES)
      get_filename_component(_lcm ${_lcm} ABSOLUTE)
      list(APPEND _lcm_paths ${_lcm})
    endforeach()
    set(_layouts ${_layouts_dir}/wire_layout_decls.inc ${_layouts_dir}/wire_layout_defs.inc
                 ${_layouts_dir}/wire_layout_samples.hpp)
    add_custom_command(
      OUTPUT ${_layouts}
      COMMAND ${Python3_EXECUTABLE} ${_generator} ${_layouts_dir} ${ARG_PACKAGE} ${_lcm_paths}
      DEPENDS ${_lcm_paths} ${_generator}
      COMMENT "wire layouts of ${ARG_PACKAGE} (cmake/lcm_wire_layouts.py)"
      VERBATIM)
    list(APPEND _headers ${_layouts})
  endif()

  add_custom_target(${ARG_TARGET}_generate DEPENDS ${_headers})
  add_library(${ARG_TARGET} INTERFACE)
  # Followed transitively by whatever links the interface library (CMake >= 3.3).
  add_dependencies(${ARG_TARGET} ${ARG_TARGET}_generate)
  target_include_directories(${ARG_TARGET} SYSTEM INTERFACE ${_cpp_dir})
  target_link_libraries(${ARG_TARGET} INTERFACE PkgConfig::LCM)
  string(REGEX REPLACE "^hystloop_" "" _alias ${ARG_TARGET})
  add_library(hystloop::${_alias} ALIAS ${ARG_TARGET})

  if(ARG_JAR AND HYSTLOOP_BUILD_JAVA)
    find_package(Java 1.8 COMPONENTS Development REQUIRED)
    include(UseJava)
    find_file(LCM_JAR lcm.jar PATHS /usr/share/java /usr/local/share/java REQUIRED
      DOC "LCM's Java library (package liblcm-java)")
    add_jar(${ARG_TARGET}_jar
      SOURCES ${_java_sources}
      INCLUDE_JARS ${LCM_JAR}
      OUTPUT_NAME ${ARG_JAR}
      OUTPUT_DIR ${CMAKE_CURRENT_BINARY_DIR})
  endif()
endfunction()
