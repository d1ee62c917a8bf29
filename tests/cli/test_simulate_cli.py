"""`shipid simulate`, `shipid vessels` and `shipid demo`, in-process through main() and once as a subprocess."""

import subprocess
import sys

import numpy as np
import pytest

from shipid.cli import main
from shipid.io import data_root
from shipid.io.files import read_trial
from shipid.simulate.manoeuvres import run_manoeuvre
from shipid.simulate.nomoto import nomoto_model


def test_simulate_writes_csv_that_reads_back(tmp_path, capsys):
    out = tmp_path / "z.csv"
    assert main(["simulate", "nomoto", "zigzag-20", "--out", str(out), "--duration", "120",
                 "--dt", "0.5"]) == 0
    assert "wrote" in capsys.readouterr().out
    tr = read_trial(out)
    ref = run_manoeuvre(nomoto_model(), "zigzag-20", duration=120, dt=0.5)
    assert len(tr) == len(ref) == 241
    for ch in ("x", "y", "psi", "r", "delta", "delta_cmd"):
        np.testing.assert_allclose(tr[ch], ref[ch], rtol=1e-12, atol=1e-12)


def test_simulate_parquet(tmp_path):
    out = tmp_path / "t.parquet"
    assert main(["simulate", "nomoto", "turning-35-port", "--out", str(out), "--duration", "60"]) == 0
    tr = read_trial(out)
    assert tr["r"][-1] < 0 and len(tr) == 601


