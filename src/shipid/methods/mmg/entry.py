"""``shipid.methods.mmg.identify``: the whole of ``identify mmg``, from files to MODEL.json.

The command line (``shipid identify mmg``) parses its options and calls this function; whatever decides
the model — how the runs are read, their rudder sign, the prior, the convention checks, the structure
selection, the refinement — happens here, so that ``shipid.identify("mmg", files)`` and the command give
the same estimates, covariance and warnings.
"""

from __future__ import annotations

import math
from dataclasses import replace

from shipid.errors import InputError
from shipid.methods._trials import as_list
from shipid.warning_lines import collect
from shipid.methods.mmg import pipeline as P
from shipid.methods.mmg import profile as PF
from shipid.methods.mmg import rudder_angle as RA
from shipid.methods.mmg import simex as SX
from shipid.methods.mmg import turning_auto as TN
from shipid.methods.mmg import turning_selection as TS
from shipid.methods.mmg.estimator import FitConfig
from shipid.methods.mmg.validate_run import validate, validate_with_run
from shipid.result import Result

#: ``selection=`` values (the criterion and candidate list of the structure selection).
#: The channels a training run must hold (those of :func:`shipid.methods.mmg.estimator.smooth_run`).
SMOOTH_CHANNELS = ("x", "y", "psi", "u", "v", "r", "delta", "n")
SELECTIONS = ("auto", "horizons", "manoeuvres", "turning", "turning-auto", "rudder-angle")
#: ``simex=`` values.
SIMEX = ("auto", "on", "off")


def default_selection(pm) -> str:
    """What ``selection="auto"`` means for a prior: ``"manoeuvres"`` for the Yasukawa-2015 structure
    (:func:`shipid.methods.mmg.rudder_angle.select_manoeuvres`), else ``"horizons"``."""
    return "manoeuvres" if pm.structure == "yasukawa2015" else "horizons"


def _selection_kw(selection: str, pm, st: str | None, equation_given: bool = False) -> tuple[str | None, dict]:
    """The structure and :func:`~shipid.methods.mmg.pipeline.identify` keywords of a ``selection``."""
    if selection == "horizons":
        return st, {}
    if selection == "manoeuvres":
        if pm.structure != "yasukawa2015":
            raise InputError(f"selection manoeuvres: for the structure 'yasukawa2015' only (not '{pm.structure}')")
        cands = RA.manoeuvre_candidates(equation_given)
        if st is not None:          # a named structure: no selection, but it may be one of these rows
            if st not in cands:
                raise InputError(f"unknown structure '{st}' (choose from {', '.join(cands)})")
            return st, {"candidates": cands, "resolve": RA.resolve}
        return st, {"candidates": cands, "selector": RA.select_manoeuvres, "resolve": RA.resolve}
    if selection == "rudder-angle":
        if pm.structure != "yasukawa2015":
            raise InputError(f"selection rudder-angle: for the structure 'yasukawa2015' only (not '{pm.structure}')")
        name = f"{RA.BASE}/{RA.CHOSEN}"
        if st is not None and st != name:
            raise InputError(f"selection rudder-angle fixes the candidate '{name}': leave the structure out")
        return name, {"candidates": {name: RA.candidates()[RA.CHOSEN]}, "resolve": RA.resolve}
    selectors = {"turning": TS.select_for_turning, "turning-auto": TN.select_auto}
    if pm.structure not in TS.TURNING_CANDIDATES:
        raise InputError(f"selection {selection}: no turning candidates for the structure '{pm.structure}' "
                         f"(only {', '.join(TS.TURNING_CANDIDATES)})")
    return st, {"candidates": TS.TURNING_CANDIDATES[pm.structure], "selector": selectors[selection],
                "resolve": TS.resolve}


