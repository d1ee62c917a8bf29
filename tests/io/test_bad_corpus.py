"""Every malformed file in tests/io/bad/ is answered by the CLI with exit 2 and one line.

The files are made by ``make_corpus.py``. For each one the table below gives the
extra command-line options (some files are bad only under a stated repair limit)
and a fragment the one-line message must contain, so that the message names the
problem and not just "error".
"""

import subprocess
import sys
from pathlib import Path

import pytest

from shipid.cli import main

BAD = Path(__file__).parent / "bad"

EXPECTED: dict[str, tuple[list[str], str]] = {
    "empty.csv": ([], "empty file"),
    "whitespace_only.csv": ([], "empty file"),
    "header_only.csv": ([], "header only, no data rows"),
    "nan_value.csv": ([], "channel 'u', row 3: missing value"),
    "empty_cell.csv": ([], "channel 'psi', row 2: missing value"),
    "inf_value.csv": ([], "channel 'x', row 4: infinite value"),
    "nonmonotonic_time.csv": ([], "channel 't', row 5: time not increasing"),
    "duplicate_timestamp.csv": ([], "channel 't', row 4: duplicated timestamp"),
    "negative_dt.csv": ([], "channel 't', row 2: time not increasing"),
    "unknown_unit.csv": ([], "channel 'u': unknown unit 'blorps'"),
    "missing_channel.csv": (["--require", "u,v,r"], "channel 'v': required channel missing"),
    "text_in_numeric.csv": ([], "channel 'u', row 4: not a number: 'abc'"),
    "semicolon_mixed_decimal.csv": ([], "semicolon-separated with a decimal comma (row 3) and a decimal point"),
    "ambiguous_delimiter.csv": ([], "cannot tell the delimiter"),
    "pipe_delimiter.csv": ([], "separated by '|'"),
    "binary_junk.csv": ([], "binary content"),
    "non_uniform_sampling.csv": ([], "channel 't', row 4: non-uniform sampling"),
    "duplicate_column.csv": ([], "channel 'x': duplicate column name"),
    "missing_unit_brackets.csv": ([], "channel 'x': no unit in header cell 'x'"),
    "too_few_fields.csv": ([], "row 3: has 2 fields, the header has 4"),
    "too_many_fields.csv": ([], "row 5: has 5 fields, the header has 4"),
    "header_garbage.csv": ([], "malformed header cell 'x [m]]]'"),
    "no_header_numbers.csv": ([], "no header line"),
    "empty_header_cell.csv": ([], "empty header cell in column 2"),
    "no_time_column.csv": ([], "no time column 't'"),
    "time_in_metres.csv": ([], "channel 't': unit 'm' is not a unit of s"),
    "wrong_unit_dimension.csv": ([], "channel 'psi': unit 'm' is not a unit of rad"),
    "single_row.csv": ([], "only one data row"),
    "time_gap.csv": ([], "channel 't', row 5: time gap of 0.7 s"),
    "time_gap_too_long.csv": (["--interpolate-gaps", "0.5"], "longer than --interpolate-gaps 0.5 s"),
    "nan_gap_too_long.csv": (["--interpolate-gaps", "0.3"], "channel 'u', row 4: missing value (empty cell or "
                                                            "NaN): gap of 0.5 s"),
    "nan_at_start.csv": (["--interpolate-gaps", "1"], "row 1: missing value (empty cell or NaN) at the start"),
    "trailing_empty_rows.csv": ([], "channel 't', row 7: missing value"),
    "utf16.csv": ([], "UTF-16"),
    "truncated.parquet": ([], "not a readable Parquet file"),
    "csv_named_parquet.parquet": ([], "not a readable Parquet file"),
    "parquet_named_csv.csv": ([], "is a Parquet file, not CSV"),
    "parquet_no_units.parquet": ([], "channel 't': no unit"),
    "wrong_extension.xlsx": ([], "cannot tell the format from the extension '.xlsx'"),
    "kvlcc2_short_row.dat": ([], "row 3: has 11 fields"),
    "kvlcc2_header_only.dat": ([], "header only"),
}

FILES = sorted(p.name for p in BAD.iterdir() if p.is_file())
# a few go through a real subprocess (the console path, not only main())
SUBPROCESS = ["binary_junk.csv", "nan_value.csv", "truncated.parquet", "utf16.csv", "missing_channel.csv"]


def test_corpus_is_complete():
    assert len(FILES) >= 22
    assert set(FILES) == set(EXPECTED), "every bad file needs an expectation and vice versa"


def _check(rc, stderr, name, fragment):
    assert rc == 2
    assert "Traceback" not in stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    line = lines[0]
    assert line.startswith("shipid: error: ")
    assert name in line            # the file is named
    assert fragment in line        # and the problem


@pytest.mark.parametrize("name", FILES)
def test_cli_check_answers_bad_file(name, capsys):
    args, fragment = EXPECTED[name]
    rc = main(["check", str(BAD / name), *args])
    out, err = capsys.readouterr()
    _check(rc, err, name, fragment)
    assert out == ""


@pytest.mark.parametrize("name", SUBPROCESS)
def test_cli_subprocess_answers_bad_file(name):
    args, fragment = EXPECTED[name]
    proc = subprocess.run([sys.executable, "-m", "shipid", "check", str(BAD / name), *args],
                          capture_output=True, text=True, timeout=60)
    _check(proc.returncode, proc.stderr, name, fragment)


def test_convert_answers_bad_file_and_writes_nothing(tmp_path, capsys):
    dest = tmp_path / "out.csv"
    rc = main(["convert", str(BAD / "duplicate_timestamp.csv"), str(dest)])
    _check(rc, capsys.readouterr().err, "duplicate_timestamp.csv", "duplicated timestamp")
    assert not dest.exists()
