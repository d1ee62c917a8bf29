"""Nomoto K, T (and T1, T2, T3) of manoeuvring models, with standard errors."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.optimize import least_squares
from scipy.signal import ss2tf

from shipid.errors import InputError
from shipid.export import load, nomoto, state_space
from shipid.export.nomoto import nomoto_from_matrices
from shipid.simulate.manoeuvres import run_manoeuvre
from shipid.simulate.registry import get_ship_model


def test_second_order_nomoto_is_the_transfer_function_of_the_state_space():
    """K (1 + T3 s) / ((1 + T1 s)(1 + T2 s)) equals r/delta of the sway-yaw rows, from scipy's ss2tf."""
    ss = state_space("esso-osaka")
    a, b = ss.A[1:3, 1:3], ss.B[1:3, :1]
    num, den = ss2tf(a, b, np.array([[0.0, 1.0]]), np.zeros((1, 1)))
    K, T, T1, T2, T3 = nomoto_from_matrices(a, b[:, 0], 325.0, 5.144)[:5]
    # scipy: (n1 s + n0) / (s^2 + d1 s + d0); Nomoto: K T3 s + K over T1 T2 s^2 + (T1 + T2) s + 1
    np.testing.assert_allclose([K * T3 / (T1 * T2), K / (T1 * T2)], num[0, 1:], rtol=1e-9)
    np.testing.assert_allclose([(T1 + T2) / (T1 * T2), 1 / (T1 * T2)], den[1:], rtol=1e-9)
    assert T == pytest.approx(T1 + T2 - T3, rel=1e-12)


def _zigzag_fit(trial, K0, T0):
    """First-order Nomoto T r' + r = K delta fitted to the yaw rate of a trial (scipy least squares; the
    measured rudder held over each sample, the exact solution over each step)."""
    t, r, d = trial.t, trial["r"], trial["delta"]
    h = np.diff(t)

    def response(q):
        K, T = q
        out = np.empty_like(r)
        out[0] = r[0]
        a = np.exp(-h / T)
        for k in range(t.size - 1):
            out[k + 1] = a[k] * out[k] + (1 - a[k]) * K * d[k]
        return out

    sol = least_squares(lambda q: response(q) - r, [K0, T0], x_scale=[abs(K0), abs(T0)])
    return sol.x


def _zigzag_fit_std(trial, K0, T0):
    """:func:`_zigzag_fit` with its least-squares std ``s^2 (J^T J)^-1`` (residuals taken as white)."""
    t, r, d = trial.t, trial["r"], trial["delta"]
    K, T = _zigzag_fit(trial, K0, T0)
    h = 1e-6
    base = _response(t, r, d, K, T)
    J = np.column_stack([(_response(t, r, d, K * (1 + h), T) - base) / (K * h),
                         (_response(t, r, d, K, T * (1 + h)) - base) / (T * h)])
    res = base - r
    cov = res @ res / (r.size - 2) * np.linalg.inv(J.T @ J)
    return np.array([K, T]), np.sqrt(np.diag(cov))


def _response(t, r, d, K, T):
    a = np.exp(-np.diff(t) / T)
    out = np.empty_like(r)
    out[0] = r[0]
    for k in range(t.size - 1):
        out[k + 1] = a[k] * out[k] + (1 - a[k]) * K * d[k]
    return out


def test_packaged_esso_osaka_nomoto_against_a_10_10_zigzag_fit():
    """Nomoto K, T of the packaged Esso Osaka model (Yoon & Rhee 2003, Table 3) against a first-order fit to a
    10/10 zig-zag simulated by the same model.

    The packaged model has no covariance, so there is no std to compare within. What the linearisation and the
    zig-zag both determine is K/T, the yaw acceleration per rudder angle: they agree within 10 % (measured
    4.8 %). K and T separately do not agree, and the export says why: the ship is nearly course-unstable
    (T2 = 5753 s, T' = 91), so the first-order T = T1 + T2 - T3 holds only for responses slower than T2, while
    a 10/10 zig-zag (1500 s here) fits K = -0.11 1/s, T = 990 s against the export's -0.67 1/s, 5726 s.
    """
    src = load("esso-osaka")
    nm = nomoto(src)
    assert np.isnan(nm.std["K"]) and "no covariance" in nm.note
    trial = run_manoeuvre(get_ship_model("esso-osaka"), "zigzag-10", duration=1500.0, dt=1.0)
    K_fit, T_fit = _zigzag_fit(trial, nm.K, nm.T)
    assert K_fit / T_fit == pytest.approx(nm.values["K_over_T"], rel=0.10)
    assert nm.values["T2"] > 20 * nm.values["T1"]
    assert any("nearly course-unstable" in n for n in nm.extra["notes"])


