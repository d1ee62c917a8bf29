"""A trial as a user writes it: ``Time (ms)``, ``Heading (deg)``, ``Speed (kn)`` ... read by the methods.

A short simulated ESSO OSAKA run (:func:`shipid.methods.ebm.trials.simulate_trial`) is
written by hand the way a logger or a spreadsheet writes it: headers ``name (unit)`` in the
units of the bridge (ms, deg, kn, rpm), own column names. ``identify mmg`` and
``identify ebm`` take it with one ``--channels`` option, the same on both, or refuse it
with one line (exit 2) that names every problem: each channel the method needs and the
file lacks, with the columns that could give it. Identification quality is not looked at.
"""

from __future__ import annotations

import numpy as np
import pytest

from shipid.cli import main
from shipid.io.files import read_trial
from shipid.io.paths import data_root
from shipid.methods.ebm.trials import simulate_trial

#: The one --channels option of every command below.
CHANNELS = "t=Time,x=X,y=Y,psi=Heading,U=Speed,delta=Rudder,n=Shaft,x_dot=Vx,y_dot=Vy,u=Surge,v=Sway,r=Yaw rate"
BASIC = ["Time (ms)", "X (m)", "Y (m)", "Heading (deg)", "Speed (kn)", "Rudder (deg)", "Shaft (rpm)"]


def _write(path, cols: dict[str, np.ndarray]) -> None:
    lines = [",".join(cols)]
    lines += [",".join(f"{v:.10g}" for v in row) for row in np.column_stack(list(cols.values()))]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("own")
    tr = simulate_trial("zigzag-20", 240.0, seed=3)
    psi = tr["psi"]
    u = tr["x_dot"] * np.cos(psi) + tr["y_dot"] * np.sin(psi)
    v = -tr["x_dot"] * np.sin(psi) + tr["y_dot"] * np.cos(psi)
    basic = {"Time (ms)": tr.t * 1000.0, "X (m)": tr["x"], "Y (m)": tr["y"], "Heading (deg)": np.rad2deg(psi),
             "Speed (kn)": tr["U"] * 3600.0 / 1852.0, "Rudder (deg)": np.rad2deg(tr["delta"]),
             "Shaft (rpm)": tr["n"] * 60.0}
    full = dict(basic)
    full.update({"Vx (m/s)": tr["x_dot"], "Vy (m/s)": tr["y_dot"], "Surge (m/s)": u, "Sway (m/s)": v,
                 "Yaw rate (deg/s)": np.gradient(np.unwrap(np.rad2deg(psi)), tr.t)})
    out = {"basic": d / "basic.csv", "full": d / "full.csv", "truth": tr}
    _write(out["basic"], basic)
    _write(out["full"], full)
    return out


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("shipid: error: "), err
    return err


def test_the_hand_written_file_reads_in_si(files):
    tr = read_trial(files["full"], channel_map=CHANNELS)
    truth = files["truth"]
    np.testing.assert_allclose(tr.t, truth.t, rtol=1e-9, atol=1e-9)
    for name in ("x", "y", "psi", "U", "delta", "n", "x_dot", "y_dot"):
        np.testing.assert_allclose(tr[name], truth[name], rtol=1e-8, atol=1e-9)
    assert tr.meta["units_in"]["t"] == "ms" and tr.meta["units_in"]["n"] == "rpm"
    assert tr.meta["columns"]["psi"] == "Heading"


@pytest.mark.parametrize("method, needs", [("mmg", ["u", "v", "r"]), ("ebm", ["x_dot", "y_dot"])])
def test_without_channels_one_line_names_every_problem(files, capsys, method, needs):
    assert main(["identify", method, "--trial", str(files["basic"])]) == 2
    err = _one_line_error(capsys)
    # the columns X and Y are not the forces X and Y; no time column; every channel the method needs
    assert "problems:" in err and "channel 'X': unit 'm' is not a unit of N" in err and "no time column 't'" in err
    for ch in ["x", "y", "psi", "delta", "n", *needs]:
        assert f"channel '{ch}': required by identify {method} but missing" in err or \
            f"channel '{ch}': required by {method} but missing" in err, ch
    # with the columns that could give them, and a ready --channels map
    assert "could be column 'Heading' [deg]" in err and "could be column 'Time' [ms]" in err
    assert "try --channels 't=Time,x=X,y=Y,psi=Heading" in err and "delta=Rudder,n=Shaft" in err


