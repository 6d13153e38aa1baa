# follow_bot_common's CMake functions, for the packages that use it (included by its CMake
# extras from the devel or install space) and for itself (included from its source tree). The
# templates they use lie next to this file.
set(FOLLOW_BOT_COMMON_CMAKE_DIR ${CMAKE_CURRENT_LIST_DIR})

# follow_bot_package_defaults(): the build settings every package on follow_bot_common shares,
# for the targets it makes after the call: a Release build unless one is asked for, and C++17.
macro(follow_bot_package_defaults)
  if(NOT CMAKE_BUILD_TYPE)
    set(CMAKE_BUILD_TYPE Release)
  endif()
  set(CMAKE_CXX_STANDARD 17)
  set(CMAKE_CXX_STANDARD_REQUIRED ON)
endmacro()

# add_behaviour_node(NODE_NAME NODELET_FACTORY NODELET_HEADER NODELET_LIBRARY NODE_HELP): the
# executable NODE_NAME of the calling package, a generated main (node_main.cpp.in) that runs the
# nodelet made by the C++ expression NODELET_FACTORY() (declared in NODELET_HEADER, linked from
# NODELET_LIBRARY) in a process of its own and sends its final stop on shutdown; with -h or
# --help it prints NODE_HELP() (a follow_bot_common::NodeHelp, declared in NODELET_HEADER) and
# the path of the node's manual, the package's doc/NODE_NAME.md (which must exist), without a
# master. Installed, and the package's README.md and doc/ (its manuals) with it.
# The target is NODE_NAME, or NODE_NAME_node when that is the package's own name.
function(add_behaviour_node NODE_NAME NODELET_FACTORY NODELET_HEADER NODELET_LIBRARY NODE_HELP)
  set(target ${NODE_NAME})
  if(target STREQUAL PROJECT_NAME)
    set(target ${NODE_NAME}_node)
  endif()
  set(main ${CMAKE_CURRENT_BINARY_DIR}/nodes/${NODE_NAME}_main.cpp)
  configure_file(${FOLLOW_BOT_COMMON_CMAKE_DIR}/node_main.cpp.in ${main} @ONLY)
  add_executable(${target} ${main})
  set_target_properties(${target} PROPERTIES OUTPUT_NAME ${NODE_NAME})
  target_link_libraries(${target} ${NODELET_LIBRARY} ${catkin_LIBRARIES})
  install(TARGETS ${target} RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
  if(NOT EXISTS ${PROJECT_SOURCE_DIR}/doc/${NODE_NAME}.md)
    message(FATAL_ERROR "add_behaviour_node(${NODE_NAME}): no manual ${PROJECT_SOURCE_DIR}/doc/"
      "${NODE_NAME}.md, the page its --help names")
  endif()
  get_property(docs_installed DIRECTORY PROPERTY FOLLOW_BOT_DOCS_INSTALLED)
  if(NOT docs_installed)  # once per package
    install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${CATKIN_PACKAGE_SHARE_DESTINATION})
    install(DIRECTORY ${PROJECT_SOURCE_DIR}/doc DESTINATION ${CATKIN_PACKAGE_SHARE_DESTINATION})
    set_property(DIRECTORY PROPERTY FOLLOW_BOT_DOCS_INSTALLED TRUE)
  endif()
endfunction()

