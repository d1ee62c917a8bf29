"""Reports an engineer reads without squinting (issue 20): a verdict on top, undetermined
coefficients labelled so, units everywhere, no raw numpy/Python text, no machine paths,
figure labels that neither overlap nor clip, and the Esso ``identify mmg`` report filled in."""

from __future__ import annotations

import html as _html
import re
from pathlib import Path

import numpy as np
import pytest

from shipid.report import build_report
from shipid.report import figures as F
from shipid.report.verdict import NOT_DETERMINED, effective_status
from shipid.result import Estimate, Result

REPO = Path(__file__).resolve().parents[2]


def _text(html: str) -> str:
    """Visible text of the report (no style, no data URIs)."""
    s = re.sub(r"<style>.*?</style>", "", html, flags=re.S)
    s = re.sub(r'src="data:[^"]+"', 'src=""', s)
    return _html.unescape(re.sub(r"<[^>]+>", " ", s))


def _result(estimates: dict, method: str = "ebm", **diag) -> Result:
    return Result(method=method, estimates=estimates, diagnostics=dict(diag), provenance={}, model={})


# -- verdict and status ----------------------------------------------------------------------------

def test_relative_se_above_100_percent_is_not_determined():
    e_bad = Estimate(value=0.009, std=0.014, unit="-", status="estimated")
    e_ok = Estimate(value=-0.0298, std=0.00084, unit="-", status="estimated")
    e_flag = Estimate(value=1.0, std=0.01, unit="-", status="not determined")
    e_fixed = Estimate(value=2.0, std=float("nan"), unit="m", status="fixed")
    assert effective_status(e_bad) == NOT_DETERMINED
    assert effective_status(e_ok) == "estimated"
    assert effective_status(e_flag) == NOT_DETERMINED   # the method's own verdict wins
    assert effective_status(e_fixed) == "fixed"
    html = build_report(_result({"Y_vvr": e_bad, "Y_v": e_ok, "N_x": e_flag, "L": e_fixed}, converged=True))
    rows = {m.group(1): m.group(0) for m in re.finditer(r"<tr[^>]*><td><b>([^<]+)</b>.*?</tr>", html, re.S)}
    assert 'class="notdet"' in rows["Y_vvr"] and "grade notdet" in rows["Y_vvr"] and "estimated" not in rows["Y_vvr"]
    assert "0.009" not in rows["Y_vvr"] and "1.00" not in rows["N_x"]     # never shown as an estimate
    assert 'class="notdet"' in rows["N_x"]
    assert "grade well" in rows["Y_v"] and "notdet" not in rows["Y_v"]


def test_verdict_panel_says_convergence_determination_coverage_and_warnings():
    est = {"a": Estimate(1.0, 0.01, "m"), "b": Estimate(1.0, 0.3, "m"), "c": Estimate(0.1, 0.5, "m")}
    html = build_report(_result(est, converged=False, warnings=["gyro channel repaired at row 12"]))
    m = re.search(r'<section class="verdict".*?</section>', html, re.S)
    assert m and html.index('class="verdict"') < html.index('id="data"')
    v = _text(m.group(0))
    assert "Did not converge" in v
    assert "Well determined" in v and "a (1 %)" in v
    assert "Loosely determined" in v and "b (30 %)" in v
    assert "Not determined" in v and "c." in v and "c (500 %)" not in v   # named, not given a value
    # EBM publishes its last coverage study (shipid.methods.ebm.estimator.COVERAGE): the verdict quotes it with its source
    assert "ebm-coverage" in v and "No coverage study" not in v
    assert "2 warnings" in v        # the method's, and the report's line naming c (estimated, rel. SE 500 %)
    html = build_report(_result(est, method="toy", converged=True))     # a method with no published study
    assert "No coverage study" in _text(re.search(r'<section class="verdict".*?</section>', html, re.S).group(0))
    cov = build_report(_result(est, converged=True, coverage={"coverage": 0.80, "n": 200, "nominal": 0.954}))
    v2 = _text(re.search(r'<section class="verdict".*?</section>', cov, re.S).group(0))
    assert "Converged" in v2 and "80 % of 200" in v2 and "too small" in v2


def test_a_coverage_table_published_by_the_method_module_is_used(monkeypatch):
    import shipid.methods.ebm as mod   # the package publishes COVERAGE (shipid.registry reads it there)

    monkeypatch.setattr(mod, "COVERAGE", {"coverage": 0.95, "n": 100, "source": "tests: made up"}, raising=False)
    html = build_report(_result({"a": Estimate(1.0, 0.01, "m")}, converged=True))
    v = _text(re.search(r'<section class="verdict".*?</section>', html, re.S).group(0))
    assert "95 % of 100" in v and "about right" in v and "source: tests: made up" in v


def test_demo_masscm_setting_is_one_where_the_method_works():
    """The demo's mass-cm data (white sensor noise): no warning, white equation errors, m near the truth."""
    from shipid.methods.masscm.estimator import fit_mass_cm
    from shipid.methods.masscm.series import with_series
    from shipid.models.roll_reduced import KnownParams
    from shipid.models.roll_sim import NoiseSpec, simulate_datasets
    from shipid.methods.masscm.demo import DEMO_MASSCM_NOISE
    from shipid.report.stats import residual_stats
    from shipid.vessels import load_vessel

    v = load_vessel("fishing-vessel")
    d = simulate_datasets("fishing-vessel", seed=0, noise=NoiseSpec(**DEMO_MASSCM_NOISE))
    r = with_series(fit_mass_cm(list(d.items()), KnownParams.from_vessel("fishing-vessel"),
                                z_f=float(v.value("general", "z_f"))))
    assert r.diagnostics.get("converged") and not r.diagnostics.get("warnings")
    m = r.estimates["m"]
    assert abs(m.value - float(v.value("general", "m"))) < 3 * m.std
    for name, e in r.series["residuals"].items():
        st, _ = residual_stats(e["values"], e.get("std"))
        assert st.frac_outside <= 0.10 and st.ljung_box_p > 0.01, name


