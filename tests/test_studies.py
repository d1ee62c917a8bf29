"""Each study script (``studies/*/run.py``) is a client of the public API: it imports only ``shipid`` and
``shipid.api`` and uses only their public names, so that every figure it publishes is one a user gets
from ``shipid.identify`` / ``shipid.validate`` / ``shipid.simulate`` or the commands."""

import ast
from pathlib import Path

import pytest

import shipid
import shipid.api

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted((ROOT / "studies").glob("*/run.py"))
PUBLIC = {"shipid": set(shipid.__all__), "shipid.api": set(shipid.api.__all__)}


def shipid_uses(source: str) -> list[str]:
    """Every import of a ``shipid`` module and every ``shipid.<name>`` / ``<alias>.<name>`` the code uses that is
    not a public name of ``shipid`` or ``shipid.api`` (empty: the code keeps to the public API)."""
    tree = ast.parse(source)
    bad, alias = [], {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] != "shipid":
                    continue
                if a.name not in PUBLIC:
                    bad.append(f"import {a.name}")
                else:
                    alias[a.asname or a.name.split(".")[0]] = a.name if a.asname else "shipid"
        elif isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "shipid":
            if node.level or node.module not in PUBLIC:
                bad.append(f"from {node.module} import ...")
                continue
            for a in node.names:
                if a.name not in PUBLIC[node.module] and not (node.module == "shipid" and a.name == "api"):
                    bad.append(f"from {node.module} import {a.name}")
                elif node.module == "shipid" and a.name == "api":
                    alias[a.asname or "api"] = "shipid.api"
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in alias:
            mod = alias[node.value.id]
            if node.attr not in PUBLIC[mod] and not (mod == "shipid" and node.attr == "api"):
                bad.append(f"{mod}.{node.attr}")
        elif (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Attribute)
              and isinstance(node.value.value, ast.Name) and alias.get(node.value.value.id) == "shipid"
              and node.value.attr == "api" and node.attr not in PUBLIC["shipid.api"]):
            bad.append(f"shipid.api.{node.attr}")
    return bad


def test_the_checker_finds_private_uses():
    assert shipid_uses("import shipid\nshipid.identify('mmg', [])\nfrom shipid.api import validate\n") == []
    assert shipid_uses("import shipid.methods.mmg.staged as S\n") == ["import shipid.methods.mmg.staged"]
    assert shipid_uses("from shipid.methods.mmg import pipeline\n") == ["from shipid.methods.mmg import ..."]
    assert shipid_uses("import shipid\nshipid.methods.mmg\n") == ["shipid.methods"]
    assert shipid_uses("from shipid import models\n") == ["from shipid import models"]
    assert shipid_uses("import shipid\nshipid.api._private\n") == ["shipid.api._private"]


@pytest.mark.parametrize("script", SCRIPTS, ids=[p.parent.name for p in SCRIPTS])
def test_each_study_imports_only_public_names(script):
    assert shipid_uses(script.read_text(encoding="utf-8")) == []


def test_there_are_studies():
    assert SCRIPTS, "no studies/*/run.py found"


def _splits():
    """The papers' Esso Osaka splits as the study scripts read them (``studies/esso_runs.py``)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("esso_runs", ROOT / "studies" / "esso_runs.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.SPLITS


def test_esso_splits_are_disjoint_and_match_the_readme_counts():
    # esso_osaka_3m/README_upstream.md: Miyauchi Train-TRZ has 6 runs and 5 test runs; Wakita Train-TZRB+ 35, test 6
    splits = _splits()
    for name, n_train, n_test in (("miyauchi2022", 6, 5), ("wakita2022", 35, 6)):
        sp = splits[name]
        assert len(sp["train"]) == n_train and len(sp["test"]) == n_test
        assert not set(sp["train"]) & set(sp["test"])


def test_esso_split_files_exist(data_root):
    for sp in _splits().values():
        for f in sp["train"] + sp["test"]:
            assert (data_root / "esso_osaka_3m" / "data" / f).is_file(), f
