"""``shipid report RESULT.json --out report.html``: writes atomically, never clobbers, one-line errors."""

import subprocess
import sys

from shipid.cli import main
from report.examples import mass_cm_example
from shipid.result import Estimate, Result


def _small_result(tmp_path):
    p = tmp_path / "result.json"
    Result("ebm", {"N_r": Estimate(-1.7e-3, 5e-5, "-")}, model={"vessel": "esso-osaka"}).write_json(p)
    return p


def test_report_written_and_not_clobbered(tmp_path, capsys):
    res = _small_result(tmp_path)
    out = tmp_path / "sub" / "report.html"
    assert main(["report", str(res), "--out", str(out)]) == 0
    text = out.read_text(encoding="utf-8")
    assert "N_r" in text and "esso-osaka" in text
    assert f"report written to {out}" in capsys.readouterr().out
    out.write_text("keep me")
    assert main(["report", str(res), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "exists" in err[0] and "--force" in err[0]
    assert out.read_text() == "keep me"
    assert main(["report", str(res), "--out", str(out), "--force"]) == 0
    assert "N_r" in out.read_text(encoding="utf-8")
    assert [p.name for p in out.parent.iterdir()] == ["report.html"]  # no temporary left behind


def test_bad_inputs_are_one_line_exit_2(tmp_path, capsys):
    out = tmp_path / "r.html"
    bad_json = tmp_path / "bad.json"
    bad_json.write_text('{"method": "dp", "estimates": {')
    not_result = tmp_path / "list.json"
    not_result.write_text("[1, 2, 3]")
    bad_est = tmp_path / "est.json"
    bad_est.write_text('{"method": "dp", "estimates": {"a": {"value": 1, "colour": "red"}}}')
    binary = tmp_path / "bin.json"
    binary.write_bytes(b"\xff\xfe\x00\x81")
    for path, words in [(tmp_path / "missing.json", "no such file"), (bad_json, "not valid JSON"),
                        (not_result, "not a shipid result"), (bad_est, "not a valid shipid result"),
                        (binary, "not a text file"), (tmp_path, "directory")]:
        assert main(["report", str(path), "--out", str(out)]) == 2, path
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and words in err[0] and str(path) in err[0], err
        assert not out.exists()


def test_subprocess_end_to_end(tmp_path):
    res = tmp_path / "masscm.json"
    mass_cm_example().write_json(res)
    out = tmp_path / "masscm.html"
    proc = subprocess.run([sys.executable, "-m", "shipid", "report", str(res), "--out", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    html = out.read_text(encoding="utf-8")
    assert html.count('<img src="data:image/png;base64,') == 4 and "Linder et al. 2015, Fig. 4)" in html
    proc = subprocess.run([sys.executable, "-m", "shipid", "report", str(tmp_path / "nope.json"), "--out",
                           str(tmp_path / "x.html")], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1
