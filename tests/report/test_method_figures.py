"""Each method's own report shows the figures and tables of issue 8, from real (small, seeded) runs.

The results come from the methods themselves (``tests/report/conftest.py``: ``method_reports``),
go through their JSON, and are rendered by ``build_report``. For every expected caption there
must be a ``<figure>`` whose ``<img>`` is an inline PNG (or a ``<table>`` with that caption), and
the numbers behind the figures must make sense (consistency of the innovations, the cost
minimum at the estimate, the fit of the overlays) — so these tests fail when a series is
missing, empty, or wrong.
"""

import base64
import html as _html
import re

import numpy as np
import pytest
from known.linder2015 import paper_mean, true_value

FIG_RE = re.compile(r'<figure><img src="data:image/png;base64,([^"]+)" alt="[^"]*">'
                    r"<figcaption><b>Figure \d+\.</b> (.*?)</figcaption></figure>", re.S)
TAB_RE = re.compile(r"<caption><b>Table \d+\.</b> (.*?)</caption>", re.S)


def figures(html: str) -> list[str]:
    """Captions (unescaped) of the figures whose image is a real, decodable PNG."""
    out = []
    for b64, cap in FIG_RE.findall(html):
        png = base64.b64decode(b64)
        if png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 5000:
            out.append(_html.unescape(cap))
    return out


def tables(html: str) -> list[str]:
    return [_html.unescape(c) for c in TAB_RE.findall(html)]


def count(caps: list[str], spec: str) -> int:
    """Captions that start with the text after " — " and cite the paper figure before it.

    ``"Fig. 4 — IV cost"`` counts captions "IV cost ... (Linder et al. 2015, Fig. 4)": the report's own
    number comes first, the paper's reference in parentheses (one numbering scheme).
    """
    ref, sep, text = spec.partition(" — ")
    if not sep:
        return sum(c.startswith(spec) for c in caps)
    return sum(c.startswith(text) and re.search(r"\([^()]*\d{4}, " + re.escape(ref) + r"\)", c) is not None
               for c in caps)


def test_captions_never_start_with_a_paper_number(method_reports):
    """One numbering scheme: "Figure 3. <text> (Yoon & Rhee 2003, Fig. 7)", never "Figure 3. Fig. 7 —"."""
    for name, (_, html, _) in method_reports.items():
        for cap in figures(html) + tables(html):
            assert not re.match(r"(Figs?\.?|Tables?) ?\d", cap), (name, cap)
            assert "Seed 00" not in cap and "seed 00" not in cap, (name, cap)


def frac_inside_2sigma(entry) -> float:
    v, s = np.asarray(entry["values"], float), np.asarray(entry["std"], float)
    ok = np.isfinite(v) & np.isfinite(s)
    return float(np.mean(np.abs(v[ok]) <= 2 * s[ok]))


def r2(entry) -> float:
    m, mo = np.asarray(entry["measured"], float), np.asarray(entry["model"], float)
    return float(1 - np.nanvar(m - mo) / np.nanvar(m))


def test_checker_rejects_a_broken_figure():
    bad = ('<figure><img src="data:image/png;base64,AAAA" alt="x"><figcaption><b>Figure 1.</b> Fig. 4 — x'
           "</figcaption></figure>")
    assert figures(bad) == []


# -- seed 000 -----------------------------------------------------------------------------------------

