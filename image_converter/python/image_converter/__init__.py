"""image_converter from Python: `from image_converter import core` gives the C++ overlay, feature
matching and stitching.

`core` is a compiled module (pybind11) over the same C++ functions the nodes and the `stitch`
command run; see the manual follow_bot/doc/python.md ("From Python").
"""
