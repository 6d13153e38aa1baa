# The Python package image_converter (python/image_converter), installed by
# catkin_python_setup(); the compiled module image_converter.core is built and installed next to
# it by python/CMakeLists.txt.
from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(**generate_distutils_setup(packages=["image_converter"], package_dir={"": "python"}))
