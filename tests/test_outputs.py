"""Output files follow the umask, are written atomically and are never clobbered without force."""

import dataclasses
import json
import os
import stat
from pathlib import Path

import numpy as np
import pytest

from shipid.cli import main
from shipid.errors import OutputExistsError
from shipid.outputs import atomic_write, atomic_write_text, json_default, jsonable


@pytest.fixture
def umask022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def _mode(p):
    return stat.S_IMODE(os.stat(p).st_mode)


def test_text_file_gets_0644_under_umask_022(tmp_path, umask022):
    p = atomic_write_text(tmp_path / "a.json", "{}")
    assert _mode(p) == 0o644


def test_mode_follows_a_stricter_umask(tmp_path):
    old = os.umask(0o077)
    try:
        p = atomic_write_text(tmp_path / "a.json", "{}")
    finally:
        os.umask(old)
    assert _mode(p) == 0o600


def test_not_clobbered_without_force_and_no_temp_left(tmp_path, umask022):
    p = atomic_write_text(tmp_path / "a.txt", "old")
    with pytest.raises(OutputExistsError):
        atomic_write_text(p, "new")
    assert p.read_text() == "old"
    atomic_write_text(p, "new", force=True)
    assert p.read_text() == "new" and _mode(p) == 0o644
    assert sorted(x.name for x in tmp_path.iterdir()) == ["a.txt"]


def test_failed_write_leaves_old_file_and_no_temp(tmp_path):
    p = atomic_write_text(tmp_path / "a.txt", "old")

    def boom(tmp):
        tmp.write_text("half")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError):
        atomic_write(p, boom, force=True)
    assert p.read_text() == "old"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["a.txt"]


def test_cli_json_csv_and_png_outputs_are_0644(tmp_path, umask022, capsys):
    """Every kind of output a command writes: a trial CSV, a result JSON, a figure PNG, an HTML report."""
    csv = tmp_path / "z.csv"
    assert main(["simulate", "nomoto", "zigzag-10", "--duration", "60",
                 "--out", str(csv)]) == 0
    out = tmp_path / "dp.json"
    png = tmp_path / "dp.png"
    assert main(["study", "dp-supply", "--duration", "120", "--trials", "1", "--out", str(out),
                 "--plot", str(png)]) == 0
    html = tmp_path / "r.html"
    assert main(["report", str(out), "--out", str(html)]) == 0
    capsys.readouterr()
    for p in (csv, out, png, html):
        assert _mode(p) == 0o644, p


def test_jsonable_is_the_one_json_rule():
    @dataclasses.dataclass
    class P:
        a: np.ndarray
        b: float

    obj = {"x": np.float64(0.1), "n": np.int32(3), "arr": np.array([[1.0, np.nan]]), "p": P(np.arange(2), 2.5),
           "path": Path("/tmp/a"), "s": {3, 1}, 7: (1, 2)}
    out = jsonable(obj, strict=True)
    assert out["x"] == 0.1 and type(out["x"]) is float and out["n"] == 3 and type(out["n"]) is int
    assert out["arr"][0][0] == 1.0 and np.isnan(out["arr"][0][1])
    assert out["p"] == {"a": [0, 1], "b": 2.5} and out["path"] == "/tmp/a" and out["s"] == [1, 3]
    assert out["7"] == [1, 2]                                  # keys strings and tuples lists, as in JSON
    assert json.dumps(obj, default=json_default) == json.dumps(out)
    with pytest.raises(TypeError, match="object is not JSON-serialisable"):
        jsonable({"f": object()}, strict=True)
    assert jsonable({"f": 1j}) == {"f": "1j"}                  # not strict: anything else as text
