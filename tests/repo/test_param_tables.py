"""The parameter tables of the READMEs and the nodes' manuals (<package>/doc/*.md) are generated
from the .cfg files: they fail this test as soon as a .cfg (name, type, default, range, unit,
description) and its table drift apart."""

import subprocess
import sys

from harness.testing import REPO as ROOT

sys.path.insert(0, str(ROOT / "tools"))

import param_tables

CFGS = sorted(ROOT.glob("*/cfg/*.cfg"))


def test_every_cfg_has_exactly_one_table():
    tables = [
        match["cfg"]
        for doc in param_tables.documents()
        for match in param_tables.BLOCK.finditer(doc.read_text())
    ]
    assert sorted(tables) == [str(cfg.relative_to(ROOT)) for cfg in CFGS]


def test_the_tables_match_the_cfgs():
    result = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "param_tables.py")], capture_output=True, text=True
    )
    assert result.returncode == 0, result.stderr + "run `make docs` to regenerate them"


def test_a_changed_default_makes_the_table_stale(tmp_path):
    cfg = ROOT / "follow_bot" / "cfg" / "Parker.cfg"
    changed = tmp_path / "Parker.cfg"
    changed.write_text(cfg.read_text().replace('"Top turn rate [rad/s]", 1.2', '"x [rad/s]", 1.3'))
    assert "| `~max_angular` | double | `1.2` | [0.01, 10] | rad/s | Top turn rate |" in (
        param_tables.table(cfg)
    )
    assert "| `~max_angular` | double | `1.3` | [0.01, 10] | rad/s | x |" in (
        param_tables.table(changed)
    )


def test_every_number_has_a_range_and_every_description_a_text():
    for cfg in CFGS:
        for param in param_tables.read_cfg(cfg):
            assert param["description"].strip(), (cfg, param["name"])
            if param["type"] in ("int", "double"):
                assert abs(param["min"]) < 1e9 and abs(param["max"]) < 1e9, (cfg, param["name"])
