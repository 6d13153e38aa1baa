"""follow_bot from Python: `from follow_bot import core` gives the C++ detectors and controllers.

`core` is a compiled module (pybind11) over the same C++ classes the nodes run; see the
manual follow_bot/doc/python.md ("From Python").
"""
