"""The harness interpreter imports exactly one numpy and one cv2: the venv's pinned copies."""

import subprocess
import sys

from harness.testing import REPO

REQUIREMENTS = REPO / "harness" / "requirements.txt"


def pinned(name: str) -> str:
    for line in REQUIREMENTS.read_text().splitlines():
        if line.startswith(f"{name}=="):
            return line.split("==", 1)[1].strip()
    raise AssertionError(f"{name} is not pinned in {REQUIREMENTS}")


def fresh_interpreter(code: str) -> str:
    """What `code` prints, run by a fresh harness interpreter: nothing pytest imported first can
    hide a second copy of a module."""
    return subprocess.run(
        [sys.executable, "-c", code], check=True, capture_output=True, text=True
    ).stdout


def test_numpy_and_cv2_come_from_the_venv_alongside_rospy():
    lines = fresh_interpreter(
        "import rospy, sensor_msgs.msg, numpy, cv2, matplotlib, sys;"
        "print(numpy.__file__); print(cv2.__file__); print(numpy.__version__);"
        "print(cv2.__version__); print(sys.prefix)"
    ).split()
    numpy_file, cv2_file, numpy_version, cv2_version, prefix = lines
    assert numpy_file.startswith(prefix), numpy_file
    assert cv2_file.startswith(prefix), cv2_file
    assert numpy_version == pinned("numpy")
    assert cv2_version == pinned("opencv-python-headless").rsplit(".", 1)[0]


def test_only_one_numpy_is_loaded_after_importing_ros_messages():
    out = fresh_interpreter(
        "import rospy, sensor_msgs.msg, nav_msgs.msg, numpy, cv2, sys;"
        "print(sorted({m.__file__.split('/numpy/')[0] for n, m in sys.modules.items()"
        " if n.split('.')[0] == 'numpy' and getattr(m, '__file__', None)}))"
    )
    assert out.count("'") == 2, f"more than one numpy location loaded: {out}"


def test_matplotlib_and_its_toolkits_are_one_installation():
    # Two copies (pip's in the venv, Debian's python3-matplotlib) mix: Debian's mpl_toolkits is a
    # regular package and wins over pip's namespace one, and matplotlib warns on every import.
    lines = fresh_interpreter(
        "import warnings; warnings.simplefilter('error');"
        "import matplotlib, mpl_toolkits.mplot3d, os;"
        "print(os.path.dirname(os.path.dirname(matplotlib.__file__)));"
        "print(os.path.dirname(list(mpl_toolkits.__path__)[0]))"
    ).split()
    assert lines[0] == lines[1], lines
