"""`python3 cfg_defaults.py PACKAGE CFG HEADER`: writes HEADER, a ROS-free C++ header with the
defaults the dynamic_reconfigure CFG declares, as `struct <Name>Defaults` (Name: its file name) of
static constexpr members named as the parameters, in namespace PACKAGE. The cores' Config
structs use them as member initialisers, so each default is written once, in the .cfg.
(generate_cfg_defaults in follow_bot_common's CMake extras runs it at build time.)

read_cfg is also tools/param_tables.py's reader of the .cfg files.
"""

import contextlib
import runpy
import sys
from pathlib import Path
from unittest import mock

from dynamic_reconfigure import parameter_generator_catkin

CPP_TYPES = {"int": "int", "double": "double", "str": "const char*", "bool": "bool"}


def read_cfg(path: Path) -> list[dict]:
    """The parameters `path` declares, in order, as dynamic_reconfigure's generator holds them."""
    generators = []

    def capture(gen, *_names):
        generators.append(gen)
        return 0

    # The generator writes C++ and Python into directories named on argv; only its list is
    # wanted. The .cfg ends with exit(gen.generate(...)).
    with (
        mock.patch.object(parameter_generator_catkin.ParameterGenerator, "generate", capture),
        mock.patch.object(sys, "argv", [str(path), "", "", "", ""]),
        contextlib.suppress(SystemExit),
    ):
        runpy.run_path(str(path), run_name="__main__")
    (gen,) = generators
    return gen.group.get_parameters()


def literal(param: dict) -> str:
    value = param["default"]
    if param["type"] == "bool":
        return "true" if value else "false"
    if param["type"] == "str":
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if param["type"] == "double":
        return repr(float(value))
    return str(value)


def header(package: str, cfg: Path) -> str:
    lines = [
        f"// Generated from {cfg.name} by cfg_defaults.py (follow_bot_common): do not edit. The",
        "// .cfg is the one declaration of these defaults.",
        "#pragma once",
        "",
        f"namespace {package} {{",
        "",
        f"struct {cfg.stem}Defaults {{",
    ]
    for param in read_cfg(cfg):
        kind = CPP_TYPES[param["type"]]
        lines.append(f"  static constexpr {kind} {param['name']} = {literal(param)};")
    lines += ["};", "", f"}}  // namespace {package}", ""]
    return "\n".join(lines)


def main() -> int:
    if len(sys.argv) != 4 or sys.argv[1] in ("-h", "--help"):
        print(__doc__, file=sys.stderr)
        return 0 if len(sys.argv) == 2 else 2
    package, cfg, out = sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3])
    text = header(package, cfg)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
