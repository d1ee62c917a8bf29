"""The Python face of shipid: one call per task, the same names as the CLI.

``shipid.identify(method, trials, *, vessel=..., options=...)`` runs any method and returns its
:class:`~shipid.result.Result`; ``shipid.validate`` predicts a held-out run open loop with an
identified model; ``shipid.simulate`` runs a packaged vessel through a standard manoeuvre. The
methods are named as ``shipid identify --help`` lists them; :data:`METHODS` maps each name to its
paper, its options class and the trials it takes.

Trials may be :class:`~shipid.data.trial.Trial` objects or file paths (read with
:func:`shipid.data.io.read_trial` and the channels the method needs).

Examples
--------
>>> import shipid
>>> tr = shipid.simulate("esso-osaka", "zigzag-20", duration=30.0)      # doctest: +SKIP
>>> res = shipid.identify("ebm", [tr], vessel="esso-osaka")            # doctest: +SKIP
>>> res.estimates["Y_v"].value, res.estimates["Y_v"].std               # doctest: +SKIP
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from shipid.data.io import read_trial
from shipid.data.trial import Trial
from shipid.errors import InputError
from shipid.estimate.linalg import single_threaded
from shipid.methods import ebm as _ebm
from shipid.methods import realdata as _mmg
from shipid.methods import validate as _V
from shipid.methods.dp import DPOptions, identify_dp
from shipid.methods.masscm import REQUIRED as _MASSCM_REQUIRED
from shipid.methods.masscm import MassCMOptions, estimate_mass_cm
from shipid.models import mmg as _mmg_model
from shipid.models.dp import dp_vessel
from shipid.models.roll_reduced import KnownParams
from shipid.result import Result
from shipid.simulate.manoeuvres import run_manoeuvre
from shipid.simulate.noise import default_measurement_model
from shipid.simulate.registry import get_ship_model
from shipid.vessels import load_vessel

#: Channels of a DP trial (Fossen et al. 1996 §4: positions, heading, pitch ratios, azimuth angle).
DP_REQUIRED = ["x", "y", "psi", "p1", "p2", "p3", "p4", "p5", "p6", "alpha6"]


@dataclass(frozen=True)
class MethodInfo:
    """One identification method: its CLI name, what it identifies, its paper and its options class."""

    name: str
    title: str
    paper: str
    trials: str
    options: str


METHODS: dict[str, MethodInfo] = {
    "mass-cm": MethodInfo("mass-cm", "mass and centre of mass from IMU + rudder",
                          "Linder et al. 2015", "mapping nominal/calibration/loaded -> trial(s)",
                          "shipid.methods.masscm:MassCMOptions"),
    "dp": MethodInfo("dp", "DP low-frequency model, parallel state-augmented EKF",
                     "Fossen, Sagatun & Sorensen 1996", "mapping surge/sway-yaw/azimuth -> trials",
                     "shipid.methods.dp:DPOptions"),
    "ebm": MethodInfo("ebm", "Estimation-Before-Modelling of Abkowitz coefficients",
                      "Yoon & Rhee 2003", "sequence of trials", "shipid.methods.ebm:EbmConfig"),
    "mmg": MethodInfo("mmg", "MMG model from free-running model tests (EBM adapted)",
                      "Yoon & Rhee 2003 applied to the MMG structure", "sequence of trials",
                      "shipid.methods.realdata:FitConfig"),
}

_Trialish = Trial | str | os.PathLike


def _method(name: str) -> MethodInfo:
    key = str(name).strip().lower().replace("_", "-")
    if key in ("masscm", "mass-and-cm"):
        key = "mass-cm"
    if key not in METHODS:
        raise InputError(f"unknown method {name!r}; choose from {', '.join(METHODS)}")
    return METHODS[key]


def _as_trial(t: _Trialish, **read_kwargs) -> Trial:
    return t if isinstance(t, Trial) else read_trial(t, **read_kwargs)


def _as_list(x) -> list:
    if isinstance(x, (Trial, str, os.PathLike)):
        return [x]
    return list(x)


def _grouped(trials: Mapping[str, Any], groups: Sequence[str], method: str) -> dict[str, list]:
    if not isinstance(trials, Mapping):
        raise InputError(f"{method}: trials must be a mapping {{{', '.join(groups)}}} -> trial(s)")
    norm = {str(k).replace("_", "-"): v for k, v in trials.items()}
    unknown = sorted(set(norm) - set(groups))
    if unknown:
        raise InputError(f"{method}: unknown trial group(s) {', '.join(unknown)}; expected {', '.join(groups)}")
    missing = [g for g in groups if not norm.get(g)]
    if missing:
        raise InputError(f"{method}: no {', '.join(missing)} trials given")
    return {g: _as_list(norm[g]) for g in groups}


def _identify_mass_cm(trials, *, known=None, options=None, **kw) -> Result:
    groups = _grouped(trials, ("nominal", "calibration", "loaded"), "mass-cm")
    extra: dict[str, Any] = {}
    if known is None:
        raise InputError("mass-cm: known= is required (KnownParams, a dict of its fields, or a known.toml path)")
    if isinstance(known, (str, os.PathLike)):
        from shipid.cli.masscm_cmds import read_known   # the known.toml reader the CLI documents

        kn = read_known(str(known))
        known = kn["known"]
        extra = {k: kn[k] for k in ("z_f", "z_f_prior", "theta0") if kn[k] is not None}
    elif isinstance(known, Mapping):
        known = KnownParams(**known)
    datasets = [(cond, _as_trial(t, required=["t", *_MASSCM_REQUIRED], method="mass-cm"))
                for cond, ts in groups.items() for t in ts]
    extra.update(kw)
    extra.setdefault("init", "given" if extra.get("theta0") is not None else "linear")
    return estimate_mass_cm(datasets, known, options=options or MassCMOptions(), **extra)


def _identify_dp(trials, *, vessel=None, options=None, **kw) -> Result:
    groups = _grouped(trials, ("surge", "sway-yaw", "azimuth"), "dp")
    v = dp_vessel(load_vessel(vessel or "supply"))
    t = {g: [_as_trial(x, required=DP_REQUIRED, manoeuvre=f"dp-{g}") for x in ts] for g, ts in groups.items()}
    return identify_dp(t["surge"], t["sway-yaw"], t["azimuth"], v, options or DPOptions(), **kw)


def _identify_ebm(trials, *, vessel=None, options=None, **kw) -> Result:
    vessel = vessel or "esso-osaka"
    data = [_as_trial(x, required=list(_ebm.REQUIRED), method="ebm", vessel=vessel) for x in _as_list(trials)]
    return _ebm.identify(data, vessel, config=options or _ebm.EbmConfig(), **kw)


def _identify_mmg(trials, *, vessel=None, options=None, prior=None, **kw) -> Result:
    data = [_as_trial(x, trim_empty_rows=True, interpolate_gaps=1.0, method="shipid.identify mmg")
            for x in _as_list(trials)]
    prior = prior or vessel
    if prior is None:
        raise InputError("mmg: prior= is required (a published set such as 'esso_osaka_3m' or 'kvlcc2_hsva', "
                         "or an identified model JSON)")
    if isinstance(prior, str):
        prior = (_V.load_model(prior) if prior.endswith(".json")
                 else _mmg_model.load_published(prior.replace("published:", "")))
    if options is not None:
        kw["fit_config"] = options
    return _mmg.identify(data, prior, **kw)


_IDENTIFY: dict[str, Callable[..., Result]] = {
    "mass-cm": _identify_mass_cm, "dp": _identify_dp, "ebm": _identify_ebm, "mmg": _identify_mmg,
}


@single_threaded
def identify(method: str, trials, *, vessel: str | None = None, options=None, **kwargs) -> Result:
    """Identify a model with ``method`` from ``trials``; the Python form of ``shipid identify METHOD``.

    Parameters
    ----------
    method : {"mass-cm", "dp", "ebm", "mmg"}
        See :data:`METHODS` (paper, options class, trials taken).
    trials
        ``mass-cm``: a mapping ``{"nominal": ..., "calibration": ..., "loaded": ...}`` of a trial or a
        list of trials each; ``dp``: ``{"surge": [...], "sway-yaw": [...], "azimuth": [...]}``;
        ``ebm`` and ``mmg``: a sequence of trials. A trial is a :class:`Trial` or a file path.
    vessel : str, optional
        Packaged vessel (``shipid vessels``): DP particulars (default ``supply``), the EBM ship
        (default ``esso-osaka``); for ``mmg`` the prior may be given here or as ``prior=``.
    options
        The method's frozen options (``MassCMOptions``, ``DPOptions``, ``EbmConfig``, ``FitConfig``).
    **kwargs
        Passed to the method: ``known=`` (mass-cm, required: KnownParams, dict or known.toml path),
        ``z_f=``, ``z_f_prior=``, ``theta0=`` (mass-cm), ``prior=``, ``structure=``, ``folds=`` (mmg) ...

    Returns
    -------
    Result
        Estimates with standard errors, covariance, diagnostics (``converged``, ``warnings``) and
        provenance, as the CLI's ``--json`` prints it. BLAS runs one thread during the call
        (:func:`shipid.estimate.linalg.one_blas_thread`), so the numbers do not depend on the core count.
    """
    info = _method(method)
    if info.name == "mass-cm":
        return _IDENTIFY[info.name](trials, options=options, **kwargs)
    return _IDENTIFY[info.name](trials, vessel=vessel, options=options, **kwargs)


@single_threaded
def validate(model, trial: _Trialish, *, horizon: float = 60.0, **kwargs):
    """Open-loop prediction of a measured run by an identified MMG model (``shipid validate``).

    Parameters
    ----------
    model : Result, MmgModel or str
        An ``identify("mmg", ...)`` result, a model JSON path, or ``"published:<name>"``.
    trial : Trial or path
        The measured run (not used for training).
    horizon : float
        Length of the restarted horizons, s.

    Returns
    -------
    shipid.methods.validate.Validation
        RMS and maximum errors over 30 s, 60 s, the whole run and restarted horizons.

    Only MMG models can be validated today; other results raise :class:`~shipid.errors.InputError`.
    """
    if isinstance(model, Result):
        if model.method not in ("mmg-ebm", "mmg"):
            raise InputError(f"validate: a {model.method!r} result cannot be validated yet (MMG models only)")
        model = _V.model_from_result(model.to_dict())
    elif isinstance(model, (str, os.PathLike)):
        model = _V.load_model(model)
    elif not isinstance(model, _mmg_model.MmgModel):
        raise InputError("validate: model must be a Result, an MmgModel or a model path")
    tr = _as_trial(trial, trim_empty_rows=True, interpolate_gaps=1.0, method="shipid.validate")
    return _V.validate(model, tr, horizon=horizon, **kwargs)


def simulate(vessel: str, manoeuvre: str, *, duration: float | None = None, dt: float = 0.1, seed: int = 0,
             speed: float | None = None, noise: bool = False) -> Trial:
    """Run a packaged vessel through a standard manoeuvre (``shipid simulate VESSEL MANOEUVRE``).

    ``manoeuvre`` as the CLI takes it: ``straight``, ``turning-35[-port]``, ``zigzag-20``,
    ``zigzag-10-5``, ``prbs-10[-T]``, ``dp-surge``, ``dp-sway-yaw``, ``dp-azimuth``. With ``noise`` the
    default measurement model is applied with the random stream ``(seed, 1)``, as the CLI does.
    """
    trial = run_manoeuvre(get_ship_model(vessel), manoeuvre, duration=duration, dt=dt, seed=seed, speed=speed)
    if noise:
        trial = default_measurement_model().apply(trial, np.random.default_rng([seed, 1]), missing_ok=True)
    return trial


__all__ = ["identify", "validate", "simulate", "METHODS", "MethodInfo"]
