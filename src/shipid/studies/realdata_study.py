"""Held-out studies on real free-running data (issue 6).

``esso_heldout(split)``
    Train on the training runs of the split the data set's README gives
    (``miyauchi2022``: Miyauchi et al. 2022, Train-TRZ; ``wakita2022``: Wakita et al.
    2022, Train-TZRB+), choose the structure by cross-validation *within those runs*,
    and report, on the split's test runs only, the errors of 60-s horizons restarted
    from the measured state every 60 s — for the identified model and for the
    published MMG set of the same ship simulated with the same inputs and metrics.
``kvlcc2_zigzag()``
    Identify from ten of the thirteen HSVA KVLCC2 zig-zags and predict the held-out
    20/10 (port and starboard first) and 35/5 runs as closed-loop zig-zags from the
    measured state at execute; first and second overshoot angles predicted vs
    measured, for the identified model and for the KVLCC2 L7 coefficients.

Nothing here is copied from the data: the runs are read from
:func:`shipid.data.data_root` at run time.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from shipid.data import data_root, read_trial
from shipid.data.trial import Trial
from shipid.errors import InputError
from shipid.methods import realdata as R
from shipid.methods import validate as V
from shipid.models import mmg

# --------------------------------------------------------------------------- Esso Osaka splits
# shared/data/esso_osaka_3m/README_upstream.md, "Correspondence table with the paper".
_RND = "random/random_{}.csv"
SPLITS: dict[str, dict[str, list[str]]] = {
    "miyauchi2022": {
        "train": [_RND.format("06-Aug-2020_16_24_25_4"), _RND.format("06-Aug-2020_16_24_25_5"),
                  _RND.format("06-Aug-2020_16_24_25_6"), "turning/turn_cut_14-Sep-2020_16_09_02.csv",
                  "zigzag/zigzag_31-Jul-2020_13_22_52.csv", "zigzag/zigzag_31-Jul-2020_13_50_28.csv"],
        "test": [_RND.format("06-Aug-2020_16_24_25_3"), "turning/turn_14-Sep-2020_14_50_41.csv",
                 "zigzag/zigzag_31-Jul-2020_14_10_05.csv", "berthing/berthing_12-Nov-2020_11_49_21.csv",
                 "berthing/berthing_12-Nov-2020_13_21_03.csv"],
        "train_label": ["Train-TRZ"],
    },
    "wakita2022": {
        "train": [_RND.format(s) for s in ("03-Aug-2020_11_04_37", "06-Aug-2020_16_24_25_1",
                                           "06-Aug-2020_16_24_25_4", "06-Aug-2020_16_24_25_5",
                                           "06-Aug-2020_16_24_25_6", "31-Jul-2020_12_29_58",
                                           "31-Jul-2020_12_48_39", "31-Jul-2020_14_52_18")]
        + [f"turning/turn_{s}.csv" for s in ("14-Oct-2020_14_08_51", "14-Oct-2020_14_17_39",
                                            "14-Oct-2020_14_29_49", "14-Oct-2020_14_39_54",
                                            "14-Oct-2020_14_56_07", "14-Oct-2020_15_21_57",
                                            "14-Sep-2020_13_39_32", "14-Sep-2020_13_51_45",
                                            "14-Sep-2020_14_16_04", "14-Sep-2020_14_50_41",
                                            "14-Sep-2020_15_47_33", "14-Sep-2020_15_58_08",
                                            "cut_14-Sep-2020_15_58_08", "cut_14-Sep-2020_16_09_02")]
        + [f"zigzag/zigzag_31-Jul-2020_{s}.csv" for s in ("13_04_24", "13_14_21", "13_22_52", "13_29_19",
                                                          "13_50_28", "13_57_45", "14_03_39", "14_10_05")]
        + [f"berthing/berthing_12-Nov-2020_{s}.csv" for s in ("11_07_23", "11_14_47", "11_21_46",
                                                             "13_09_11", "13_37_05")],
        "test": [_RND.format("06-Aug-2020_16_24_25_3"), "turning/turn_14-Oct-2020_15_06_53.csv",
                 "zigzag/zigzag_31-Jul-2020_13_42_53.csv", "berthing/berthing_12-Nov-2020_11_38_50.csv",
                 "berthing/berthing_12-Nov-2020_11_49_21.csv", "berthing/berthing_12-Nov-2020_13_21_03.csv"],
        "train_label": ["Train-TZRB+"],
    },
}


def _esso_dir(root: Path | None) -> Path:
    root = data_root() if root is None else Path(root)
    d = None if root is None else root / "esso_osaka_3m" / "data"
    if d is None or not d.is_dir():
        raise InputError("the Esso Osaka data (esso_osaka_3m/data) was not found; set SHIPID_DATA")
    return d


def read_esso(rel: str, root: Path | None = None) -> Trial:
    """One Esso Osaka run (empty trailing rows trimmed, as the data set's README allows)."""
    return read_trial(_esso_dir(root) / rel, trim_empty_rows=True, method="realdata study")


def _pooled(rows: Sequence[dict]) -> dict[str, dict[str, float]]:
    """Pool horizon metrics over runs (RMS weighted by horizon count, max of maxima)."""
    out = {}
    w = np.array([r["count"] for r in rows], float)
    for q in V.QUANTITIES:
        rms = np.array([r[q]["rms"] for r in rows])
        mx = np.array([r[q]["max"] for r in rows])
        out[q] = {"rms": float(np.sqrt(np.sum(w * rms ** 2) / np.sum(w))), "max": float(np.max(mx)),
                  "unit": V.UNITS[q]}
    out["count"] = int(w.sum())
    return out


def evaluate(models: dict[str, mmg.MmgModel], trials: Sequence[Trial], horizon: float = 60.0,
             progress: Callable[[], None] | None = None) -> dict[str, Any]:
    """Horizon errors of every model on every trial, and pooled over trials."""
    per: dict[str, dict[str, dict]] = {name: {} for name in models}
    for tr in trials:
        key = Path(str(tr.meta.get("source", ""))).name
        for name, m in models.items():
            v = V.validate(m, tr, horizon=horizon, windows=(), whole=False)
            per[name][key] = v.horizons
            if progress is not None:
                progress()
    pooled = {name: _pooled(list(per[name].values())) for name in models}
    return {"per_run": per, "pooled": pooled}


def esso_heldout(split: str = "miyauchi2022", *, root: Path | None = None, folds: int | None = 3,
                 select: bool = True, structure: str | None = None, max_train: int | None = None,
                 progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Train on the split's training runs, report held-out horizon errors (module docstring).

    Parameters
    ----------
    folds : int or None
        Cross-validation folds within the training runs for the structure choice
        (None: leave one run out).
    max_train : int, optional
        Use only the first ``max_train`` training runs (for quick checks; the study
        proper uses all).
    """
    if split not in SPLITS:
        raise InputError(f"unknown split '{split}' (choose from {', '.join(SPLITS)})")
    sp = SPLITS[split]
    say = progress or (lambda s: None)
    train_files = sp["train"][:max_train] if max_train else sp["train"]
    assert not set(train_files) & set(sp["test"]), "a test run is in the training set"
    say(f"{split}: reading {len(train_files)} training runs")
    train = [read_esso(f, root) for f in train_files]
    test = [read_esso(f, root) for f in sp["test"]]
    prior = mmg.load_published("esso_osaka_3m", root)
    say(f"{split}: identifying (step 1 smoothing, structure by {folds or 'leave-one-out'}-fold CV in training runs)")
    res = R.identify(train, prior, structure=structure, select=select, folds=folds,
                     name=f"esso-osaka-3m-ebm-{split}",
                     extra_provenance={"split": split, "train_label": sp["train_label"],
                                       "test_runs_never_used": sp["test"]})
    ident = V.model_from_result(res.to_dict())
    say(f"{split}: validating on {len(test)} test runs")
    ev = evaluate({"identified": ident, "published": prior}, test)
    return {"split": split, "train": train_files, "test": sp["test"], "result": res.to_dict(),
            "structure": res.model.get("structure_candidate"),
            "selection": res.diagnostics.get("structure_selection"), "heldout": ev}


def format_esso(study: dict[str, Any]) -> str:
    """Text table of :func:`esso_heldout`."""
    ev = study["heldout"]
    lines = [f"split {study['split']}: trained on {len(study['train'])} runs, structure '{study['structure']}'"]
    sel = study.get("selection")
    if sel:
        lines.append(f"  structure chosen by {sel['method']}:")
        for c, row in sel["table"].items():
            lines.append(f"    {c:<36} CV score {row['score']:8.3f}  (psi {row['psi_rms_deg']:.2f} deg, "
                         f"pos {row['pos_rms_m']:.3f} m, {row['folds']} folds)")
    lines.append("  held-out 60-s horizons restarted from the measured state (RMS / max):")
    head = f"  {'test run':<40} {'model':<11}" + "".join(f"{q + ' [' + V.UNITS[q] + ']':>19}" for q in V.QUANTITIES)
    lines.append(head)
    runs = list(next(iter(ev["per_run"].values())).keys())
    for run in runs + ["POOLED"]:
        for name in ev["per_run"]:
            s = ev["pooled"][name] if run == "POOLED" else ev["per_run"][name][run]
            lines.append(f"  {run:<40} {name:<11}" + "".join(f"{s[q]['rms']:>9.3g} /{s[q]['max']:>8.3g}"
                                                              for q in V.QUANTITIES))
    pi, pp = ev["pooled"]["identified"], ev["pooled"]["published"]
    better = pi["psi"]["rms"] < pp["psi"]["rms"] and pi["pos"]["rms"] < pp["pos"]["rms"]
    lines.append(f"  pooled heading RMS {pi['psi']['rms']:.2f} vs {pp['psi']['rms']:.2f} deg, position RMS "
                 f"{pi['pos']['rms']:.3f} vs {pp['pos']['rms']:.3f} m (identified vs published): "
                 f"{'identified better on both' if better else 'target NOT met'}")
    return "\n".join(lines)


# --------------------------------------------------------------------------- KVLCC2 zig-zags
KVLCC2_TEST = ("HSVA_CPMC_KVLCC2_Z_20_10_P.dat", "HSVA_CPMC_KVLCC2_Z_20_10_S.dat", "HSVA_CPMC_KVLCC2_Z_35_05.dat")
KVLCC2_TRAIN = ("HSVA_CPMC_KVLCC2_Z_05_01.dat", "HSVA_CPMC_KVLCC2_Z_10_01.dat", "HSVA_CPMC_KVLCC2_Z_10_05.dat",
                "HSVA_CPMC_KVLCC2_Z_10_10_P.dat", "HSVA_CPMC_KVLCC2_Z_10_10_S.dat",
                "HSVA_CPMC_KVLCC2_Z_15_01.dat", "HSVA_CPMC_KVLCC2_Z_15_05.dat", "HSVA_CPMC_KVLCC2_Z_20_05.dat",
                "HSVA_CPMC_KVLCC2_Z_25_05.dat", "HSVA_CPMC_KVLCC2_Z_30_05.dat")


def read_kvlcc2(name: str, root: Path | None = None) -> Trial:
    """One HSVA zig-zag with the rudder in the MMG convention.

    HSVA records the rudder positive to port: in every run the yaw rate has the sign
    of −δ (checked on all 13 files). The MMG convention (positive δ turns the ship to
    starboard) needs ``δ = −δ_HSVA``; the flip is recorded in ``meta``.
    """
    root = data_root() if root is None else Path(root)
    d = None if root is None else root / "kvlcc2_hsva"
    if d is None or not d.is_dir():
        raise InputError("the KVLCC2 HSVA data (kvlcc2_hsva) was not found; set SHIPID_DATA")
    tr = read_trial(d / name, fmt="kvlcc2", method="realdata study")
    out = tr.with_channels(delta=-tr["delta"])
    out.meta["rudder_sign_flipped"] = "delta = -delta_HSVA (HSVA: positive to port)"
    return out


def zigzag_angles(name: str) -> tuple[float, float]:
    """(rudder, switch heading) in rad from an HSVA file name ``..._Z_20_10_P.dat``."""
    m = re.search(r"_Z_(\d+)_(\d+)", name)
    if not m:
        raise InputError(f"cannot read the zig-zag angles from '{name}'")
    return np.deg2rad(float(m.group(1))), np.deg2rad(float(m.group(2)))


def execute_index(delta: np.ndarray, threshold: float = np.deg2rad(1.0)) -> int:
    """First sample where the rudder has moved more than ``threshold`` from its initial value."""
    k = np.flatnonzero(np.abs(delta - delta[0]) > threshold)
    if k.size == 0:
        raise InputError("no rudder execute found")
    return max(int(k[0]) - 1, 0)


def overshoots(t: np.ndarray, psi: np.ndarray, k_exec: int, psi_switch: float, side: int,
               count: int = 2) -> list[float]:
    """Overshoot angles (rad) from the heading alone.

    ``ψ₀ = ψ(k_exec)``; the i-th reversal is where ``d_i (ψ − ψ₀)`` first reaches the
    switch angle (``d_1 = side``, alternating); the i-th overshoot is the largest
    ``d_i (ψ − ψ₀) − ψ_switch`` between that reversal and the next. The same rule is
    applied to measured and predicted headings, so their overshoots are comparable
    whatever the rudder signal's noise.
    """
    p = np.unwrap(psi) - np.unwrap(psi)[k_exec]
    out, k, d = [], k_exec, side
    for _ in range(count):
        hit = np.flatnonzero(d * p[k:] >= psi_switch)
        if hit.size == 0:
            break
        k1 = k + int(hit[0])
        nxt = np.flatnonzero(-d * p[k1:] >= psi_switch)
        end = k1 + int(nxt[0]) if nxt.size else p.size
        seg = d * p[k1:end]
        j = int(np.argmax(seg))
        if end == p.size and j == seg.size - 1:
            break                                   # still turning when the record ends
        out.append(float(seg[j] - psi_switch))
        k, d = k1, -d
    return out


def reversal_delays(tr: Trial, psi_switch: float, threshold: float = np.deg2rad(0.5)) -> list[float]:
    """Delays (s) between each measured heading crossing of ±ψ_switch and the rudder starting to reverse.

    The tank's autopilot does not reverse the rudder at the very sample the heading
    passes the switch angle: on the HSVA runs it starts 0.3–0.7 s later. The start is
    the first sample after the crossing where the rudder has left its value at the
    crossing by ``threshold`` towards the other side.
    """
    k0 = execute_index(tr["delta"])
    p = np.unwrap(tr["psi"]) - np.unwrap(tr["psi"])[k0]
    d = tr["delta"]
    side = 1 if np.mean(d[k0:k0 + int(round(5 / tr.dt))]) > 0 else -1
    out, k, s = [], k0, side
    while True:
        hit = np.flatnonzero(s * p[k:] >= psi_switch)
        if hit.size == 0:
            break
        k1 = k + int(hit[0])
        mv = np.flatnonzero(s * (d[k1:] - d[k1]) < -threshold)
        if mv.size == 0:
            break
        out.append(float(tr.t[k1 + int(mv[0])] - tr.t[k1]))
        k, s = k1, -s
    return out


def simulate_zigzag(model: mmg.MmgModel, tr: Trial, delta_z: float, psi_switch: float, *,
                    rate: float, delay: float = 0.0, duration: float | None = None) -> np.ndarray:
    """Closed-loop zig-zag of ``model`` from the measured state at execute; heading history (n,).

    The rudder moves at ``rate`` (rad/s) towards ``±delta_z`` and reverses ``delay``
    seconds after the *predicted* heading passes ``±psi_switch`` from ψ at execute
    (Kempf's rule with the tank autopilot's reaction time); propeller revolutions are
    the measured ones.
    """
    Z = V.measured_states(tr)
    Uin = V.trial_inputs(tr)
    k0 = execute_index(tr["delta"])
    t = tr.t[k0:] if duration is None else tr.t[k0:k0 + int(round(duration / tr.dt))]
    dt = float(np.median(np.diff(t)))
    x = Z[k0][None].copy()
    psi0 = x[0, 2]
    side = 1 if np.mean(tr["delta"][k0:k0 + int(5 / dt)]) > 0 else -1   # MMG: δ > 0 turns to starboard
    d = side
    delta = float(tr["delta"][k0])
    out = np.full(t.size, np.nan)
    out[0] = x[0, 2]
    switches = 0
    pending: float | None = None       # time at which an ordered reversal takes effect
    cmd = d
    for k in range(t.size - 1):
        tk = t[k] - t[0]
        if pending is None and d * (x[0, 2] - psi0) >= psi_switch:
            d = -d
            switches += 1
            pending = tk + delay
            if switches > 3:          # the second overshoot ends at the third reversal
                return out[:k + 1]
        if pending is not None and tk >= pending - 1e-9:
            cmd, pending = d, None
        target = cmd * delta_z
        delta += np.clip(target - delta, -rate * dt, rate * dt)
        u = np.array([[delta, Uin[k0 + k, 1], 0.0, 0.0]])
        x = mmg.simulate_batch(model, np.array([0.0, dt]), x, u[:, None, :].repeat(2, axis=1))[:, -1]
        out[k + 1] = x[0, 2]
    return out


def rudder_rate(tr: Trial) -> float:
    """Rudder rate of the run (rad/s): 95th percentile of |dδ/dt| over samples where the rudder moves."""
    dd = np.abs(np.diff(tr["delta"])) / np.diff(tr.t)
    moving = dd[dd > np.deg2rad(1.0)]
    return float(np.percentile(moving, 95)) if moving.size else float(np.deg2rad(15.0))


def kvlcc2_zigzag(*, root: Path | None = None, folds: int | None = 5, select: bool = True,
                  structure: str | None = None, train: Sequence[str] = KVLCC2_TRAIN,
                  test: Sequence[str] = KVLCC2_TEST,
                  progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Identify from ``train`` zig-zags, predict the held-out ``test`` zig-zags (module docstring)."""
    say = progress or (lambda s: None)
    assert not set(train) & set(test), "a test run is in the training set"
    prior = mmg.load_published("kvlcc2_hsva", root)
    trs = [read_kvlcc2(f, root) for f in train]
    # the autopilot's reaction time and the rudder rate: from the training runs only
    delays = [dl for f, tr in zip(train, trs) for dl in reversal_delays(tr, zigzag_angles(f)[1])]
    delay = float(np.median(delays)) if delays else 0.0
    rate = float(np.median([rudder_rate(tr) for tr in trs]))
    say(f"kvlcc2: identifying from {len(trs)} zig-zags")
    res = R.identify(trs, prior, structure=structure, select=select, folds=folds, name="kvlcc2-hsva-ebm",
                     extra_provenance={"test_runs_never_used": list(test)})
    ident = V.model_from_result(res.to_dict())
    models = {"identified": ident, "published": prior}
    rows = []
    for f in test:
        tr = read_kvlcc2(f, root)
        dz, ps = zigzag_angles(f)
        k0 = execute_index(tr["delta"])
        side = 1 if np.mean(tr["delta"][k0:k0 + 100]) > 0 else -1
        meas = overshoots(tr.t, tr["psi"], k0, ps, side)
        row = {"run": f, "delta_deg": float(np.degrees(dz)), "psi_switch_deg": float(np.degrees(ps)),
               "first_side": "starboard" if side > 0 else "port",
               "measured_deg": [float(np.degrees(o)) for o in meas]}
        for name, m in models.items():
            say(f"kvlcc2: {name} zig-zag on {f}")
            psi = simulate_zigzag(m, tr, dz, ps, rate=rate, delay=delay)
            pred = overshoots(tr.t[k0:], psi, 0, ps, side)
            row[f"{name}_deg"] = [float(np.degrees(o)) for o in pred]
            row[f"{name}_error_deg"] = [float(np.degrees(a - b)) for a, b in zip(pred, meas)]
        rows.append(row)
    ev = evaluate(models, [read_kvlcc2(f, root) for f in test])
    return {"train": list(train), "test": list(test), "result": res.to_dict(),
            "autopilot": {"reversal_delay_s": delay, "rudder_rate_deg_s": float(np.degrees(rate)),
                          "from": "median over the training zig-zags"},
            "structure": res.model.get("structure_candidate"),
            "selection": res.diagnostics.get("structure_selection"), "overshoots": rows, "heldout": ev}


def format_kvlcc2(study: dict[str, Any]) -> str:
    lines = [f"KVLCC2 HSVA: trained on {len(study['train'])} zig-zags, structure '{study['structure']}'"]
    sel = study.get("selection")
    if sel:
        lines.append(f"  structure chosen by {sel['method']}:")
        for c, row in sel["table"].items():
            lines.append(f"    {c:<36} CV score {row['score']:8.3f}")
    lines.append(f"  {'held-out run':<34} {'overshoot':>10} {'measured':>9} {'identified':>11} {'error':>7} "
                 f"{'L7 coefs':>9} {'error':>7}   [deg]")
    worst = 0.0
    for row in study["overshoots"]:
        for i, m in enumerate(row["measured_deg"]):
            def g(key):
                v = row[key]
                return v[i] if i < len(v) else float("nan")
            e = g("identified_error_deg")
            worst = max(worst, abs(e)) if np.isfinite(e) else float("inf")
            lines.append(f"  {row['run']:<34} {['1st', '2nd', '3rd'][i]:>10} {m:9.2f} {g('identified_deg'):11.2f} "
                         f"{e:7.2f} {g('published_deg'):9.2f} {g('published_error_deg'):7.2f}")
    lines.append(f"  largest |error| of the identified model: {worst:.2f} deg "
                 f"({'within' if worst <= 2.0 else 'NOT within'} the 2 deg target)")
    ev = study["heldout"]["pooled"]
    lines.append(f"  60-s horizons on the held-out runs: heading RMS {ev['identified']['psi']['rms']:.2f} vs "
                 f"{ev['published']['psi']['rms']:.2f} deg, position RMS {ev['identified']['pos']['rms']:.3f} vs "
                 f"{ev['published']['pos']['rms']:.3f} m (identified vs L7 coefficients)")
    return "\n".join(lines)


__all__ = ["SPLITS", "esso_heldout", "format_esso", "kvlcc2_zigzag", "format_kvlcc2", "evaluate",
           "overshoots", "simulate_zigzag", "read_esso", "read_kvlcc2", "zigzag_angles", "execute_index",
           "KVLCC2_TRAIN", "KVLCC2_TEST"]
