"""ROS-free core of the robot-vision simulator harness (world, camera, renderer, scoring)."""
