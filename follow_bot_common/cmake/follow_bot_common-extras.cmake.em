# follow_bot_common's CMake functions (follow_bot_package_defaults, generate_cfg_defaults,
# add_behaviour_node, add_python_core): one file, from the source tree in the devel space,
# installed next to this one.
@[if DEVELSPACE]@
include("@(CMAKE_CURRENT_SOURCE_DIR)/cmake/follow_bot_common-functions.cmake")
@[else]@
include("${follow_bot_common_DIR}/follow_bot_common-functions.cmake")
@[end if]@