def test_refuses_to_clobber_without_force(tmp_path, capsys):
    out = tmp_path / "z.csv"
    out.write_text("precious\n")
    assert main(["simulate", "nomoto", "straight", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--force" in err
    assert out.read_text() == "precious\n"
    assert main(["simulate", "nomoto", "straight", "--out", str(out), "--force", "--duration", "10"]) == 0
    assert len(read_trial(out)) == 101


@pytest.mark.parametrize("args,needle", [
    (["no-such-ship", "zigzag-20"], "unknown vessel"),
    (["nomoto", "zigzag"], "unknown manoeuvre"),
    (["nomoto", "dp-surge"], "drives p1"),
    (["nomoto", "zigzag-20", "--duration", "-5"], "duration"),
    (["nomoto", "zigzag-20", "--duration", "1e9"], "limit"),
    (["nomoto", "zigzag-20", "--dt", "0"], "time step"),
])
def test_bad_arguments_one_line_exit_2(tmp_path, capsys, args, needle):
    out = tmp_path / "o.csv"
    assert main(["simulate", *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and needle in err
    assert not out.exists()


def test_bad_extension(tmp_path, capsys):
    assert main(["simulate", "nomoto", "straight", "--out", str(tmp_path / "o.txt")]) == 2
    assert ".csv or .parquet" in capsys.readouterr().err


def test_noise_is_seeded(tmp_path):
    paths = [tmp_path / f"{i}.csv" for i in range(3)]
    for p, seed in zip(paths, (4, 4, 5)):
        assert main(["simulate", "nomoto", "straight", "--out", str(p), "--duration", "30",
                     "--noise", "--seed", str(seed)]) == 0
    a, b, c = (read_trial(p) for p in paths)
    np.testing.assert_array_equal(a["psi"], b["psi"])
    assert not np.array_equal(a["psi"], c["psi"])
    assert 0 < np.std(a["psi"]) < np.deg2rad(0.2)       # default gyro noise 0.1 deg on ψ = 0


def test_subprocess_simulate(tmp_path):
    out = tmp_path / "s.csv"
    proc = subprocess.run([sys.executable, "-m", "shipid", "simulate", "nomoto", "prbs-10-20",
                           "--out", str(out), "--duration", "100", "--seed", "3"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert len(read_trial(out)) == 1001
    proc = subprocess.run([sys.executable, "-m", "shipid", "simulate", "nomoto", "prbs-10",
                           "--out", str(out)], capture_output=True, text=True)
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1
    assert "Traceback" not in proc.stderr


def test_vessels_lists_packaged_vessels_with_sources(capsys):
    assert main(["vessels"]) == 0
    out = capsys.readouterr().out
    for name in ("esso-osaka", "supply", "fishing-vessel", "nomoto"):
        assert name in out
    assert "Yoon" in out and "Fossen" in out and "Linder" in out


@pytest.mark.slow  # ~40 s: one full demo (all three methods and their reports); the slow suite runs it in CI
def test_demo_writes_overwrites_with_force_and_does_not_clobber(tmp_path, capsys):
    """ONE full demo run (the slowest test here): with --force into a folder that already holds
    stale files of names the demo writes, which must all be replaced; then without --force it
    must stop (exit 2) and leave every file as it was."""
    d = tmp_path / "demo"
    d.mkdir()
    stale = ["nomoto_turning-35.csv"] + [f"{kind}-{m}.{ext}" for m in ("mass-cm", "dp", "ebm")
                                         for kind, ext in (("result", "json"), ("report", "html"))]
    for name in stale:
        (d / name).write_text("stale\n")
    assert main(["demo", "--out-dir", str(d), "--force"]) == 0
    out = capsys.readouterr().out
    files = sorted(p.name for p in d.iterdir())
    assert "nomoto_turning-35.csv" in files
    assert "demo done" in out
    skipped = [ln for ln in out.splitlines() if "skipped" in ln]
    root = data_root()
    if root is None or not (root / "kvlcc2_hsva").is_dir():   # the real-data step is named, nothing else
        assert skipped and all("real data" in ln for ln in skipped), skipped
    else:
        assert not skipped, skipped
    for name in stale:
        assert (d / name).read_text(encoding="utf-8")[:6] != "stale\n", name
    for f in files:
        if f.endswith(".csv"):  # the demo also writes result JSON and HTML reports (issue 8)
            assert len(read_trial(d / f)) > 100
    # the reports show the papers' figures and tables (issue 8; details in tests/report), each caption
    # numbered by the report and naming the paper's figure or table at its end (issue 20)
    html = {m: (d / f"report-{m}.html").read_text(encoding="utf-8") for m in ("mass-cm", "dp", "ebm")}
    L, F, Y = "(Linder et al. 2015, ", "(Fossen, Sagatun &amp; Sørensen 1996, ", "(Yoon &amp; Rhee 2003, "
    for m, marks in {"mass-cm": (L + "Fig. 4)", L + "Table 3)", "Roll rate p of the loaded dataset"),
                     "dp": (F + "Fig. 8)", "Innovation of heading ψ"),
                     "ebm": (Y + "Figs 4, 9)", Y + "Table 1)", Y + "Table 4)", Y + "Fig. 7)",
                             Y + "Figs 6, 10)")}.items():
        for mark in marks:
            assert mark in html[m], (m, mark)
    before = {p.name: p.stat().st_mtime_ns for p in d.iterdir()}
    assert main(["demo", "--out-dir", str(d)]) == 2
    assert {p.name: p.stat().st_mtime_ns for p in d.iterdir()} == before


def test_demo_default_folder_is_fresh(tmp_path, monkeypatch, capsys):
    import shipid.demo as demo

    def tiny(ctx):                                  # a quick stand-in step: the folder logic is under test
        p = ctx.out_dir / "a.txt"
        p.write_text("x")
        ctx.files.append(p)
        return [{"vessel": "v", "value": "1"}]

    monkeypatch.setattr(demo, "demo_steps", lambda: [demo.DemoStep("tiny", tiny, 0, "tiny step")])
    monkeypatch.chdir(tmp_path)
    assert main(["demo"]) == 0
    assert main(["demo"]) == 0                      # a second run gets its own folder
    runs = sorted((tmp_path / "shipid-demo").iterdir())
    assert len(runs) == 2 and all((r / "a.txt").exists() for r in runs)
    out = capsys.readouterr().out
    assert "[tiny] tiny step" in out and "vessel  value" in out


def test_demo_step_registry_order():
    from shipid.demo import demo_steps
    steps = demo_steps()
    assert steps[0].name == "simulate"
    assert [s.order for s in steps] == sorted(s.order for s in steps)


def test_a_csv_trial_names_the_sensor_positions_it_cannot_keep(tmp_path, capsys):
    """An EBM trial written to CSV loses its DGPS antenna and speed-log positions (Yoon & Rhee 2003 eq. 8): the
    command says which options give them back; Parquet keeps them in its metadata and says nothing."""
    csv, pq = tmp_path / "p.csv", tmp_path / "p.parquet"
    assert main(["simulate", "esso-osaka", "prbs-35-105", "--duration", "30", "--noise", "--out", str(csv)]) == 0
    assert "--antenna -120,5 --log-offset 2" in capsys.readouterr().out
    assert "x_D" not in read_trial(csv).meta
    assert main(["simulate", "esso-osaka", "prbs-35-105", "--duration", "30", "--noise", "--out", str(pq)]) == 0
    assert "note:" not in capsys.readouterr().out
    assert {k: read_trial(pq).meta[k] for k in ("x_D", "y_D", "y_S")} == {"x_D": -120.0, "y_D": 5.0, "y_S": 2.0}
