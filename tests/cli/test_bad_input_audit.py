"""Audit (issue 13 follow-up): bad user input to the data-reading commands fails loudly.

Each defect is built in tmp_path from one small valid trial file; the command must exit 2 with
exactly one stderr line ``shipid: error: FILE, channel 'C', row R: ...`` (file/channel/row where the
defect has them), no traceback, no raw Python warning, and must not write its output file.
"""

import pytest

from shipid.cli import main
from shipid.io.files import write_trial
from shipid.methods.ebm.trials import simulate_trial

ROW = 10  # the data row (0-based) a defect is put in; reported as file row 11 (header is row 0... 1-based data)


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    p = tmp_path_factory.mktemp("audit") / "good.csv"
    write_trial(simulate_trial("zigzag-20", 200.0, seed=1), p)
    return p


def _variant(good, tmp_path, kind):
    lines = good.read_text().splitlines()
    hdr, rows = lines[0].split(","), [ln.split(",") for ln in lines[1:]]
    ci = 2  # 'y [m]', a channel every reader uses

    def cell(val):
        return [r if i != ROW else r[:ci] + [val] + r[ci + 1:] for i, r in enumerate(rows)]

    def timecell(src):
        return [r if i != ROW else [rows[src][0]] + r[1:] for i, r in enumerate(rows)]

    texts = {
        "nan_cell": (hdr, cell("nan")), "empty_cell": (hdr, cell("")), "text_cell": (hdr, cell("abc")),
        "dup_time": (hdr, timecell(ROW - 1)), "nonmono_time": (hdr, timecell(5)),
    }
    if kind in texts:
        h, rs = texts[kind]
        text = "\n".join([",".join(h)] + [",".join(r) for r in rs]) + "\n"
    else:
        text = {"empty": "", "header_only": ",".join(hdr) + "\n"}[kind]
    p = tmp_path / f"{kind}.csv"
    p.write_text(text)
    return p


# defect -> (channel, row) the one error line must name; None where the defect has no channel/row
EXPECT = {
    "nan_cell": ("'y'", "row 11"), "empty_cell": ("'y'", "row 11"), "text_cell": ("'y'", "row 11"),
    "dup_time": ("'t'", "row 11"), "nonmono_time": ("'t'", "row 11"),
    "empty": None, "header_only": None,
}
COMMANDS = {
    "check": lambda f, out: ["check", str(f)],
    "convert": lambda f, out: ["convert", str(f), str(out)],
    "identify-ebm": lambda f, out: ["identify", "ebm", "--trial", str(f), "--json", "-o", str(out)],
}


@pytest.mark.parametrize("kind", sorted(EXPECT))
@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_bad_input_is_one_error_line_exit_2(good, tmp_path, capsys, command, kind):
    f = _variant(good, tmp_path, kind)
    out = tmp_path / "out.csv"
    assert main(COMMANDS[command](f, out)) == 2
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith(f"shipid: error: {f}")
    assert "Traceback" not in err and "Warning:" not in err and ".py" not in err
    if EXPECT[kind]:
        chan, row = EXPECT[kind]
        assert f"channel {chan}" in lines[0] and row in lines[0]
    assert not out.exists()


def test_convert_does_not_clobber_an_existing_dest(good, tmp_path, capsys):
    dest = tmp_path / "dest.csv"
    dest.write_text("keep me\n")
    rc = main(["convert", str(good), str(dest)])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err
    assert dest.read_text() == "keep me\n"