def identify(trials, *, vessel: str | None = None, options: FitConfig | None = None, prior=None,
             fmt: str | None = None, channels=None, rudder_sign: int | None = None, structure: str | None = None,
             folds: int | None = None, selection: str = "auto", refine: str = "auto", simex: str = "auto",
             equation: str = "auto", water_depth: float | None = None, retime="auto",
             command: str = "shipid.identify", **kw) -> Result:
    """An MMG model from free-running model tests (EBM applied to the MMG structure).

    Parameters
    ----------
    trials : sequence
        Measured runs (objects or paths); files are read by :func:`shipid.methods.mmg.profile.read_run`
        (empty rows trimmed, gaps of up to 1 s interpolated; each repair is one warning).
    vessel, prior : str or MmgModel, optional
        The prior: a published set (``"esso_osaka_3m"``, ``"kvlcc2_hsva"``, ``"published:<name>"``), an
        identified model JSON or an :class:`~shipid.models.mmg.MmgModel`; ``vessel`` is accepted as the
        same argument. Default: the set of the runs' data profile
        (:data:`~shipid.methods.mmg.profile.PROFILE_DEFAULTS`), else the Esso Osaka 3 m set with a warning.
    options : FitConfig, optional
        Step-2 settings; ``equation`` other than ``"auto"`` replaces its regression form.
    fmt, channels : optional
        Trial format and column map of the files (default: from each file).
    rudder_sign : {1, -1}, optional
        Sign of the files' rudder relative to MMG's (default: from the data profile, -1 for HSVA KVLCC2).
        Each run's yaw response to its first rudder step is checked against it (one warning per run
        that contradicts it).
    structure : str, optional
        A candidate name, or None / ``"auto"`` to choose by cross-validation over the runs: for the Esso
        low-speed prior with enough restarted horizons the staged selection of
        :func:`shipid.methods.mmg.staged.select_staged` (port/starboard and surge variants, regression or
        output error), else the regression CV (:func:`shipid.methods.mmg.pipeline.select_structure`); the
        criterion, the tables and why are in ``diagnostics["structure_selection"]``.
    folds : int, optional
        CV folds (default: leave one run out; the output-error stages of the staged selection: 4).
    selection : {"auto", "horizons", "manoeuvres", "turning", "turning-auto", "rudder-angle"}
        Criterion and candidate list of the structure selection (``shipid identify mmg --help``).
        ``"auto"``: :func:`default_selection` (``"manoeuvres"``, the forward CV by rudder angle of
        :func:`shipid.methods.mmg.rudder_angle.select_manoeuvres`, for the Yasukawa-2015 structure;
        ``"horizons"`` for any other).
    refine : {"auto", "none", "output-error"}
        See :func:`shipid.methods.mmg.pipeline.identify`.
    simex : {"auto", "on", "off"}
        SIMEX correction (:mod:`shipid.methods.mmg.simex`): only where its pilot finds it material, always,
        never.
    equation : {"auto", "integral", "differential"}
        Step-2 regression form (:class:`~shipid.methods.mmg.estimator.FitConfig`).
    water_depth : float, optional
        Water depth of the runs, m, over what a data profile records.
    retime : {"auto", True, False}
        Re-time the state channels and the inputs onto the position clock by offsets estimated on these
        runs (:func:`shipid.methods.mmg.profile.estimate_retime`), before anything else; recorded in
        ``model["retime"]`` and applied by ``validate`` to the runs it reads; one data-repair line.
        ``"auto"``: for runs of the profiles in :data:`~shipid.methods.mmg.profile.RETIME_PROFILES` (Esso).
    command : str
        Recorded in the provenance.
    **kw
        Further keywords of :func:`shipid.methods.mmg.pipeline.identify`.

    Returns
    -------
    Result
        MODEL.json: estimates, covariance, the structure selection table, and in ``model`` the prior,
        the conventions and the reading settings ``validate`` applies to runs of the same profile.
    """
    paths = as_list(trials)
    if not paths:
        raise InputError("no training runs given")
    if water_depth is not None and not (math.isfinite(water_depth) and water_depth > 0):
        raise InputError(f"water depth must be positive, got {water_depth:g}")
    if selection not in SELECTIONS:
        raise InputError(f"unknown selection '{selection}' ({', '.join(SELECTIONS)})")
    if simex not in SIMEX:
        raise InputError(f"unknown simex '{simex}' ({', '.join(SIMEX)})")
    raw = [PF.as_run(p, fmt, channels, method="identify mmg", required=SMOOTH_CHANNELS) for p in paths]
    if water_depth is not None:   # the runs' depth as given, over what a data profile records
        raw = [PF.with_meta(tr, water_depth=float(water_depth), water_depth_source="given") for tr in raw]
    profiles = {tr.meta.get("profile") for tr in raw}
    notes: list[str] = []
    rudder_sign, sign_from = PF.rudder_sign_of(raw, rudder_sign)
    data, steps = [], []
    for tr in raw:
        tr = PF.flip(tr, rudder_sign)
        st, w = PF.convention_warning(tr, rudder_sign, "MMG's convention (rudder positive turns to starboard)")
        steps.append({"file": tr.meta.get("source", ""), **st})
        if w:
            notes.append(w)
        data.append(tr)
    rt = None
    if PF.wants_retime(retime, profiles):
        rt = PF.estimate_retime(data)
        data = [PF.apply_retime(tr, rt) for tr in data]
        notes.append(PF.retime_line(rt, f"the {len(data)} training runs"))
    pm, prior_info = PF.choose_prior(prior if prior is not None else vessel, profiles, notes)
    st = None if structure in (None, "auto") else structure
    if selection == "auto":
        selection = default_selection(pm)
    st, sel_kw = _selection_kw(selection, pm, st, equation != "auto")
    cfg = options or FitConfig()
    if equation != "auto":
        cfg = replace(cfg, equation=equation)
    sx = {"auto": SX.SimexConfig(), "on": SX.SimexConfig(pilot=False), "off": None}[simex]
    kw = {**sel_kw, **kw}
    res = P.identify(data, pm, structure=st, select=st is None, folds=folds, refine=refine, simex=sx,
                     fit_config=cfg, extra_provenance={"command": command, "rudder_sign": rudder_sign,
                                                       "selection": selection}, **kw)
    res.model["prior"] = prior_info
    res.model["conventions"] = {
        "rudder_sign": rudder_sign, "rudder_sign_from": sign_from,
        "rudder": "delta = rudder_sign x the file's rudder; positive turns the ship to starboard (MMG)",
        "yaw_rate": "positive to starboard", "heading": "clockwise from x0", "first_rudder_step": steps}
    res.model["validate"] = {"rudder_sign": rudder_sign, "format": fmt, "channels": channels,
                             "profiles": sorted(p for p in profiles if p), "horizon_s": 60.0,
                             "read": PF.READ_SETTINGS, "retime": rt is not None}
    res.model["retime"] = rt
    collect(res, trials=data, extra=notes)
    return res


__all__ = ["identify", "validate", "validate_with_run", "default_selection", "SELECTIONS", "SIMEX"]