def test_masscm_report_overlays_residuals_and_fig4(method_reports):
    res, html, _ = method_reports["mass-cm"]
    caps = figures(html)
    assert count(caps, "Fig. 4 — IV cost (40)") == 1
    for cond in ("nominal", "calibration", "loaded"):
        assert count(caps, f"Roll rate p of the {cond} dataset") == 1
        assert count(caps, f"Prefiltered equation error (42)-(43) of the {cond} dataset") == 1
        # noise-free data: rudder and (black-box) yaw rate explain the roll almost fully (measured R² 0.98)
        assert r2(res.series["overlays"][f"p_{cond}"]) > 0.95
        # λ of the noise model is the variance of its innovations: ~95 % inside ±2σ (measured 0.96)
        assert 0.85 < frac_inside_2sigma(res.series["residuals"][f"equation_error_{cond}"]) < 0.995
    # Fig. 4: the cost minimum of the grid is the estimate (grid centre, ±1 cell)
    c = res.series["contours"]["cost"]
    z = np.asarray(c["z"])
    i, j = np.unravel_index(np.argmin(z), z.shape)
    assert abs(i - z.shape[0] // 2) <= 1 and abs(j - z.shape[1] // 2) <= 1
    assert c["points"][0]["label"] == "estimate" and c["points"][0]["x"] == pytest.approx(res.value("m"))
    # the data used: one trial summary per dataset
    ins = res.provenance["inputs"]
    assert [e["note"] for e in ins] == ["condition: nominal", "condition: calibration", "condition: loaded"]
    assert all(e["n_samples"] == 3000 and e["dt_s"] == pytest.approx(0.02) for e in ins)
    assert "condition: loaded" in html and "Trials the estimates come from." in html


def test_masscm_study_report_table3(method_reports):
    res, html, _ = method_reports["mass-cm-spread"]
    assert count(tables(html), "Table 3 — Sensitivity to the initial values: 4 of 4 runs plausible") == 1
    assert count(figures(html), "Table 3 — Estimates (m, z̄_m) of the 4 plausible runs") == 1
    rows = {r[0]: r for r in res.series["tables"]["spread"]["rows"]}
    assert list(rows) == ["A_x", "d", "k", "K_delta", "K_r", "K_vdot", "z_f", "m", "zm_bar"]
    # columns: parameter, unit, true, mean, std, lower, upper, paper mean, paper std (Table 3)
    assert rows["m"][2] == true_value("m") and rows["m"][7] == pytest.approx(paper_mean("m"))
    assert rows["m"][3] == pytest.approx(0.4, rel=2e-3)        # z_f known: every run reaches m (0.05 % off)
    assert len(res.series["xy"]["spread"]["x"]) == 4
    assert len(res.provenance["inputs"]) == 3


# -- seed 001 -----------------------------------------------------------------------------------------

def test_dp_report_innovation_checks(method_reports):
    res, html, _ = method_reports["dp"]
    caps = figures(html)
    assert count(caps, "Fig. 8 — Parameter estimates versus time") >= 1
    names = {"innovation_SI1_s"} | {f"innovation_SI{k}_{c}" for k in (2, 3) for c in ("x", "y", "psi")}
    assert set(res.series["residuals"]) == names
    assert count(caps, "Innovation of") == len(names)
    for n in names:
        e = res.series["residuals"][n]
        assert len(e["std"]) == len(e["values"]) == 301
        # a consistent EKF: ~95 % of the innovations inside its predicted ±2σ (measured 0.93-0.97)
        assert 0.85 < frac_inside_2sigma(e) < 0.995, n
    assert "inside ±2σ" in html          # the residual-checks table
    assert count(caps, "heading ψ of the first sway–yaw trial") == 1
    assert r2(res.series["overlays"]["SI2_psi"]) > 0.99
    ins = res.provenance["inputs"]
    assert [e["note"] for e in ins] == ["scheme SI1", "scheme SI2", "scheme SI3"]
    assert all(e["duration_s"] == pytest.approx(300.0) for e in ins)


# -- seed 002 -----------------------------------------------------------------------------------------

def test_ebm_report_paper_figures(method_reports):
    res, html, _ = method_reports["ebm"]
    caps, tabs = figures(html), tables(html)
    assert count(caps, "Figs 4, 9 — Step 1 (EKF + MBF smoother) of zigzag-20 trial") == 1
    assert count(caps, "Table 1 — Correlation WᵀW of the unit-length-scaled surge regressors") == 1
    assert count(caps, "Table 2 — Correlation WᵀW of the unit-length-scaled sway regressors") == 1
    assert count(tabs, "Table 4 — Collinearity and fit of the ridge regression") == 1
    assert count(caps, "Fig. 7 — D-optimality of the PRBS rudder input") == 1
    assert count(caps, "Figs 6, 10 — heading ψ of a held-out simulated prbs-10-40 trial") == 1
    for f in ("surge force X", "sway force Y", "yaw moment N"):
        assert count(caps, f"{f} of zigzag-20 trial") == 1
    assert count(caps, "Step-1 EKF innovation of psi") == 1
    s = res.series
    # Table 4: R is the root of R². (The yaw κ no longer equals the sway κ: the yaw regression is weighted
    # by 1/σ of the smoothed moment since issue 16, so its rows are no longer L times the sway rows.)
    rows = {r[0]: r for r in s["tables"]["conditioning"]["rows"]}
    assert set(rows) == {"surge", "sway", "yaw"}
    for mode, r in rows.items():
        assert r[2] == pytest.approx(np.sqrt(r[3])) and r[1] >= 1.0
    C = np.asarray(s["matrices"]["regressor_correlation_sway"]["values"])
    assert np.allclose(np.diag(C), 1.0) and np.allclose(C, C.T)
    assert s["matrices"]["regressor_correlation_sway"]["rows"][1] == "Y_v"
    # step 2 explains the smoothed forces (measured R² 0.91 / 0.99 / 0.998 on this 300-s zig-zag)
    assert r2(s["overlays"]["X_fit"]) > 0.8 and r2(s["overlays"]["Y_fit"]) > 0.95 and r2(s["overlays"]["N_fit"]) > 0.95
    # the held-out heading is predicted by the identified model (measured R² 0.996)
    assert r2(s["overlays"]["psi_validation"]) > 0.95 and s["overlays"]["psi_validation"]["kind"] == "validation"
    for n in ("innovation_psi", "innovation_u_log"):
        assert 0.85 < frac_inside_2sigma(s["residuals"][n]) < 0.995
    sig = s["signals"]["t1_force_Y"]
    assert sig["unit"] == "N" and set(sig["lines"]) == {"Y smoothed", "Y true"} and "Y smoothed" in sig["std"]
    assert res.provenance["inputs"][0]["channels"]["psi"] == "rad"


def test_identify_ebm_figures_flag_adds_fig7(tmp_path, capsys, monkeypatch):
    """``shipid identify ebm --figures``: the result JSON carries the (coarse) D-optimal map, Fig. 7."""
    import json

    from shipid.cli import main
    from shipid.io.files import write_trial
    from shipid.methods.ebm import series as ebm_series
    from shipid.methods.ebm.trials import simulate_trial

    monkeypatch.setattr(ebm_series, "COARSE_AMPLITUDES", (10.0, 35.0))   # 2 x 2 grid of 200-s runs: quick
    monkeypatch.setattr(ebm_series, "COARSE_PERIODS", (30.0, 105.0))
    monkeypatch.setattr(ebm_series, "COARSE_DURATION", 200.0)
    f = tmp_path / "zz.csv"
    write_trial(simulate_trial("zigzag-20", 200.0, seed=3), f)
    assert main(["identify", "ebm", "--trial", str(f), "--json", "--figures"]) == 0
    res = json.loads(capsys.readouterr().out)
    c = res["series"]["contours"]["d_optimal"]
    assert c["x"] == [30.0, 105.0] and c["y"] == [10.0, 35.0] and c["paper"] == "Fig. 7"
    z = np.asarray(c["z"])
    assert z.shape == (2, 2) and np.all(np.isfinite(z)) and np.all(z <= 0.0)   # log10 |WᵀW| <= 0
    best = np.unravel_index(np.argmax(z), z.shape)
    assert c["points"][0]["x"] == c["x"][best[1]] and c["points"][0]["y"] == c["y"][best[0]]
    assert res["provenance"]["inputs"][0]["name"].endswith("zz.csv")


def test_masscm_sensitivity_out_writes_a_table3_result(tmp_path, capsys):
    """``shipid study mass-cm-sensitivity --out R.json``: the study as a Result for ``shipid report``."""
    from shipid.cli import main
    from shipid.report import build_report
    from shipid.result import Result

    out = tmp_path / "t3.json"
    args = ["study", "mass-cm-sensitivity", "--runs", "3", "--workers", "1", "--json", "--out", str(out)]
    assert main(args) == 0
    res = Result.from_json(out.read_text(encoding="utf-8"))
    assert res.method == "mass-cm" and res.diagnostics["runs"] == 3
    assert len(res.series["tables"]["spread"]["rows"]) == 9 and len(res.series["xy"]["spread"]["x"]) == 3
    assert res.estimates["m"].value == pytest.approx(0.4, rel=2e-3)
    assert count(tables(build_report(res)), "Table 3 — Sensitivity to the initial values: 3 of 3 runs") == 1
    capsys.readouterr()
    assert main(args) == 2 and "exists" in capsys.readouterr().err     # checked before the study runs
