"""Real commands through the loud-failure mechanism (issue 13): identify mass-cm, identify ebm.

The shared mechanism itself is tested in test_loud.py; identify mmg and validate in
test_mmg_conventions.py.
"""

import json

import pytest

from shipid.cli import main
from shipid.io.files import write_trial
from shipid.methods.ebm.trials import simulate_trial
from shipid.models.roll_sim import simulate_datasets

KNOWN_FREE_ZF = """U = 1.0
M = 22.04
zg_bar = 0.0
m_c = 0.2
zc_bar = -0.172
zs_bar = -0.2
g = 9.82
"""


def _warnings(err):
    return [ln for ln in err.splitlines() if ln.startswith("shipid: warning: ")]


@pytest.fixture(scope="module")
def masscm_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("masscm")
    paths = {}
    for cond, tr in simulate_datasets(seed=4).items():
        paths[cond] = str(d / f"{cond}.csv")
        write_trial(tr, paths[cond])
    (d / "known.toml").write_text(KNOWN_FREE_ZF)
    paths["known"] = str(d / "known.toml")
    return paths


def _masscm(files, *extra):
    return ["identify", "mass-cm", "--nominal", files["nominal"], "--calibration", files["calibration"],
            "--loaded", files["loaded"], "--known", files["known"], *extra]


def test_mass_cm_not_identifiable_m_is_a_warning_line_in_json_and_strict_exit_3(masscm_files, capsys):
    """Without z_f, m is not identifiable: a warning on stderr, in the JSON, and exit 3 under --strict."""
    assert main(_masscm(masscm_files, "--json")) == 0
    cap = capsys.readouterr()
    w = _warnings(cap.err)
    assert any("m is not identifiable" in x for x in w)
    assert cap.err.count("\n") == len(w)                      # nothing but warning lines on stderr
    d = json.loads(cap.out)
    assert [f"shipid: warning: {x}" for x in d["diagnostics"]["warnings"]] == w
    assert main(["--strict", *_masscm(masscm_files)]) == 3
    capsys.readouterr()


@pytest.fixture(scope="module")
def ebm_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("ebm")
    paths = []
    for i, (m, dur) in enumerate([("turning-35", 300.0), ("zigzag-20", 400.0)]):
        p = d / f"t{i}.csv"
        write_trial(simulate_trial(m, dur, seed=i), p)
        paths.append(str(p))
    return paths


def test_ebm_converged_reaches_the_text_output(ebm_files, capsys, monkeypatch):
    """The text output says whether EBM converged; a fit that did not is one warning line and exit 3 strict.

    The non-converged case takes the real result of the same run and marks its sway mode as a
    ridge fit whose k iteration did not converge would (the CLI must pass that on, whatever the cause).
    """
    monkeypatch.setenv("SHIPID_NO_PROGRESS", "1")
    argv = ["identify", "ebm", *sum((["--trial", p] for p in ebm_files), [])]
    assert main(argv) == 0
    cap = capsys.readouterr()
    conv = [ln for ln in cap.out.splitlines() if ln.startswith("converged:")]
    assert conv and conv[0].startswith("converged: yes")

    from shipid.methods.ebm import estimator as ebm

    real = ebm.identify_run

    def not_converged(*a, **k):
        run = real(*a, **k)
        run.result.diagnostics["converged"] = False
        return run

    monkeypatch.setattr(ebm, "identify_run", not_converged)
    assert main(argv) == 0
    cap = capsys.readouterr()
    assert "converged: NO" in cap.out
    assert any("ebm: the estimator did not converge" in x for x in _warnings(cap.err))
    assert main(["--strict", *argv]) == 3
    capsys.readouterr()