# generate_cfg_defaults(CFG...): for each dynamic_reconfigure cfg/<Name>.cfg of the calling
# package, the ROS-free header <package>/<Name>Defaults.h (struct <Name>Defaults: the .cfg's
# defaults as constexpr members) in the devel include directory, which it adds to the calling
# directory's include directories; installed. Built by the target <package>_cfg_defaults, which
# the cores that include the headers depend on (and, exported, those of the packages that use
# this one: call it before catkin_package()).
function(generate_cfg_defaults)
  set(include_dir ${CATKIN_DEVEL_PREFIX}/${CATKIN_GLOBAL_INCLUDE_DESTINATION})
  include_directories(${include_dir})
  set(headers)
  foreach(cfg ${ARGN})
    get_filename_component(name ${cfg} NAME_WE)
    set(header ${include_dir}/${PROJECT_NAME}/${name}Defaults.h)
    add_custom_command(OUTPUT ${header}
      COMMAND ${PYTHON_EXECUTABLE} ${FOLLOW_BOT_COMMON_CMAKE_DIR}/cfg_defaults.py ${PROJECT_NAME}
        ${CMAKE_CURRENT_SOURCE_DIR}/${cfg} ${header}
      DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${cfg} ${FOLLOW_BOT_COMMON_CMAKE_DIR}/cfg_defaults.py
      COMMENT "Generating ${name}Defaults.h from ${cfg}")
    list(APPEND headers ${header})
  endforeach()
  add_custom_target(${PROJECT_NAME}_cfg_defaults ALL DEPENDS ${headers})
  # For the packages whose code includes the headers too (catkin_EXPORTED_TARGETS).
  set(${PROJECT_NAME}_EXPORTED_TARGETS ${${PROJECT_NAME}_EXPORTED_TARGETS}
    ${PROJECT_NAME}_cfg_defaults PARENT_SCOPE)
  # = CATKIN_PACKAGE_INCLUDE_DESTINATION, which only catkin_package() may have set yet.
  install(FILES ${headers} DESTINATION ${CATKIN_GLOBAL_INCLUDE_DESTINATION}/${PROJECT_NAME})
endfunction()

# add_python_core(SOURCE...): the calling package's Python module <package>.core,
# pybind11 bindings (the SOURCEs) over its <package>_core library, built into the devel space's
# Python path next to the package catkin_python_setup() makes (python/<package>, ../setup.py),
# so `from <package> import core` works after sourcing devel/ or install/; installed. Also the
# executable core_reference (target <package>_core_reference, from core_reference.cpp): the C++ results
# tests/bindings/test_python_core.py compares the module's with, on the same image files.
# The interpreter catkin builds for (the Makefile passes /usr/bin/python3), with its headers
# (python3-dev). Found as Python3: a dependency's CMake (ament_cmake_core's python.cmake) already
# runs find_package(Python3), which puts Debian's pybind11 in its FindPython mode anyway.
function(add_python_core)
  set(Python3_EXECUTABLE ${PYTHON_EXECUTABLE})
  find_package(Python3 REQUIRED COMPONENTS Interpreter Development.Module)
  find_package(pybind11 2.6 CONFIG REQUIRED)
  # A workspace-unique target name; Python sees the file as <package>/core.<SOABI>.so. What
  # pybind11_add_module does, spelt out so catkin_lint can follow the target.
  add_library(${PROJECT_NAME}_python_core MODULE ${ARGN})
  pybind11_extension(${PROJECT_NAME}_python_core)  # the module's file name
  target_link_libraries(${PROJECT_NAME}_python_core PRIVATE pybind11::module ${PROJECT_NAME}_core
    ${OpenCV_LIBRARIES})
  target_compile_options(${PROJECT_NAME}_python_core PRIVATE -Wall -Wextra -Werror)
  set_target_properties(${PROJECT_NAME}_python_core PROPERTIES
    OUTPUT_NAME core
    CXX_VISIBILITY_PRESET hidden  # as pybind11 requires of a module
    LIBRARY_OUTPUT_DIRECTORY ${CATKIN_DEVEL_PREFIX}/${CATKIN_PACKAGE_PYTHON_DESTINATION})
  install(TARGETS ${PROJECT_NAME}_python_core
    LIBRARY DESTINATION ${CATKIN_PACKAGE_PYTHON_DESTINATION})

  add_executable(${PROJECT_NAME}_core_reference core_reference.cpp)
  set_target_properties(${PROJECT_NAME}_core_reference PROPERTIES OUTPUT_NAME core_reference)
  target_link_libraries(${PROJECT_NAME}_core_reference ${PROJECT_NAME}_core ${OpenCV_LIBRARIES})
  target_compile_options(${PROJECT_NAME}_core_reference PRIVATE -Wall -Wextra -Werror)
  install(TARGETS ${PROJECT_NAME}_core_reference RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
endfunction()
