"""``shipid simulate fishing-vessel mass-cm-stream``, ``shipid monitor mass-cm`` and the report of a run."""

import io
import json
import sys

import pytest

from shipid.cli import main


@pytest.fixture(scope="module")
def stream(tmp_path_factory):
    d = tmp_path_factory.mktemp("monitor")
    out = d / "s.csv"
    rc = main(["simulate", "fishing-vessel", "mass-cm-stream", "--duration", "400", "--change-at", "250",
               "--to", "0.7,-0.14", "--seed", "3", "--out", str(out)])
    assert rc == 0
    return d


def _args(d, *extra):
    return ["monitor", "mass-cm", "--nominal", str(d / "s.nominal.csv"), "--calibration",
            str(d / "s.calibration.csv"), "--known", str(d / "s.known.toml"), *extra]


def test_simulate_writes_the_files(stream):
    for name in ("s.csv", "s.nominal.csv", "s.calibration.csv", "s.known.toml", "s.truth.json"):
        assert (stream / name).exists(), name
    truth = json.loads((stream / "s.truth.json").read_text())
    assert truth["change_at"] == 250.0 and truth["after"] == {"m": 0.7, "zm_bar": -0.14}
    assert "phi" not in (stream / "s.csv").read_text().splitlines()[0]      # the stream holds what an IMU measures
    # no clobbering
    assert main(["simulate", "fishing-vessel", "mass-cm-stream", "--out", str(stream / "s.csv")]) == 2


def test_monitor_file_and_stdin_agree(stream, capsys, monkeypatch):
    rc = main(_args(stream, "--stream", str(stream / "s.csv"), "--json"))
    cap = capsys.readouterr()
    assert rc == 0
    lines = [json.loads(x) for x in cap.out.splitlines()]
    assert len(lines) == 40 and lines[-1]["t"] == 400.0
    alarms = [x for x in lines if x["alarm"]]
    assert len(alarms) == 1 and 250 < alarms[0]["t"] <= 370
    assert "alarm at t =" in cap.err
    monkeypatch.setattr(sys, "stdin", io.StringIO((stream / "s.csv").read_text()))
    out = stream / "stdin-run.jsonl"
    rc = main(_args(stream, "--stream", "-", "--json", "-o", str(out)))
    assert rc == 0
    printed = capsys.readouterr().out
    assert [json.loads(x) for x in printed.splitlines()] == lines
    assert out.read_text(encoding="utf-8") == printed          # -o writes the lines --json prints
    rc = main(_args(stream, "--stream", str(stream / "s.csv"), "-o", str(out)))
    assert rc == 2 and capsys.readouterr().err.strip() == f"shipid: error: {out}: output file exists (use --force to overwrite)"
    assert out.read_text(encoding="utf-8") == printed


def test_report_of_a_run(stream, capsys, tmp_path):
    run = tmp_path / "run.jsonl"                 # its own run: no dependence on another test's files
    assert main(_args(stream, "--stream", str(stream / "s.csv"), "-o", str(run))) == 0
    capsys.readouterr()
    out = tmp_path / "r.html"
    rc = main(["report", str(run), "--out", str(out), "--truth", str(stream / "s.truth.json")])
    assert rc == 0
    page = out.read_text()
    assert "data:image/png;base64," in page and "detection delay" in page
    assert "<td>none</td>" in page and "0 false alarms" in page   # no false alarm, said in words
    assert 'class="verdict"' in page and "[]" not in page


def test_bad_stream_is_one_line(stream, capsys, tmp_path):
    """A cell that is not a number, or a missing file, is bad input: one line, exit 2."""
    lines = (stream / "s.csv").read_text().splitlines(True)
    bad = tmp_path / "bad.csv"
    row = lines[1000].split(",")
    row[1] = "abc"
    bad.write_text("".join(lines[:1000]) + ",".join(row) + "".join(lines[1001:3000]))
    rc = main(_args(stream, "--stream", str(bad), "--json"))
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "bad.csv" in err[0]
    rc = main(_args(stream, "--stream", str(tmp_path / "none.csv")))
    assert rc == 2


