"""CSV dialects (shipid.io.csv_dialect): ',', ';' or tab delimiters and a decimal comma."""

import numpy as np
import pytest

from shipid.cli import main
from shipid.io import read_trial
from shipid.io.csv_dialect import Dialect, detect_dialect
from shipid.errors import InputError

T = [0.0, 0.1, 0.2, 0.3]
X = [0.0, 0.125, 0.25, 0.375]
PSI = [0.0, 0.001, 0.002, 0.003]


def _write(path, sep, decimal="."):
    lines = [sep.join(["t [s]", "x [m]", "psi [rad]"])]
    for row in zip(T, X, PSI):
        lines.append(sep.join(repr(v).replace(".", decimal) for v in row))
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("sep, decimal, name", [(",", ".", "comma"), (";", ".", "semicolon"),
                                                (";", ",", "semicolon"), ("\t", ".", "tab"),
                                                ("\t", ",", "tab")])
def test_dialects_read_the_same_numbers(tmp_path, sep, decimal, name):
    tr = read_trial(_write(tmp_path / "d.csv", sep, decimal))
    assert tr.meta["csv_dialect"] == {"delimiter": name, "decimal": decimal}
    np.testing.assert_array_equal(tr.t, T)
    np.testing.assert_array_equal(tr["x"], X)
    np.testing.assert_array_equal(tr["psi"], PSI)


def test_detect_rules():
    assert detect_dialect("t [s]", ["0", "0.1"]) == Dialect(",", ".")
    assert detect_dialect("t [s],x [m]", ["0,1"]) == Dialect(",", ".")
    # ';' in the header and ',' inside the brackets: only ';' counts
    assert detect_dialect("t [s];N [kN,m]", ["0;1,5"]) == Dialect(";", ",")
    # both in the header outside brackets: the one that splits the rows like the header wins
    assert detect_dialect("t [s];x, east [m]", ["0;1,5", "0,1;2,5"]) == Dialect(";", ",")
    assert detect_dialect("t [s]\tx [m]", ["0\t1", "0.1\t2"]) == Dialect("\t", ".")


def test_ambiguous_delimiter_is_one_line(tmp_path):
    p = tmp_path / "a.csv"
    p.write_text("t [s],x [m];u [m/s],psi [rad]\n0,1;2,3\n0.1,1;2,3\n")
    with pytest.raises(InputError, match="cannot tell the delimiter: the header holds both comma and semicolon"):
        read_trial(p)


def test_mixed_decimal_marks_are_an_error_naming_rows(tmp_path):
    p = tmp_path / "m.csv"
    p.write_text("t [s];x [m]\n0;1,5\n0.1;2,5\n")
    with pytest.raises(InputError, match=r"decimal comma \(row 1\) and a decimal point \(row 2\)") as info:
        read_trial(p)
    assert "\n" not in str(info.value) and str(p) in str(info.value)
    assert main(["check", str(p)]) == 2


def test_pipe_is_still_named(tmp_path):
    p = tmp_path / "p.csv"
    p.write_text("t [s]|x [m]\n0|1\n0.1|2\n")
    with pytest.raises(InputError, match="separated by '\\|'"):
        read_trial(p)


def test_cli_check_semicolon_decimal_comma(tmp_path, capsys):
    p = _write(tmp_path / "eu.csv", ";", ",")
    assert main(["check", str(p), "--json"]) == 0
    assert '"samples": 4' in capsys.readouterr().out