def test_zigzag_nomoto_of_the_packaged_model_agrees_with_a_direct_10_10_zigzag_fit():
    """``nomoto(about="zigzag-10")`` of the packaged Esso Osaka model against this file's own first-order fit to a
    10/10 zig-zag: simulated by the packaged simulator (not the export's), 1500 s at 1 s (the export: 24 L/U
    = 1516 s at 1.26 s), fitted without a neutral-rudder term from the straight-run K, T (the export: with one,
    from an equation-error start). They agree within the combined std of the two fits (measured 0.3 std for K
    and T); the straight-run K, T (5.5 and 4.7 times larger) do not."""
    nm = nomoto("esso-osaka", about="zigzag-10")
    fit = nm.extra["fit"]
    assert nm.about == "zigzag-10" and np.isnan(nm.values["T2"]) and nm.method == "zigzag-fit"
    assert nm.std["K"] == pytest.approx(fit["K_std"], rel=1e-12)       # no covariance: the fit's std alone
    straight = nomoto("esso-osaka")
    trial = run_manoeuvre(get_ship_model("esso-osaka"), "zigzag-10", duration=1500.0, dt=1.0)
    q, sd = _zigzag_fit_std(trial, straight.K, straight.T)
    for j, k in enumerate(("K", "T")):
        comb = np.hypot(nm.std[k], sd[j])
        assert abs(nm.values[k] - q[j]) < comb, k
        assert abs(straight.values[k] - q[j]) > 10 * comb, k
    assert nm.values["K_over_T"] == pytest.approx(straight.values["K_over_T"], rel=0.10)


def test_zigzag_fit_std_is_the_size_of_the_spread_over_record_lengths():
    """The fit std of the zig-zag K, T is scaled for the time correlation of the residuals (the response a
    first-order model leaves out). Checked against what it stands for: fits to the first 18, 20, ... 30 L/U of
    one 10/10 zig-zag scatter by more than the white-residual std (4 times, measured) and by less than the
    scaled std (0.4 of it, measured)."""
    from shipid.export.nomoto import zigzag_fit
    from shipid.export.params import simulate_source

    src = load("esso-osaka")
    LU = src.length / src.model.U0
    trial = simulate_source(src, "zigzag-10", duration=30 * LU, dt=0.02 * LU)[0]
    fits = [zigzag_fit(trial.t[:m], trial["r"][:m], trial["delta"][:m])
            for m in (int(n / 0.02) + 1 for n in range(18, 31, 2))]
    for k in ("K", "T"):
        spread = np.std([f[k] for f in fits], ddof=1)
        scaled = np.mean([f[f"{k}_std"] for f in fits])
        white = np.mean([f[f"{k}_std"] / np.sqrt(f["inflation"]) for f in fits])
        assert white < spread < scaled, k


def test_a_zigzag_fit_whose_t_runs_off_leaves_k_and_t_not_determined():
    """A model whose 10/10 zig-zag yaw rate grows (N_r times 0.9: course-unstable, T2 = -1217 s) has no
    first-order T within the record: K and T are labelled not determined with an infinite std and a note, K/T
    is kept."""
    src = load("esso-osaka")
    src = src.with_coefficients({"N_r": 0.9 * src.coef["N_r"]})
    nm = nomoto(src, about="zigzag-10")
    st = nm.status
    assert st["K"] == st["T"] == "not determined" and nm.std["K"] == np.inf
    assert any("only K/T" in n for n in nm.extra["notes"]) and f"{nm.K:.5g}" not in nm.summary()
    assert st["K_over_T"] == "estimated"


def _with_cov(rel: float):
    """The packaged Esso Osaka model with independent coefficient errors of ``rel`` times each value."""
    src = load("esso-osaka")
    names = tuple(src.coef)
    sd = np.array([rel * abs(src.coef[k]) for k in names])
    return dataclasses.replace(src, cov_names=names, cov=np.diag(sd ** 2), cov_note="test: 2 % independent")


