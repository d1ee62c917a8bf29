"""``shipid.methods.masscm.identify``: the common entry shape around :func:`estimate_mass_cm`."""

from __future__ import annotations

import os
from typing import Any, Mapping

from shipid.errors import InputError
from shipid.methods._trials import as_trial, grouped
from shipid.methods.masscm.known import read_known
from shipid.methods.masscm.estimator import REQUIRED, MassCMOptions, estimate_mass_cm
from shipid.models.roll_reduced import KnownParams
from shipid.result import Result


def identify(trials, *, vessel: str | None = None, options: MassCMOptions | None = None, known=None,
             **kw) -> Result:
    """Mass and centre of mass of a load (Linder et al. 2015, Algorithm 1).

    Parameters
    ----------
    trials : mapping
        ``{"nominal": ..., "calibration": ..., "loaded": ...}``, a trial (object or path) or a list each.
    vessel : str, optional
        Not used: the ship's known particulars come in ``known``.
    options : MassCMOptions, optional
    known : KnownParams, dict or path
        Required: the known mass, geometry and inertia (a ``known.toml`` as the CLI reads it).
    **kw
        ``z_f=``, ``z_f_prior=``, ``theta0=``, ``init=`` of :func:`estimate_mass_cm`.
    """
    groups = grouped(trials, ("nominal", "calibration", "loaded"), "mass-cm")
    extra: dict[str, Any] = {}
    if known is None:
        raise InputError("mass-cm: known= is required (KnownParams, a dict of its fields, or a known.toml path)")
    if isinstance(known, (str, os.PathLike)):
        kn = read_known(str(known))
        known = kn["known"]
        extra = {k: kn[k] for k in ("z_f", "z_f_prior", "theta0") if kn[k] is not None}
    elif isinstance(known, Mapping):
        known = KnownParams(**known)
    datasets = [(cond, as_trial(t, required=["t", *REQUIRED], method="mass-cm"))
                for cond, ts in groups.items() for t in ts]
    extra.update(kw)
    extra.setdefault("init", "given" if extra.get("theta0") is not None else "linear")
    return estimate_mass_cm(datasets, known, options=options or MassCMOptions(), **extra)
