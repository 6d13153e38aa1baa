#!/usr/bin/python3
"""Generate the READMEs' and manuals' parameter tables from the dynamic_reconfigure .cfg files.

The .cfg files are the single declaration of every runtime parameter: name, type, default,
range, and the description, which ends with its unit in brackets ("Top speed [m/s]"; none for a
plain number). A Markdown file holds a table between

    <!-- params: follow_bot/cfg/Follower.cfg -->
    <!-- end params -->

(the path relative to the repository root), in README.md, a package's README.md or its manuals
(<package>/doc/*.md), or docs/*.md. --write rewrites every such table; --check (the default)
exits 1 naming each table that differs from its .cfg.
"""

import argparse
import ast
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "follow_bot_common" / "cmake"))
from cfg_defaults import read_cfg  # noqa: E402  (the one .cfg reader, also the build's)

BLOCK = re.compile(r"(<!-- params: (?P<cfg>\S+) -->\n)(?P<table>.*?)(<!-- end params -->)", re.S)
UNIT = re.compile(r"^(?P<text>.*?)\s*\[(?P<unit>[^\]]+)\]$")
NONE = "\N{EN DASH}"  # an empty cell
TYPES = {"int": "int", "double": "double", "str": "string", "bool": "bool"}


def number(value) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def row(param: dict) -> str:
    kind = param["type"]
    match = UNIT.match(param["description"])
    text, unit = (match["text"], match["unit"]) if match else (param["description"], NONE)
    if kind in ("int", "double"):
        default = number(param["default"])
        value_range = f"[{number(param['min'])}, {number(param['max'])}]"
    elif kind == "bool":
        default, value_range = str(param["default"]).lower(), "true, false"
    else:
        default = f"'{param['default']}'" if param["default"] else "'' (none)"
        choices = param["edit_method"] and ast.literal_eval(param["edit_method"])["enum"]
        value_range = ", ".join(c["value"] for c in choices) if choices else NONE
    cells = [f"`~{param['name']}`", TYPES[kind], f"`{default}`", value_range, unit, text]
    return "| " + " | ".join(cells) + " |"


def table(cfg: Path) -> str:
    lines = ["| parameter | type | default | range | unit | meaning |", "| --- " * 6 + "|"]
    return "\n".join(lines + [row(p) for p in read_cfg(cfg)]) + "\n"


def documents() -> list[Path]:
    readmes = [ROOT / "README.md", *ROOT.glob("*/README.md")]
    return sorted([*readmes, *ROOT.glob("*/doc/*.md"), *ROOT.glob("docs/*.md")])


def regenerate(text: str) -> str:
    return BLOCK.sub(lambda m: m[1] + table(ROOT / m["cfg"]) + m[4], text)


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--write", action="store_true", help="rewrite the tables in place")
    args = parser.parse_args()
    stale = []
    for doc in documents():
        text = doc.read_text()
        fresh = regenerate(text)
        if fresh != text:
            stale.append(doc.relative_to(ROOT))
            if args.write:
                doc.write_text(fresh)
    for doc in stale:
        print(f"{doc}: {'rewrote' if args.write else 'stale'} parameter tables", file=sys.stderr)
    return 1 if stale and not args.write else 0


if __name__ == "__main__":
    sys.exit(main())