def test_delta_method_and_monte_carlo_agree_where_the_model_is_nearly_linear_in_the_coefficients():
    """With 2 % independent coefficient errors, the delta-method std of T1, T3 and K/T (smooth in the
    coefficients) is within 25 % of the Monte Carlo std of 400 seeded draws (sampling error of a std from 400
    draws: 3.5 %; the rest is the curvature the delta method leaves out)."""
    src = _with_cov(0.02)
    d = nomoto(src)
    mc = nomoto(src, samples=400, seed=11)
    assert d.method == "delta" and mc.method == "monte-carlo" and mc.seed == 11
    for k in ("T1", "T3", "K_over_T"):
        assert np.isfinite(d.std[k]) and d.std[k] > 0
        assert mc.std[k] == pytest.approx(d.std[k], rel=0.25)
    again = nomoto(src, samples=400, seed=11)
    assert again.std == mc.std


def test_monte_carlo_needs_a_seed():
    with pytest.raises(InputError, match="seed"):
        nomoto(_with_cov(0.02), samples=10)


def test_dp_model_has_no_nomoto():
    with pytest.raises(InputError, match="manoeuvring"):
        nomoto("supply")


def test_frame_and_summary():
    nm = nomoto("esso-osaka")
    f = nm.to_frame()
    assert list(f.columns) == ["value", "std", "status", "unit", "meaning"] and f.loc["T", "unit"] == "s"
    assert f.loc["T", "status"] == "no std"
    z = nomoto("esso-osaka", about="zigzag-10")
    assert z.status["K"] == z.status["T"] == z.status["K_over_T"] == "estimated" and np.isnan(z.values["T1"])
    text = nm.summary()
    assert "K'" in text and len(text.splitlines()) < 20 and max(map(len, text.splitlines())) <= 200
    assert "T = 5726" in repr(nm) or "T = 5.726e+03" in repr(nm)


@pytest.mark.slow
def test_ebm_identified_esso_osaka_straight_run_k_and_t_are_not_determined():
    """An EBM model identified from a simulated 20/20 zig-zag and 35 deg turn of the Esso Osaka (Yoon & Rhee
    2003 §5.1, noise of eq. 19) carries standard errors. Its straight-run K and T have a delta-method std above
    their magnitude (T2 depends on the small determinant of the sway-yaw matrix, which EBM determines to a few
    per cent), so they are labelled not determined; K/T, which does not go through that determinant, is
    estimated and agrees with the 10/10 zig-zag fit of the packaged model within 2 std."""
    from shipid.methods.ebm import estimator as ebm
    from shipid.methods.ebm import trials as ebm_trials

    trials = [ebm_trials.simulate_trial("zigzag-20", 600.0, seed=1), ebm_trials.simulate_trial("turning-35", 600.0, seed=2)]
    nm = nomoto(ebm.identify(trials))
    assert nm.method == "delta"
    assert nm.status["K"] == nm.status["T"] == "not determined" and "not determined" in nm.summary()
    assert nm.status["K_over_T"] == "estimated"
    trial = run_manoeuvre(get_ship_model("esso-osaka"), "zigzag-10", duration=1500.0, dt=1.0)
    K_fit, T_fit = _zigzag_fit(trial, -0.1, 1000.0)
    assert abs(K_fit / T_fit - nm.values["K_over_T"]) < 2 * nm.std["K_over_T"]


@pytest.mark.slow
def test_ebm_identified_esso_osaka_zigzag_nomoto_against_the_ship():
    """The EBM model identified from one simulated PRBS run of the Esso Osaka (the README example), exported
    as the K, T of its 10/10 zig-zag with Monte Carlo std over its covariance (40 seeded draws), against the
    same export of the packaged model it was identified from (the ship). K/T is determined and covers the
    ship's within 2 std (measured 0.6 std with 100 draws). K and T are not: some draws are course-unstable, their zig-zag
    yaw rate grows and the fitted T runs off, so the std of K and T exceeds their magnitude and they are
    labelled not determined rather than printed as estimates."""
    import shipid

    run = shipid.simulate("esso-osaka", "prbs-35-105", duration=600, noise=True, seed=2)
    res = shipid.identify("ebm", [run], vessel="esso-osaka")
    nm = nomoto(res, about="zigzag-10", samples=40, seed=1)
    ship = nomoto("esso-osaka", about="zigzag-10")
    assert nm.method == "monte-carlo" and "percentiles_16_50_84" in nm.extra
    assert nm.status["K_over_T"] == "estimated"
    comb = np.hypot(nm.std["K_over_T"], ship.std["K_over_T"])
    assert abs(nm.values["K_over_T"] - ship.values["K_over_T"]) < 2 * comb
    assert nm.status["K"] == nm.status["T"] == "not determined"
    assert "not determined" in nm.summary() and f"{nm.K:.5g}" not in nm.summary()
