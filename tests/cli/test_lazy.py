"""Lazy loading: ``shipid --help``, ``shipid vessels``, ``shipid check`` and ``shipid.identify`` import no method.

The groups list their commands from the generated index ``shipid.cli.INDEX``; a command's
module is imported when the command is resolved. The index must be what the command modules say
(names, modules, summaries), and the lazy help must be the help of the fully loaded tree.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import shipid
import shipid.cli
from shipid.cli import INDEX, build_index, load_all_commands, main

SRC = str(Path(shipid.__file__).resolve().parents[1])
PROBE = """
import json, sys
{body}
mods = sys.modules
sys.stderr.write("\\nPROBE " + json.dumps({{"numba": "numba" in mods,
    "methods": sorted(m for m in mods if m.startswith("shipid.methods.") and m.count(".") == 2)}}) + "\\n")
"""


def _fresh(body: str) -> tuple[str, dict]:
    """Run ``body`` in a fresh interpreter; its stdout and what it had imported."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([SRC, *filter(None, [os.environ.get("PYTHONPATH")])]))
    p = subprocess.run([sys.executable, "-c", PROBE.format(body=body)], env=env, capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 0, p.stderr
    probe = json.loads(p.stderr.rsplit("PROBE ", 1)[1])
    return p.stdout, probe


def test_the_index_is_current():
    """If this fails, refresh it: python -c "import shipid.cli as c; c.write_index()"."""
    assert shipid.cli.INDEX_CURRENT, "a command module changed since the index was written: refresh it"
    assert build_index() == INDEX


def test_an_out_of_date_index_is_not_used():
    """With an index whose source key does not match, every command module is imported (slow, never wrong)."""
    body = ("import types; fake = types.ModuleType('shipid.cli._index'); fake.SOURCES = 'stale'; fake.INDEX = {}; "
            "sys.modules['shipid.cli._index'] = fake; import shipid.cli as c; assert not c.INDEX_CURRENT; "
            "c.main(['identify', '--help'])")
    out, probe = _fresh(body)
    assert probe["numba"] and {"shipid.methods.masscm", "shipid.methods.mmg"} <= set(probe["methods"])
    assert "mass-cm" in out and "mmg" in out


@pytest.mark.parametrize("args", [["--help"], ["identify", "--help"], ["study", "--help"], ["analyse", "--help"]],
                         ids=" ".join)
def test_group_help_imports_no_method_and_equals_the_loaded_help(args, capsys):
    out, probe = _fresh(f"from shipid.cli import main; main({args!r})")
    assert probe == {"numba": False, "methods": []}
    load_all_commands()
    assert main(args) == 0
    assert capsys.readouterr().out == out


def test_vessels_and_check_import_no_method(tmp_path):
    f = tmp_path / "t.csv"
    f.write_text("t [s],u [m/s],r [rad/s],delta [rad]\n0,1,0,0\n0.1,1,0,0.01\n0.2,1,0.001,0.02\n", encoding="utf-8")
    body = f"from shipid.cli import main; assert main(['vessels']) == 0; assert main(['check', {str(f)!r}]) == 0"
    out, probe = _fresh(body)
    assert probe == {"numba": False, "methods": []}
    assert "fishing-vessel" in out and "3 samples" in out


def test_a_command_is_imported_when_it_runs():
    out, probe = _fresh("from shipid.cli import main; assert main(['identify', 'mass-cm', '--help']) == 0")
    assert "shipid.methods.masscm" in probe["methods"] and "shipid.methods.mmg" not in probe["methods"]
    assert "Usage: shipid identify mass-cm" in out


def test_import_shipid_is_cheap_and_keeps_its_api():
    out, probe = _fresh("import shipid; print(sorted(m for m in ('numpy', 'numba', 'click') if m in sys.modules)); "
                        "print(shipid.__version__, callable(shipid.identify), shipid.Result.__name__)")
    first, second = out.splitlines()
    assert first == "[]"                                  # import shipid alone: none of them
    assert second.split() == [shipid.__version__, "True", "Result"]
    assert probe == {"numba": False, "methods": []}       # shipid.identify alone loads no method


def _imported_by(body: str) -> list[str]:
    out, _ = _fresh(body + "; print(json.dumps(sorted(sys.modules)))")
    return json.loads(out.splitlines()[-1])


def test_shipid_identify_imports_no_click_and_no_method():
    """``import shipid; shipid.identify``: no click, no numba, nothing under ``shipid.methods``, no scipy.signal."""
    mods = _imported_by("import shipid; shipid.identify; shipid.validate; shipid.Result")
    heavy = [m for m in mods if m.split(".")[0] in ("click", "numba", "pandas")
             or m.startswith(("shipid.methods", "shipid.cli", "scipy.signal", "scipy.stats"))]
    assert heavy == []


@pytest.mark.parametrize("name, package", [("mass-cm", "masscm"), ("dp", "dp"), ("ebm", "ebm"), ("mmg", "mmg")])
def test_a_method_named_loads_that_method_only(name, package):
    """``registry.get(name).identify`` (what ``shipid.identify(name, ...)`` runs) imports that method's
    package and no other, and no command-line module."""
    mods = _imported_by(f"import shipid; from shipid import registry; registry.get({name!r}).identify; "
                        f"registry.get({name!r}).options")
    methods = {m.split(".")[2] for m in mods if m.startswith("shipid.methods.") and not m.split(".")[2].startswith("_")}
    assert methods == {package}
    assert [m for m in mods if m.split(".")[0] == "click" or m.startswith("shipid.cli")] == []


def test_the_monitor_imports_no_scipy_signal():
    mods = _imported_by("import shipid.methods.monitor.estimator, shipid.methods.monitor.bj_prefilter")
    assert [m for m in mods if m.startswith(("scipy.signal", "scipy.stats", "click"))] == []
