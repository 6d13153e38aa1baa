"""Lets catkin put harness/src on the devel space's PYTHONPATH."""

from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(**generate_distutils_setup(packages=["harness"], package_dir={"": "src"}))
