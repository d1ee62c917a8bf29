"""Simulated coverage study of ``identify mmg`` (fixed structure, ``refine='none'`` unless asked).

Each campaign run (:func:`shipid.campaign.engine.run_campaign`, task :func:`run_one`) draws from its own
``SeedSequence``: a TRUE model, the published Esso Osaka 3-m MMG set
(:func:`shipid.models.mmg.load_published`) with every coefficient of ``coef`` multiplied by
``1 + 0.15 N(0, 1)`` (the coefficients free in the structure below; the fixed ones stay) clipped to [0.05, 1.95] (sign kept); measurement noise on x, y, psi, u, v, r
with standard deviations drawn per run (the estimator is not told them); rudder/propeller
sequences: a 35-deg turn to each side, a timed 20-deg zig-zag and a random-input run from
u = 0.4 m/s at n = 10 1/s, simulated by :func:`shipid.models.mmg.simulate_batch`.
:func:`shipid.methods.mmg.pipeline.identify` then fits the fixed structure ``hull+rudder+thrust``
(no structure selection) and the run compares every free coefficient with the truth, using the
standard error MODEL.json carries (run bootstrap / HAC, :mod:`shipid.methods.mmg.covariance`).
:func:`summarise` gives per coefficient bias and spread of the relative error and coverage of ±2 std.

Rudder orders are followed at :data:`RUDDER_RATE` (the IMO steering-gear minimum, Froude-scaled;
``--rudder-rate inf`` gives instantaneous steps).

Options (:func:`run_one`): ``refine="output-error"`` refines each fit by output error (the study then
needs long runs, ``--duration 1200``); ``imo_samples=N`` compares the IMO criteria and their bands with the
truth's; ``vessel="kvlcc2"`` (:data:`VESSELS`) draws truths around the ``kvlcc2_hsva`` prior with seven
150-s zig-zags and the structure ``full/symmetric-gamma_R``. :func:`summarise` also reports the coverage with
the model-form term of :func:`shipid.methods.mmg.pipeline.form_check` (``coverage_2std_with_form``) and
counts that check's flags (``summary["form_check"]``).

What the campaigns measured, and the changes to the estimator they led to: ``docs/validation/mmg.md``.
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass

import numpy as np

from shipid.io.trial import Trial
from shipid.errors import ShipidError
from shipid.methods.mmg import imo
from shipid.methods.mmg import manoeuvres as M
from shipid.methods.mmg.candidates import CANDIDATES, apply_candidate
from shipid.methods.mmg.estimator import FitConfig
from shipid.methods.mmg.output_error import LEAST_SQUARES, OEConfig
from shipid.methods.mmg.pipeline import identify
from shipid.methods.mmg.simex import SimexConfig
from shipid.models import mmg

STRUCTURE = "hull+rudder+thrust"
#: The output-error criteria ``run_one(criterion=...)`` knows.
CRITERIA = {"huber": OEConfig(), "least-squares": LEAST_SQUARES}
SPREAD = 0.15
DT = 0.1
#: Propeller rate (rev/s) of the IMO manoeuvres compared in :func:`imo_comparison`: the campaign's approach rate.
IMO_RPS = 10.0


def free_coefficients(base: mmg.MmgModel, structure: str = STRUCTURE) -> list[str]:
    """The coefficients ``structure`` leaves free (the others stay at ``base``'s values in the fit)."""
    _, free = apply_candidate(base, CANDIDATES[base.structure][structure])
    return [c for m in mmg.MODES for c in free.get(m, ())]


def draw_truth(rng: np.random.Generator, base: mmg.MmgModel, structure: str = STRUCTURE) -> mmg.MmgModel:
    """``base`` with each FREE coefficient × clip(1 + SPREAD N(0,1), 0.05, 1.95) (sign kept); the
    coefficients the structure fixes keep their values, so the fit's fixed values are right. The truth
    carries the structure's particulars (:func:`apply_candidate`), so it lies inside the fitted model class."""
    base, free = apply_candidate(base, CANDIDATES[base.structure][structure])
    names = {c for m in mmg.MODES for c in free.get(m, ())}
    coef = {k: float(v) * (float(np.clip(1.0 + SPREAD * rng.standard_normal(), 0.05, 1.95)) if k in names else 1.0)
            for k, v in base.coef.items()}
    return mmg.MmgModel(base.structure, dict(base.particulars), coef, name="coverage-truth",
                        sources=dict(base.sources))


def _orders(kind: str, t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    U = np.zeros((t.size, 4))
    U[:, 1] = 10.0
    if kind == "turn+":
        U[:, 0] = np.deg2rad(35.0) * (t > 5.0)
    elif kind == "turn-":
        U[:, 0] = -np.deg2rad(35.0) * (t > 5.0)
    elif kind == "zigzag":
        U[:, 0] = np.deg2rad(20.0) * np.sign(np.sin(2 * np.pi * t / 40.0))
    else:
        k = np.arange(t.size) // 80
        U[:, 0] = np.deg2rad(rng.uniform(-30, 30, k.max() + 1))[k]
        U[:, 1] = rng.uniform(7, 12, k.max() + 1)[k]
    return U


#: Rudder rate of the simulated steering gear (deg/s): the IMO minimum, 35 deg to 30 deg on the other side
#: in 28 s (2.32 deg/s, SOLAS II-1/29), Froude-scaled from the Esso Osaka's 325 m to the 3-m model.
RUDDER_RATE = 2.32 * float(np.sqrt(325.0 / 3.0))


def rate_limited(delta: np.ndarray, rate_deg_s: float, dt: float = DT) -> np.ndarray:
    """The rudder angle ``delta`` (rad) as a steering gear of ``rate_deg_s`` follows it (inf: unchanged)."""
    if not np.isfinite(rate_deg_s):
        return delta
    out = np.array(delta, float)
    step = np.deg2rad(rate_deg_s) * dt
    for k in range(1, out.size):
        out[k] = out[k - 1] + np.clip(delta[k] - out[k - 1], -step, step)
    return out


def simulate_campaign(truth: mmg.MmgModel, rng: np.random.Generator, seconds: float = 120.0,
                      rudder_rate: float = RUDDER_RATE):
    """The four measured runs of ``truth`` and the noise standard deviations drawn for them; the rudder
    orders followed at ``rudder_rate`` deg/s (inf: instantaneous steps)."""
    sig = np.array([0.02, 0.02, 0.005, 0.01, 0.01, 0.003]) * rng.uniform(0.5, 2.0, 6)
    t = np.arange(0.0, seconds, DT)
    trials = []
    for kind in ("turn+", "turn-", "zigzag", "random"):
        U = _orders(kind, t, rng)
        U[:, 0] = rate_limited(U[:, 0], rudder_rate)
        X = mmg.simulate_batch(truth, t, np.array([[0, 0, 0, 0.4, 0, 0]]), U[None])[0]
        ch = {c: X[:, i] + s * rng.standard_normal(t.size) for i, (c, s) in enumerate(zip(mmg.STATE_NAMES, sig))}
        ch.update(delta=U[:, 0], n=U[:, 1])
        trials.append(Trial(t, ch, {}, {"source": f"coverage-{kind}"}))
    return trials, sig


@dataclass(frozen=True)
class Vessel:
    """A campaign's ship and test programme.

    ``published``: the MMG set whose perturbations are the truths (:func:`shipid.models.mmg.load_published`);
    ``structure``: the fixed structure identified (a key of ``CANDIDATES[base.structure]``); ``rps``: the
    propeller rate (rev/s) of the runs and of the IMO comparison; ``rudder_rate``: the steering gear (deg/s);
    ``dt``: sample interval (s); ``noise``: standard deviations of x, y, ψ, u, v, r (m, rad, m/s, rad/s),
    each multiplied by U(0.5, 2) per campaign; ``zigzags``: the runs as (order deg, switch deg, first side
    +1 starboard / −1 port), Kempf zig-zags from the truth's straight-line speed at ``rps``
    (:func:`simulate_zigzag_campaign`); empty: the Esso programme of :func:`simulate_campaign`;
    ``seconds``: default run length (s)."""

    published: str
    structure: str
    rps: float
    rudder_rate: float
    dt: float
    noise: tuple[float, ...]
    zigzags: tuple[tuple[float, float, float], ...] = ()
    seconds: float = 120.0


#: The campaigns :func:`run_one` knows. ``kvlcc2``: the HSVA test programme of the KVLCC2 L7 model (13
#: zig-zags, 5°–35°, at 10.23 rev/s, rudder at 13 deg/s: the medians :func:`shipid.methods.mmg.manoeuvres.training_conditions`
#: gives on the HSVA runs) cut to seven zig-zags of 150 s, identified in the structure the
#: horizon selection chooses on all 13 HSVA runs (``full/symmetric-gamma_R``) with the differential
#: form (:data:`shipid.methods.mmg.estimator.EQUATION_BY_STRUCTURE`); truths around the prior the
#: HSVA runs are identified from (``kvlcc2_hsva``: Yasukawa & Yoshimura 2015's coefficients, HSVA
#: particulars; needs the shared data folder).
VESSELS = {
    "esso-osaka": Vessel("esso_osaka_3m", STRUCTURE, IMO_RPS, RUDDER_RATE, DT,
                         (0.02, 0.02, 0.005, 0.01, 0.01, 0.003)),
    "kvlcc2": Vessel("kvlcc2_hsva", "full/symmetric-gamma_R", 10.23, 13.0, 0.05,
                     (0.01, 0.01, 0.002, 0.005, 0.005, 0.002),
                     ((10.0, 10.0, 1.0), (10.0, 10.0, -1.0), (20.0, 20.0, 1.0), (20.0, 20.0, -1.0),
                      (15.0, 5.0, 1.0), (25.0, 5.0, -1.0), (35.0, 5.0, 1.0)), 150.0),
}


def simulate_zigzag_campaign(truth: mmg.MmgModel, rng: np.random.Generator, vessel: Vessel,
                             seconds: float | None = None):
    """The zig-zags of ``vessel`` on ``truth`` (:func:`shipid.methods.mmg.manoeuvres.simulate_rudder_batch`,
    after a 10-s approach at the truth's straight-line speed at ``vessel.rps``), with measurement noise,
    and the noise standard deviations drawn for them."""
    sig = np.asarray(vessel.noise, float) * rng.uniform(0.5, 2.0, 6)
    cond = M.Conditions(speed=M.equilibrium_speed(truth, vessel.rps), rps=vessel.rps,
                        rudder_rate=float(np.deg2rad(vessel.rudder_rate)))
    order, switch, side = (np.array(c, float) for c in zip(*vessel.zigzags))
    rec = M.simulate_rudder_batch(truth, M.theta_rows(truth), np.deg2rad(order), np.deg2rad(switch), side, cond,
                                  dt=vessel.dt, t_max=float(vessel.seconds if seconds is None else seconds),
                                  until_reversals=np.iinfo(np.int32).max)
    trials = []
    for i, (o, sw, sd) in enumerate(vessel.zigzags):
        ch = {c: rec.x[i, :, j] + s * rng.standard_normal(rec.t.size)
              for j, (c, s) in enumerate(zip(mmg.STATE_NAMES, sig))}
        ch.update(delta=rec.delta[i], n=rec.n[i])
        trials.append(Trial(rec.t, ch, {}, {"source": f"coverage-zigzag-{o:g}-{sw:g}-{'S' if sd > 0 else 'P'}"}))
    return trials, sig


def imo_comparison(result: dict, truth: mmg.MmgModel, samples: int, seed: int,
                   vessel: Vessel | None = None, form_term: bool = True) -> dict:
    """The IMO criteria (:func:`shipid.methods.mmg.imo.assess`) of the identified MODEL.json dict ``result``
    with ``samples`` Monte Carlo draws, and of ``truth`` (no draws), both at the campaign's propeller rate
    (``vessel.rps``, each model at its own straight-line speed there) and steering gear (``vessel.rudder_rate``;
    ``vessel`` None: the Esso campaign's, :data:`IMO_RPS` and :data:`RUDDER_RATE`):
    per criterion the nominal value, its std and band, and the truth's value (criteria either side lacks
    are left out)."""
    vessel = VESSELS["esso-osaka"] if vessel is None else vessel
    kw = {"rps": vessel.rps, "rudder_rate_deg_s": vessel.rudder_rate}
    a = imo.assess(result, samples=samples, seed=seed, form_term=form_term, **kw)
    b = imo.assess({"model": truth.to_dict()}, samples=0, **kw)
    out = {}
    for ca, cb in zip(a["criteria"], b["criteria"]):
        if np.isfinite(ca["value"]) and np.isfinite(cb["value"]) and np.isfinite(ca["std"]):
            out[ca["name"]] = {"value": ca["value"], "std": ca["std"], "band": list(ca["band"]),
                               "true": cb["value"], "unit": ca["unit"]}
    return out


def run_one(i: int, seed=0, *, seconds: float | None = None, equation: str | None = None,
            window_s: float | None = None, simex: bool = True, rudder_rate: float | None = None,
            imo_samples: int = 0, vessel: str = "esso-osaka", refine: str = "none",
            criterion: str = "huber") -> dict:
    """Campaign task: draw truth and noise, simulate, identify with a fixed structure, compare.

    ``vessel``: a key of :data:`VESSELS` (ship, structure, test programme); ``seconds`` and
    ``rudder_rate``: its defaults where None.

    ``equation`` / ``window_s``: the step-2 form (:class:`~shipid.methods.mmg.estimator.FitConfig`),
    the default's where None; ``simex``: correct the regression by
    :func:`shipid.methods.mmg.simex.simex_fit` (default :class:`~shipid.methods.mmg.simex.SimexConfig`);
    ``rudder_rate`` (deg/s) of the simulated steering gear (:data:`RUDDER_RATE`; inf: steps);
    ``refine``: ``"output-error"`` refines the fit (:mod:`shipid.methods.mmg.output_error`, its default
    :class:`~shipid.methods.mmg.output_error.OEConfig`), so the refined coefficients' horizon-cluster
    sandwich std are compared (the run records the refinement's start values, iterations and cost);
    ``criterion``: the refinement's ``"huber"`` (the default ``OEConfig``) or ``"least-squares"``
    (:data:`~shipid.methods.mmg.output_error.LEAST_SQUARES`);
    ``imo_samples`` > 0: also compare the IMO criteria and their bands with the truth's
    (:func:`imo_comparison`, the band's seed drawn from the run's generator after everything else); where
    the identified model has no IMO criteria (no straight-line equilibrium at the propeller rate) the run keeps
    its coefficients and records why (``out["imo_failed"]``), and :func:`summarise` warns.
    Where the SIMEX correction was applied the record holds its λ grid, mean path, noise and Monte Carlo
    standard errors (``out["simex"]``, from :meth:`~shipid.methods.mmg.simex.SimexInfo.to_dict`), so that
    other extrapolants can be studied on a stored campaign without refitting."""
    cfg = FitConfig()
    if equation is not None:
        cfg = dataclasses.replace(cfg, equation=equation)
    if window_s is not None:
        cfg = dataclasses.replace(cfg, window_s=float(window_s))
    ves = VESSELS[vessel]
    if rudder_rate is not None:
        ves = dataclasses.replace(ves, rudder_rate=float(rudder_rate))
    seconds = ves.seconds if seconds is None else float(seconds)
    rng = np.random.default_rng(seed)
    base = mmg.load_published(ves.published)
    truth = draw_truth(rng, base, ves.structure)
    if ves.zigzags:
        trials, sig = simulate_zigzag_campaign(truth, rng, ves, seconds)
    else:
        trials, sig = simulate_campaign(truth, rng, seconds, ves.rudder_rate)
    with warnings.catch_warnings(record=True) as caught:   # the fit's warnings go into the run's record
        warnings.simplefilter("always")
        res = identify(trials, base, structure=ves.structure, select=False, refine=refine, fit_config=cfg,
                       simex=SimexConfig() if simex else None, oe_config=CRITERIA[criterion])
    lines = list(res.diagnostics.get("warnings", []))
    lines += [str(w.message) for w in caught if str(w.message) not in lines]
    out = {"noise_sigma": sig.tolist(), "coefficients": {}, "warnings": lines}
    sx = res.diagnostics.get("simex")
    if sx and sx.get("applied"):
        out["simex"] = {"lambdas": sx["lambdas"], "path": sx["path"], "noise_sd": sx["noise_sd"], "mc_se": sx["mc_se"]}
    oe = res.diagnostics.get("output_error")
    if oe is not None:
        out["output_error"] = {k: oe.get(k) for k in ("refined", "start", "cost_start", "cost_end", "iterations",
                                                      "horizons")}
    check = res.diagnostics.get("form_check")
    if check is not None:
        out["form_check_over"] = list(check["over"])
    for nm in res.covariance_names:
        e = res.estimates[nm]
        out["coefficients"][nm] = {"true": truth.coef[nm], "value": e.value, "std": e.std, "status": e.status}
        if check is not None and nm in check["std_with_form"]:
            out["coefficients"][nm]["std_with_form"] = check["std_with_form"][nm]
        if oe is not None and nm in (oe.get("start") or {}):     # the regression value the refinement started at
            out["coefficients"][nm]["start"] = oe["start"][nm]
    if imo_samples > 0:
        d, s = res.to_dict(), int(rng.integers(2 ** 31))
        try:
            out["imo"] = imo_comparison(d, truth, int(imo_samples), s, ves)
            if check is not None:   # the same draws without the model-form term (imo.sample_coefficients)
                out["imo_estimation"] = imo_comparison(d, truth, int(imo_samples), s, ves, form_term=False)
        except ShipidError as e:    # e.g. no straight-line equilibrium (pipeline.equilibrium_line): the
            out["imo"] = {}         # coefficients are kept, the run has no IMO rows and says why
            out.pop("imo_estimation", None)
            out["imo_failed"] = str(e)
    return out


def summarise_imo(runs: list[dict], key: str = "imo") -> dict:
    """Per IMO criterion over the runs that have it: mean and RMS of (nominal − truth), mean std, and how
    often the truth lies inside the 2.275–97.725 % band and inside nominal ± 2 std. ``key``: ``"imo"``
    (the default bands) or ``"imo_estimation"`` (the same draws without the model-form term)."""
    names = sorted({n for o in runs for n in o.get(key, {})})
    table = {}
    for nm in names:
        r = [o[key][nm] for o in runs if nm in o.get(key, {})]
        err = np.array([x["value"] - x["true"] for x in r])
        std = np.array([x["std"] for x in r])
        inband = [x["band"][0] <= x["true"] <= x["band"][1] for x in r]
        table[nm] = {"n": len(r), "unit": r[0]["unit"], "bias": float(err.mean()),
                     "rms_error": float(np.sqrt(np.mean(err ** 2))), "mean_std": float(std.mean()),
                     "coverage_band": float(np.mean(inband)), "coverage_2std": float(np.mean(np.abs(err) <= 2 * std))}
    return table


def summarise(outputs) -> dict:
    """Per free coefficient: runs estimated, bias/spread of the relative error, coverage of ±2 std."""
    runs = [o for o in outputs if o is not None]
    names = sorted({n for o in runs for n in o["coefficients"]})
    table = {}
    for nm in names:
        est = [o["coefficients"][nm] for o in runs if o["coefficients"].get(nm, {}).get("status") == "estimated"]
        rel = np.array([(r["value"] - r["true"]) / abs(r["true"]) for r in est])
        z = np.array([(r["value"] - r["true"]) / r["std"] for r in est])
        table[nm] = {"estimated": len(est), "runs": len(runs),
                     "bias_rel": float(rel.mean()) if rel.size else None,
                     "spread_rel": float(rel.std(ddof=1)) if rel.size > 1 else None,
                     "coverage_2std": float(np.mean(np.abs(z) <= 2.0)) if z.size else None}
        wf = [r for r in est if "std_with_form" in r]
        if wf:   # the differential form's std with its model-form term (pipeline.form_check)
            zf = np.array([(r["value"] - r["true"]) / r["std_with_form"] for r in wf])
            table[nm]["coverage_2std_with_form"] = float(np.mean(np.abs(zf) <= 2.0))
        ws = [r for r in est if "start" in r]
        if ws:   # refined by output error: the regression start's error, and the std with the shift counted
            rs = np.array([(r["start"] - r["true"]) / abs(r["true"]) for r in ws])
            zs = np.array([(r["value"] - r["true"]) / np.hypot(r["std"], r["value"] - r["start"]) for r in ws])
            table[nm].update(bias_rel_start=float(rs.mean()), spread_rel_start=float(rs.std(ddof=1)) if rs.size > 1
                             else None, coverage_2std_with_shift=float(np.mean(np.abs(zs) <= 2.0)))
    low = [nm for nm, t in table.items() if t["coverage_2std"] is not None
           and t["coverage_2std"] < 0.95 - 2.0 * np.sqrt(0.95 * 0.05 / t["estimated"])]
    findings = []
    if low:
        findings.append(f"the +-2 std of {len(low)} of {len(table)} coefficients cover the truth less often than "
                        f"0.95 allows at these run counts ({', '.join(low)}): those standard errors are not honest "
                        "(shipid.methods.mmg.coverage)")
    out = {"runs": len(runs), "table": table, "warnings": findings}
    checked = [o["form_check_over"] for o in runs if "form_check_over" in o]
    if checked:
        # how often the differential form's own check (pipeline.form_check) said its standard errors were off
        per = {nm: sum(nm in o for o in checked) for nm in names}
        out["form_check"] = {"runs": len(checked), "flagged": sum(bool(o) for o in checked),
                             "by_coefficient": {nm: k for nm, k in per.items() if k}}
    if any("imo_estimation" in o for o in runs):
        out["imo_estimation"] = summarise_imo(runs, "imo_estimation")
    failed = [o["imo_failed"] for o in runs if "imo_failed" in o]
    if failed:
        findings.append(f"the IMO criteria of {len(failed)} of {len(runs)} identified models could not be computed "
                        f"and are left out of the IMO table; their coefficients are counted (first: {failed[0]})")
    if any("imo" in o for o in runs):
        it = summarise_imo(runs)
        out["imo"] = it
        lowi = [nm for nm, t in it.items() if t["coverage_band"] < 0.95 - 2.0 * np.sqrt(0.95 * 0.05 / t["n"])]
        if lowi:
            findings.append(f"the IMO bands of {len(lowi)} of {len(it)} criteria contain the true value less often "
                            f"than 0.95 allows at these run counts ({', '.join(lowi)}) "
                            "(shipid.methods.mmg.coverage)")
    return out


__all__ = ["run_one", "summarise", "summarise_imo", "imo_comparison", "draw_truth", "simulate_campaign",
           "simulate_zigzag_campaign", "Vessel", "VESSELS", "STRUCTURE"]