@pytest.mark.parametrize("method, needs", [("mmg", ["u", "v", "r"]), ("ebm", ["x_dot", "y_dot"])])
def test_with_channels_the_channels_the_file_lacks_in_one_line(files, capsys, method, needs):
    cmap = "t=Time,x=X,y=Y,psi=Heading,U=Speed,delta=Rudder,n=Shaft"
    assert main(["identify", method, "--trial", str(files["basic"]), "--channels", cmap]) == 2
    err = _one_line_error(capsys)
    assert f"{len(needs)} problems:" in err
    for ch in needs:
        assert f"channel '{ch}': required by" in err
    assert "psi from Heading [deg]" in err       # what the file gave, as mapped


def test_identify_ebm_runs_on_the_hand_written_file(files, tmp_path, capsys):
    out = tmp_path / "ebm.json"
    rc = main(["identify", "ebm", "--trial", str(files["full"]), "--channels", CHANNELS, "-o", str(out)])
    assert rc == 0, capsys.readouterr().err
    assert out.stat().st_size > 1000


def test_identify_mmg_runs_on_the_hand_written_file(files, tmp_path, capsys):
    root = data_root()
    if root is None or not (root / "params").is_dir():
        pytest.skip("shared data (params/) not found (set SHIPID_DATA): the MMG prior needs it")
    out = tmp_path / "mmg.json"
    rc = main(["identify", "mmg", "--trial", str(files["full"]), "--channels", CHANNELS,
               "--prior", "esso_osaka_3m", "--structure", "hull+rudder+thrust", "-o", str(out)])
    assert rc == 0, capsys.readouterr().err
    assert out.stat().st_size > 1000


READERS = [("check",), ("convert",), ("validate",), ("identify", "mmg"),
           ("identify", "ebm"), ("identify", "dp"), ("identify", "mass-cm"), ("monitor", "mass-cm")]


@pytest.mark.parametrize("path", READERS, ids=" ".join)
def test_every_command_that_reads_trials_has_the_same_channels_option(path):
    import click

    from shipid.cli import cli
    from shipid.cli._common import CHANNELS_HELP

    ctx = click.Context(cli)
    cmd = cli
    for name in path:
        cmd = cmd.get_command(ctx, name)
        ctx = click.Context(cmd, parent=ctx)
    opt = next(p for p in cmd.params if "--channels" in getattr(p, "opts", ()))
    assert opt.name == "channels" and opt.metavar == "MAP" and opt.help.startswith(CHANNELS_HELP)


def test_identify_mass_cm_refuses_a_file_without_its_channels_in_one_line(tmp_path, capsys):
    p = tmp_path / "roll.csv"
    p.write_text("time_s,roll rate (deg/s),acc (m/s2),yaw rate (deg/s),rudder (deg)\n"
                 + "".join(f"{0.02 * i:.2f},0.1,0.2,0.3,0.4\n" for i in range(50)))
    known = tmp_path / "known.toml"
    known.write_text("U = 5.0\nM = 100.0\nzg_bar = 0.1\nm_c = 1.0\nzc_bar = 0.2\nzs_bar = 0.0\ng = 9.81\n")
    argv = ["identify", "mass-cm", "--nominal", str(p), "--calibration", str(p), "--loaded", str(p),
            "--known", str(known)]
    assert main(argv) == 2
    err = _one_line_error(capsys)
    for ch in ("p", "a_s", "r", "delta"):
        assert f"channel '{ch}': required by mass-cm but missing" in err
    assert "could be column 'roll rate' [deg/s]" in err and "could be column 'acc' [m/s2]" in err
    assert err.endswith("try --channels 't=time,p=roll rate,a_s=acc,r=yaw rate,delta=rudder'")
