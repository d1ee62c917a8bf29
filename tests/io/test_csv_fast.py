"""The compiled CSV path gives what the cell-by-cell path gives: the same doubles, or the same one-line error.

:func:`shipid.io.csv_read.read_csv_table` parses with pyarrow first and falls back to the
careful path on any doubt; each file below is read both ways (the fast path switched off
by monkeypatching) and the results compared bit for bit.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from shipid.errors import InputError
from shipid.io import csv_read
from shipid.io.files import read_trial

HEAD = "t [s],x [m],psi [deg]\n"
ROWS = [f"{0.1 * i:.1f},{1.5 * i - 3.25:.17g},{np.sin(i) * 90:.17g}" for i in range(300)]

CASES = {
    "plain": HEAD + "\n".join(ROWS) + "\n",
    "no final newline": HEAD + "\n".join(ROWS),
    "crlf": (HEAD + "\n".join(ROWS) + "\n").replace("\n", "\r\n"),
    "cr": (HEAD + "\n".join(ROWS) + "\n").replace("\n", "\r"),
    "trailing blank lines": HEAD + "\n".join(ROWS) + "\n\n\n",
    "blank line inside": HEAD + "\n".join(ROWS[:250]) + "\n\n" + "\n".join(ROWS[251:]) + "\n",
    "empty cell": HEAD + "\n".join(ROWS[:5]) + "\n0.5,,1\n" + "\n".join(ROWS[6:]) + "\n",
    "spaces cell": HEAD + "\n".join(ROWS[:5]) + "\n0.5,  ,1\n" + "\n".join(ROWS[6:]) + "\n",
    "spellings": HEAD + "0,.5,5.\n0.1,+1,1e5\n0.2,-0,1E-3\n0.3,nan,inf\n0.4,-inf,NaN\n",
    "NA text": HEAD + "\n".join(ROWS[:250]) + "\n25,NA,1\n" + "\n".join(ROWS[251:]) + "\n",
    "underscore": HEAD + "0,1_0,1\n0.1,2,2\n",
    "too few fields": HEAD + "\n".join(ROWS[:220]) + "\n22,1\n" + "\n".join(ROWS[221:]) + "\n",
    "too many fields": HEAD + "\n".join(ROWS[:220]) + "\n22,1,2,3\n" + "\n".join(ROWS[221:]) + "\n",
    "quoted": HEAD + '0,"1.5",2\n0.1,2,3\n',
    "bom": "\ufeff" + HEAD + "\n".join(ROWS) + "\n",
    "semicolon decimal comma": "t [s];x [m];psi [deg]\n" + "\n".join(
        r.replace(",", ";").replace(".", ",") for r in ROWS) + "\n",
    "tab": "t [s]\tx [m]\tpsi [deg]\n" + "\n".join(r.replace(",", "\t") for r in ROWS) + "\n",
    "empty cells row at the end": HEAD + "\n".join(ROWS) + "\n,,\n",
    "spaces after the last row": HEAD + "\n".join(ROWS) + "\n  \n",
    "own headers": "Time (ms),X_m,Heading (deg)\n" + "\n".join(ROWS) + "\n",
}


@pytest.fixture(autouse=True)
def _fast_path_for_small_files(monkeypatch):
    """These files are small: let them take the fast path (by default a small file skips pyarrow)."""
    monkeypatch.setattr(csv_read, "FAST_MIN_BYTES", 0)


def _read(path):
    try:
        t = csv_read.read_csv_table(path, str(path))
    except InputError as err:
        return str(err)
    return t


@pytest.mark.parametrize("name", list(CASES))
def test_fast_and_careful_paths_agree(tmp_path, monkeypatch, name):
    p = tmp_path / "f.csv"
    p.write_bytes(CASES[name].encode("utf-8"))
    fast = _read(p)
    with monkeypatch.context() as m:
        m.setattr(csv_read, "_fast", lambda *a, **k: None)
        slow = _read(p)
    if isinstance(slow, str) or isinstance(fast, str):
        assert fast == slow
        return
    assert fast.names == slow.names and fast.units == slow.units
    assert fast.data.shape == slow.data.shape
    same = (fast.data == slow.data) | (np.isnan(fast.data) & np.isnan(slow.data))
    assert same.all()
    np.testing.assert_array_equal(np.signbit(fast.data), np.signbit(slow.data))
    np.testing.assert_array_equal(fast.rows, slow.rows)


def test_many_record_batches_give_the_same_doubles(tmp_path, monkeypatch):
    """A file parsed in many blocks (batch boundaries inside it) equals the cell-by-cell read."""
    p = tmp_path / "f.csv"
    p.write_bytes(CASES["empty cell"].encode("utf-8"))
    monkeypatch.setattr(csv_read, "BLOCK_BYTES", 1 << 10)
    fast = _read(p)
    monkeypatch.setattr(csv_read, "_fast", lambda *a, **k: None)
    slow = _read(p)
    same = (fast.data == slow.data) | (np.isnan(fast.data) & np.isnan(slow.data))
    assert fast.data.shape == (300, 3) and same.all() and np.isnan(fast.data[5, 1])


def test_a_good_file_takes_the_fast_path_and_its_columns_are_contiguous(tmp_path, monkeypatch):
    p = tmp_path / "f.csv"
    p.write_text(CASES["plain"])
    calls = []
    real = csv_read._fast
    monkeypatch.setattr(csv_read, "_fast", lambda *a: calls.append(1) or real(*a))
    tr = read_trial(p)
    assert calls and tr["x"].flags.c_contiguous and tr.t.flags.c_contiguous
    assert tr["psi"][3] == np.deg2rad(float(ROWS[3].split(",")[2]))


def test_underscore_units_read_where_nothing_else_names_the_unit(tmp_path):
    from shipid.io.files import write_trial
    from shipid.io.trial import Trial

    t = np.arange(5) * 0.1
    tr = Trial(t, {"true_N": np.ones(5), "a_s": np.zeros(5)}, {"true_N": "N*m", "a_s": "m/s^2"})
    write_trial(tr, tmp_path / "t.parquet")          # the unit in the schema metadata keeps 'true_N' whole
    back = read_trial(tmp_path / "t.parquet")
    assert back.names == ["true_N", "a_s"] and back.units["true_N"] == "N*m"
    (tmp_path / "u.csv").write_text("time_s,speed_kn,a_s [m/s^2]\n0,1,0\n0.5,2,0\n")
    u = read_trial(tmp_path / "u.csv", channel_map="t=time")
    assert u.names == ["speed", "a_s"] and u["speed"][1] == pytest.approx(2 * 1852 / 3600)


def test_a_small_file_is_read_without_loading_pyarrow(tmp_path):
    """Under FAST_MIN_BYTES the checked path reads the file and pyarrow is not imported (start-up of
    ``shipid check`` / ``shipid validate``); the numbers are those of the fast path."""
    p = tmp_path / "f.csv"
    p.write_text(CASES["plain"])
    code = ("import sys; from shipid.io.files import read_trial; tr = read_trial(sys.argv[1]); "
            "print('pyarrow' in sys.modules, repr(float(tr['psi'][7])))")
    env = {**os.environ, "PYTHONPATH": str(Path(csv_read.__file__).parents[2])}
    out = subprocess.run([sys.executable, "-c", code, str(p)], capture_output=True, text=True, check=True,
                         env=env).stdout.split()
    assert out[0] == "False"
    assert float(out[1]) == read_trial(p)["psi"][7]          # this process: the fast path (fixture above)
