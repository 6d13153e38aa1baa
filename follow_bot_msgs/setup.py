# The Python package follow_bot_msgs (src/follow_bot_msgs): beside the generated messages,
# ros_image (numpy <-> sensor_msgs/Image), shared by the lab nodes and the harness.
from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(**generate_distutils_setup(packages=["follow_bot_msgs"], package_dir={"": "src"}))
