"""Report material of ``mass-cm`` results (Linder et al. 2015, seed 000).

Default section: draws, when the result carries them, the cost over (m, z̄_m) (``contours["cost"]``,
paper Fig. 4) and the spread of the estimates over repeated runs (``tables["spread"]`` and ``xy["spread"]``,
paper Table 3).

:func:`enrich` makes the report series on request for a result that has none (one from
:func:`shipid.identify` or :func:`~shipid.methods.masscm.estimator.estimate_mass_cm`, which do no report work):
it reads the datasets again from the files the result records (``provenance["mass_cm_call"]``), runs
Algorithm 1 with the recorded known parameters, options and initialisation, checks that it reproduces the
stored estimate of m, and adds what :func:`shipid.methods.masscm.series.with_series` makes (roll-rate overlays,
prefiltered equation errors, the Fig. 4 cost map, the trial summaries).
"""

from __future__ import annotations

import copy
import os
import warnings
from typing import Mapping

from shipid.data.io import read_trial
from shipid.methods.masscm.estimator import REQUIRED, MassCMOptions, fit_mass_cm
from shipid.methods.masscm.series import with_series
from shipid.models.roll_reduced import KnownParams
from shipid.report.registry import Entry, register_section
from shipid.report.sections._util import entries


def masscm_section(result) -> list:
    """Linder et al. (2015): cost map and spread of the estimates"""
    frags: list = []
    for name, _ in entries(result, "contours", names=("cost",), prefixes=("cost_",)):
        frags.append(Entry("contours", name, paper="Fig. 4",
                           title="Identification cost over mass m and vertical centre of mass z̄_m; "
                                 "markers show the estimate and, for simulated data, the true value."))
    for name, _ in entries(result, "tables", names=("spread",), prefixes=("spread_",)):
        frags.append(Entry("tables", name, paper="Table 3",
                           title="Spread of the estimates over repeated runs."))
    for name, _ in entries(result, "xy", names=("spread",), prefixes=("spread_",)):
        frags.append(Entry("xy", name, paper="Table 3",
                           title="Estimates of the repeated runs (spread)."))
    return frags


register_section("mass-cm", masscm_section, default=True)


def _note(result, text: str):
    out = copy.copy(result)
    out.diagnostics = dict(result.diagnostics or {})
    out.diagnostics["warnings"] = [*out.diagnostics.get("warnings", []), f"report series not made: {text}"]
    return out


def enrich(result):
    """A copy of ``result`` with the report series of :func:`~shipid.methods.masscm.series.with_series`.

    Returns ``result`` itself when it is not a ``mass-cm`` estimate, already has overlays, or records no
    files (the Table-3 study result, a result of in-memory trials); a copy with one warning saying why when
    the files cannot be read or Algorithm 1 on them does not reproduce the stored m.
    """
    series = result.series if isinstance(result.series, Mapping) else {}
    call = (result.provenance or {}).get("mass_cm_call") if isinstance(result.provenance, Mapping) else None
    if result.method != "mass-cm" or series.get("overlays") or not isinstance(call, Mapping):
        return result
    files = call.get("files") or []
    if not files or any(not isinstance(p, str) for _, p in files):
        return result
    missing = [p for _, p in files if not os.path.isfile(p)]
    if missing:
        return _note(result, f"dataset file not found: {missing[0]}")
    try:
        datasets = [(c, read_trial(p, required=["t", *REQUIRED], method="mass-cm")) for c, p in files]
        known = KnownParams(**(result.model or {})["known"])
        options = MassCMOptions(**(result.diagnostics or {})["options"])
        prior = call.get("z_f_prior")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fit = fit_mass_cm(datasets, known, theta0=call.get("theta0"), z_f=call.get("z_f"),
                              z_f_prior=None if prior is None else tuple(prior), init=call.get("init"),
                              options=options, noise_check=False)
    except Exception as err:  # noqa: BLE001 - the report must still be written
        return _note(result, f"{type(err).__name__}: {' '.join(str(err).split())[:160]}")
    if fit.result.value("m") != result.value("m"):
        return _note(result, f"Algorithm 1 on the recorded files gives m = {fit.result.value('m'):.6g} kg, "
                             f"not the stored {result.value('m'):.6g} kg (files changed?)")
    made = with_series(fit, cost_map=True)
    out = copy.copy(result)
    out.series = {**dict(series), **{k: v for k, v in made.series.items() if k in ("overlays", "residuals",
                                                                                    "contours")}}
    out.provenance = {**dict(result.provenance), "inputs": made.provenance.get("inputs", [])}
    return out


__all__ = ["masscm_section", "enrich"]
