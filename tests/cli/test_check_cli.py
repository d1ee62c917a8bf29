"""``shipid check`` names where every channel came from, never ``None`` (issue 13)."""

import json

import numpy as np

from shipid.cli import main


def _kvlcc2_like(path, n=200):
    """A file in the HSVA KVLCC2 layout: 4 header lines, 12 unnamed columns (u, v derived by the reader)."""
    t = np.arange(n) * 0.05
    psi = 5.0 * np.sin(0.1 * t)
    rows = np.column_stack([t, 1.18 * t, 0.01 * t, psi, np.full(n, 1.18), np.full(n, 0.01),
                            np.gradient(psi, t), np.zeros(n), 10.0 * np.sign(np.sin(0.1 * t)),
                            np.full(n, 10.23), np.full(n, 41.0), np.full(n, 1.0)])
    head = " HSVA, experimental data CPMC\n KVLCC2\n Z10/10 starting to starboard\n Time series of motions\n"
    path.write_bytes((head + "\n".join(" ".join(f"{v:18.9f}" for v in r) for r in rows) + "\n").encode("cp1252"))
    return path


def test_check_kvlcc2_never_prints_none(tmp_path, capsys):
    f = _kvlcc2_like(tmp_path / "HSVA_CPMC_KVLCC2_Z_10_10_S.dat")
    assert main(["check", str(f)]) == 0
    out = capsys.readouterr().out
    assert "None" not in out
    lines = {ln.split()[0]: ln for ln in out.splitlines()[1:] if ln.startswith("  ")}
    assert "derived: x_dot*cos(psi) + y_dot*sin(psi)" in lines["u"]
    assert "derived: -x_dot*sin(psi) + y_dot*cos(psi)" in lines["v"]
    assert "from x0 [m]" in lines["x"]


def test_check_kvlcc2_json_says_how_u_was_derived(tmp_path, capsys):
    f = _kvlcc2_like(tmp_path / "HSVA_CPMC_KVLCC2_Z_10_10_S.dat")
    assert main(["check", str(f), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["channels"]["u"]["column"] is None
    assert d["channels"]["u"]["derived"].startswith("x_dot*cos(psi)")
    assert d["channels"]["x"]["derived"] is None


def test_check_out_writes_the_json_it_prints_and_refuses_to_clobber(tmp_path, capsys):
    f = _kvlcc2_like(tmp_path / "HSVA_CPMC_KVLCC2_Z_10_10_S.dat")
    out = tmp_path / "summary.json"
    assert main(["check", str(f), "--json", "-o", str(out)]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert json.loads(out.read_text(encoding="utf-8")) == printed and printed["samples"] == 200
    assert main(["check", str(f), "-o", str(out)]) == 2
    assert capsys.readouterr().err.strip() == f"shipid: error: {out}: output file exists (use --force to overwrite)"
    assert main(["check", str(f), "-o", str(out), "--force"]) == 0
    assert "200 samples" in capsys.readouterr().out          # without --json: the text summary on stdout
