"""Whatever bytes arrive, the front door answers with a Trial or an InputError, nothing else."""

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from shipid.io import Trial, read_trial
from shipid.errors import InputError

GOOD = Path(__file__).parent / "good"
SIMPLE = (GOOD / "simple.csv").read_bytes()
HSVA = (GOOD / "small_hsva.dat").read_bytes()

SETTINGS = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


def answer(path, data: bytes, **kw):
    path.write_bytes(data)
    try:
        tr = read_trial(path, **kw)
    except InputError as err:
        text = str(err)
        assert "\n" not in text and str(path) in text
        return None
    assert isinstance(tr, Trial)
    assert np.all(np.isfinite(tr.t)) and np.all(np.diff(tr.t) > 0)
    for v in tr.channels.values():
        assert np.all(np.isfinite(v))
    return tr


@SETTINGS
@given(data=st.binary(max_size=400), ext=st.sampled_from([".csv", ".dat", ".parquet"]))
# found by this test in CI (2026-11-22): control characters that str.splitlines takes for line breaks
# left no line at all and raised IndexError instead of an InputError
@example(data=b"\x1c", ext=".csv")
@example(data=b"\xc2\x85", ext=".csv")
@example(data=b"t [s],p [rad/s]\n0,1\x1d\n", ext=".csv")
@example(data=b"\x0c\x0b", ext=".dat")
def test_random_bytes(tmp_path, data, ext):
    answer(tmp_path / f"f{ext}", data)


@SETTINGS
@given(cut=st.integers(0, len(SIMPLE)), length=st.integers(0, 40),
       insert=st.text(alphabet=",;[]\n\r\t .-+e0123456789naifNA\"x", max_size=8),
       repair=st.booleans())
def test_mutated_csv(tmp_path, cut, length, insert, repair):
    data = SIMPLE[:cut] + insert.encode() + SIMPLE[cut + length:]
    kw = {"interpolate_gaps": 0.5, "trim_empty_rows": True} if repair else {}
    answer(tmp_path / "m.csv", data, **kw)


@SETTINGS
@given(cut=st.integers(0, len(HSVA)), length=st.integers(0, 40),
       insert=st.text(alphabet=" \n.-0123456789x", max_size=8))
def test_mutated_hsva(tmp_path, cut, length, insert):
    answer(tmp_path / "m.dat", HSVA[:cut] + insert.encode() + HSVA[cut + length:])


def test_parquet_nulls_are_missing_values_with_row(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq
    t = pa.array([0.0, 0.1, 0.2, 0.3], type=pa.float64())
    x = pa.array([1.0, None, 3.0, 4.0], type=pa.float64())
    table = pa.table({"t [s]": t, "x [m]": x})
    pq.write_table(table, tmp_path / "n.parquet")
    with pytest.raises(InputError, match=r"channel 'x', row 2: missing value"):
        read_trial(tmp_path / "n.parquet")
    tr = read_trial(tmp_path / "n.parquet", interpolate_gaps=0.2 + 1e-9)
    np.testing.assert_allclose(tr["x"], [1.0, 2.0, 3.0, 4.0])


def test_quoted_csv_cells(tmp_path):
    p = tmp_path / "q.csv"
    p.write_text('"t [s]","x [m]"\n"0.0","1.5"\n"0.1",2.5\n')
    tr = read_trial(p)
    np.testing.assert_allclose(tr["x"], [1.5, 2.5])
