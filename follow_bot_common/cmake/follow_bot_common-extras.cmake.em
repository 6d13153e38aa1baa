# add_behaviour_node(NODE_NAME NODELET_FACTORY NODELET_HEADER NODELET_LIBRARY): the executable
# NODE_NAME of the calling package, a generated main (node_main.cpp.in) that runs the nodelet
# made by the C++ expression NODELET_FACTORY() (declared in NODELET_HEADER, linked from
# NODELET_LIBRARY) in a process of its own and sends its final stop on shutdown; installed.
# The target is NODE_NAME, or NODE_NAME_node when that is the package's own name.
@[if DEVELSPACE]@
set(follow_bot_common_NODE_MAIN_TEMPLATE "@(CMAKE_CURRENT_SOURCE_DIR)/cmake/node_main.cpp.in")
set(follow_bot_common_CFG_DEFAULTS "@(CMAKE_CURRENT_SOURCE_DIR)/cmake/cfg_defaults.py")
@[else]@
set(follow_bot_common_NODE_MAIN_TEMPLATE "${follow_bot_common_DIR}/node_main.cpp.in")
set(follow_bot_common_CFG_DEFAULTS "${follow_bot_common_DIR}/cfg_defaults.py")
@[end if]@

function(add_behaviour_node NODE_NAME NODELET_FACTORY NODELET_HEADER NODELET_LIBRARY)
  set(target ${NODE_NAME})
  if(target STREQUAL PROJECT_NAME)
    set(target ${NODE_NAME}_node)
  endif()
  set(main ${CMAKE_CURRENT_BINARY_DIR}/nodes/${NODE_NAME}_main.cpp)
  configure_file(${follow_bot_common_NODE_MAIN_TEMPLATE} ${main} @@ONLY)
  add_executable(${target} ${main})
  set_target_properties(${target} PROPERTIES OUTPUT_NAME ${NODE_NAME})
  target_link_libraries(${target} ${NODELET_LIBRARY} ${catkin_LIBRARIES})
  install(TARGETS ${target} RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
endfunction()

# generate_cfg_defaults(CFG...): for each dynamic_reconfigure cfg/<Name>.cfg of the calling
# package, the ROS-free header <package>/<Name>Defaults.h (struct <Name>Defaults: the .cfg's
# defaults as constexpr members) in the devel include directory, installed; built by the target
# <package>_cfg_defaults, which the cores that include the headers depend on.
function(generate_cfg_defaults)
  set(headers)
  foreach(cfg ${ARGN})
    get_filename_component(name ${cfg} NAME_WE)
    set(header
      ${CATKIN_DEVEL_PREFIX}/${CATKIN_GLOBAL_INCLUDE_DESTINATION}/${PROJECT_NAME}/${name}Defaults.h)
    add_custom_command(OUTPUT ${header}
      COMMAND ${PYTHON_EXECUTABLE} ${follow_bot_common_CFG_DEFAULTS} ${PROJECT_NAME}
        ${CMAKE_CURRENT_SOURCE_DIR}/${cfg} ${header}
      DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${cfg} ${follow_bot_common_CFG_DEFAULTS}
      COMMENT "Generating ${name}Defaults.h from ${cfg}")
    list(APPEND headers ${header})
  endforeach()
  add_custom_target(${PROJECT_NAME}_cfg_defaults ALL DEPENDS ${headers})
  install(FILES ${headers} DESTINATION ${CATKIN_PACKAGE_INCLUDE_DESTINATION})
endfunction()