def test_held_out_error_is_in_the_verdict_for_real_data(method_reports):
    _, html, _ = method_reports["ebm"]
    v = _text(re.search(r'<section class="verdict".*?</section>', html, re.S).group(0))
    assert "Held-out prediction" in v and "RMS error" in v


# -- text: units, no repr, no paths -------------------------------------------------------------------

REPR = [r"\\n", "array(", "dtype", "np.float", "<class", "{'", "None", "nan ", "[[", "e-0", "e+0"]


@pytest.mark.parametrize("name", ["mass-cm", "dp", "ebm"])
def test_no_python_or_numpy_text_and_no_machine_paths(method_reports, raw_results, name):
    result, html, _ = method_reports[name]
    # the in-memory result too (numpy arrays in diagnostics/model, as the demo passes them)
    for h in (html, build_report(raw_results[name])):
        text = _text(h)
        for bad in REPR:
            assert bad not in text, (name, bad, text[max(0, text.find(bad) - 80):text.find(bad) + 80])
        assert str(REPO) not in text and "/tmp/" not in text and "/work/" not in text
        assert not re.search(r"[Ss]eed 00\d", text)   # papers by authors and year


def test_dp_matrices_are_tables_and_theta_also_in_si(method_reports):
    _, html, _ = method_reports["dp"]
    for key in ("A_h", "B", "T", "theta_true", "error"):
        m = re.search(rf"<th scope=\"row\">[^<]*{key}</th><td[^>]*>(.*?)</td></tr>", html, re.S)
        assert m, key
        assert m.group(1).startswith(('<table class="mat">', '<div class="vec">', '<div class="scroll"><table')), \
            (key, m.group(1)[:120])
    text = _text(html)
    assert "in SI units" in text and "time constant −1/A_h" in text and " N " in text


def test_model_particulars_have_units(method_reports):
    _, html, _ = method_reports["mass-cm"]
    m = re.search(r'<th scope="row">known\.M</th><td[^>]*>(.*?)</td>', html, re.S)
    assert m and "kg" in m.group(1)
    _, html, _ = method_reports["dp"]
    m = re.search(r'<th scope="row">L</th><td[^>]*>(.*?)</td>', html, re.S)
    assert m and "76.2" in m.group(1) and ">m<" in m.group(1)


# -- figures --------------------------------------------------------------------------------------------

def _figs(result):
    """The report's figure builders on the result's own series (as the report draws them)."""
    from shipid.report.stats import residual_stats

    s = result.series or {}
    out = []
    sig = [(n, e) for n, e in (s.get("signals") or {}).items() if isinstance(e, dict)]
    for i in range(0, len(sig), 6):
        out.append(("signals", F.signals_figure(sig[i:i + 6])))
    hist = [(n, e) for n, e in (s.get("histories") or {}).items() if isinstance(e, dict)]
    if hist:
        out.append(("histories", F.histories_figure(hist[:12])))
    for n, e in list((s.get("overlays") or {}).items())[:2]:
        resid = np.asarray(e["measured"], float) - np.asarray(e["model"], float)
        st, r = residual_stats(resid, None)
        out.append((f"overlay {n}", F.overlay_figure(n, e, resid, r, st.acf_bound)))
    for n, e in list((s.get("residuals") or {}).items())[:2]:
        st, r = residual_stats(e["values"], e.get("std"))
        out.append((f"residual {n}", F.residual_figure(n, e, r, st.acf_bound)))
    return out


@pytest.mark.parametrize("name", ["mass-cm", "dp", "ebm"])
def test_figure_labels_have_units_and_do_not_overlap(method_reports, name):
    result, _, _ = method_reports[name]
    figs = _figs(result)
    assert figs
    for what, fig in figs:
        assert F.label_problems(fig) == [], (name, what)
        for ax in fig.axes:
            if not ax.get_visible() or not ax.has_data():
                continue
            yl = ax.get_ylabel()
            assert yl and re.search(r"\[[^\]]*\]", yl), (name, what, yl)   # "quantity [unit]" or "[unit]"
        xl = [ax.get_xlabel() for ax in fig.axes if ax.get_xlabel()]
        assert xl and all("[" in x for x in xl), (name, what, xl)


def test_label_check_can_fail():
    fig = F.new_figure(height=1.2)
    ax1, ax2 = fig.subplots(2, 1)
    ax1.set_ylabel("a very long label that cannot fit [10⁶ N]")
    ax2.set_ylabel("another very long label that cannot fit [10⁶ N·m]")
    ax1.plot([0, 1], [0, 1]); ax2.plot([0, 1], [0, 1])
    assert F.label_problems(fig)


# -- Esso `identify mmg` ----------------------------------------------------------------------------------

@pytest.mark.slow
def test_esso_identify_mmg_report_has_data_and_time_histories(esso_mmg_report):
    _, html, _, runs = esso_mmg_report
    data = re.search(r'<details class="sec" id="data">.*?</table>', html, re.S).group(0)
    for r in runs:
        assert r.name in data
    rows = re.findall(r"<tr><td><code>.*?</tr>", data, re.S)
    assert len(rows) == len(runs)
    for row in rows:
        cells = re.findall(r"<td[^>]*>(.*?)</td>", row, re.S)
        assert all(c.strip() not in ("", "—") for c in cells[1:5]), cells   # samples, duration, sampling, channels
    assert 'id="series"' in html and "Open-loop simulation of the identified model" in html
    text = _text(html)
    assert "/work/" not in text and str(runs[0].parent) not in text
