# add_behaviour_node(NODE_NAME NODELET_FACTORY NODELET_HEADER NODELET_LIBRARY): the executable
# NODE_NAME of the calling package, a generated main (node_main.cpp.in) that runs the nodelet
# made by the C++ expression NODELET_FACTORY() (declared in NODELET_HEADER, linked from
# NODELET_LIBRARY) in a process of its own and sends its final stop on shutdown; installed.
# The target is NODE_NAME, or NODE_NAME_node when that is the package's own name.
@[if DEVELSPACE]@
set(follow_bot_common_NODE_MAIN_TEMPLATE "@(CMAKE_CURRENT_SOURCE_DIR)/cmake/node_main.cpp.in")
@[else]@
set(follow_bot_common_NODE_MAIN_TEMPLATE "${follow_bot_common_DIR}/node_main.cpp.in")
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