def test_sensor_faults_in_a_file_are_named_and_survived(stream, capsys, tmp_path):
    """A recorded stream with sensor faults (a 0.5-s gap, a 2-s NaN burst and a 60-s frozen roll rate, 5-sigma
    spikes, 1 % repeated and 1 % swapped samples) goes through the monitor's fault handler as a live feed does:
    exit 0, one warning per fault with its time and channel, no alarm before the change at 250 s, the change
    found within 120 s, and 'cannot estimate' instead of a number while the roll rate is frozen."""
    import numpy as np
    import pandas as pd
    from faultkit import CH, inject

    from shipid.io.files import read_trial

    st = read_trial(stream / "s.csv")
    t, X, faults = inject(st, np.random.default_rng(5), gap_short=60.0, nan_burst=80.0, clock_jump=None,
                          frozen=120.0, gap_long=None, n_spikes=3, spike_window=(30.0, 240.0))
    faulty = tmp_path / "faulty.csv"
    pd.DataFrame({"t [s]": t, **{f"{c} [{st.units[c]}]": X[:, i] for i, c in enumerate(CH)}}).to_csv(
        faulty, index=False)
    rc = main(_args(stream, "--stream", str(faulty), "--json"))
    cap = capsys.readouterr()
    assert rc == 0, cap.err
    warn = [w for w in cap.err.splitlines() if w.startswith("shipid: warning:")]
    assert any("gap of 0.5 s" in w and "t = 60 s" in w for w in warn), warn
    assert any("channel p" in w and "t = 80 s" in w for w in warn), warn
    assert any("channel p frozen" in w and "t = 120 s" in w for w in warn), warn
    spikes = [f for f in faults if f[0] == "spike"]
    assert sum("spike in channel" in w for w in warn) == len(spikes), warn
    assert any("repeated" in w for w in warn), warn
    ups = [json.loads(x) for x in cap.out.splitlines()]
    alarms = [u["t"] for u in ups if u.get("alarm")]
    assert alarms and all(250.0 < a <= 370.0 for a in alarms), alarms
    frozen = [u for u in ups if 130.0 <= u["t"] <= 170.0]
    assert frozen and all(u.get("m") is None for u in frozen), frozen


def test_live_panel_renders():
    from rich.console import Console

    from shipid.methods.monitor.cli import live_panel
    from shipid.methods.monitor.estimator import MonitorUpdate

    u = MonitorUpdate(930.0, 0.71, 0.09, -0.141, 0.018, 3.0, 0.12, False, True, 900.0, window_s=30.0, statistic=63.0)
    con = Console(file=io.StringIO(), width=100)
    con.print(live_panel(u, "s.nominal.csv"))
    text = con.file.getvalue()
    assert "0.71" in text and "ALARM" in text and "900" in text and "m [kg]" in text and "zm_bar [m]" in text


def test_monitor_noise_model_option(stream, capsys):
    """``--noise-model ar`` runs the AR(40) prefilter: a different run from the Box-Jenkins default, same stream."""
    outs = {}
    for nm in ("ar", "auto"):
        rc = main(_args(stream, "--stream", str(stream / "s.csv"), "--json", "--noise-model", nm))
        assert rc == 0
        outs[nm] = [json.loads(x) for x in capsys.readouterr().out.splitlines()]
        assert len(outs[nm]) == 40 and any(x["alarm"] for x in outs[nm])
    default = main(_args(stream, "--stream", str(stream / "s.csv"), "--json"))
    assert default == 0
    assert [json.loads(x) for x in capsys.readouterr().out.splitlines()] == outs["auto"]
    assert [x["m"] for x in outs["ar"]] != [x["m"] for x in outs["auto"]]


def test_monitor_warnings_are_counted_by_strict(stream, capsys, monkeypatch):
    """Each update's warnings are one 'shipid: warning:' line each; `shipid --strict monitor ...` exits 3
    after the stream."""
    import dataclasses

    from shipid.methods.monitor import estimator as E

    orig = E.MassCMMonitor._update

    def with_warning(self, extra_warnings=()):
        u = orig(self, extra_warnings)
        return dataclasses.replace(u, warnings=u.warnings + (f"t = {u.t:g} s: a test warning",))

    monkeypatch.setattr(E.MassCMMonitor, "_update", with_warning)
    assert main(["--strict", *_args(stream, "--stream", str(stream / "s.csv"), "--json")]) == 3
    cap = capsys.readouterr()
    lines = [json.loads(x) for x in cap.out.splitlines()]
    est = sum(x["m"] is not None for x in lines)          # the updates after the start-up window
    assert len(lines) == 40 and est > 20 and cap.err.count("shipid: warning: t = ") == est
    assert main(_args(stream, "--stream", str(stream / "s.csv"), "--json")) == 0
