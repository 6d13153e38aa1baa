# The Python package follow_bot (python/follow_bot), installed by catkin_python_setup(); the
# compiled module follow_bot.core is built and installed next to it by python/CMakeLists.txt.
from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(**generate_distutils_setup(packages=["follow_bot"], package_dir={"": "python"}))
