"""The Python face of shipid: one call per task, the same names as the CLI.

``shipid.identify(method, trials, *, vessel=..., options=...)`` runs any method and returns its
:class:`~shipid.result.Result`; ``shipid.validate`` predicts a held-out run open loop with an
identified model; ``shipid.simulate`` runs a packaged vessel through a standard manoeuvre. The
methods are named as ``shipid identify --help`` lists them; :data:`METHODS` maps each name to its
paper, its options class and the trials it takes.

Trials may be :class:`~shipid.io.trial.Trial` objects or file paths (read with
:func:`shipid.io.files.read_trial` and the channels the method needs).

Examples
--------
>>> import shipid
>>> tr = shipid.simulate("esso-osaka", "zigzag-20", duration=30.0)      # doctest: +SKIP
>>> res = shipid.identify("ebm", [tr], vessel="esso-osaka")            # doctest: +SKIP
>>> res.estimates["Y_v"].value, res.estimates["Y_v"].std               # doctest: +SKIP
"""

from __future__ import annotations

import os
import warnings
from typing import TYPE_CHECKING

from shipid import registry
from shipid.errors import InputError
from shipid.numerics.linalg import single_threaded
from shipid.warning_lines import collect, recorded
from shipid.registry import MethodInfo
from shipid.result import Result

if TYPE_CHECKING:
    from shipid.methods._trials import Trialish

# The methods, the MMG model and the simulator are imported where used, so that ``shipid.identify``
# loads the one method it runs; ``METHODS`` and ``simulate`` are read on first use (module __getattr__).


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
        (:func:`shipid.numerics.linalg.one_blas_thread`), so the numbers do not depend on the core count.
    """
    info = registry.get(method)
    if info.identify is None:
        raise InputError(f"{info.name} is not run by identify; see `shipid {info.name} --help`")
    from shipid.methods._trials import reading_log

    py: list[str] = []
    with reading_log() as read, recorded(py):
        res = info.identify(trials, vessel=vessel, options=options, **kwargs)
    collect(res, trials=read, python=py)
    for line in py:          # shown as well as recorded (the command line prints the result's list instead)
        warnings.warn(line, RuntimeWarning, stacklevel=3)
    return res


@single_threaded
def validate(model, trial: Trialish, *, horizon: float | None = None, **kwargs):
    """Open-loop prediction of a held-out run by an identified model (``shipid validate``).

    Parameters
    ----------
    model : Result, MmgModel or str
        A result of ``identify(...)`` of any method that has a ``validate`` module (``mmg``, ``ebm``,
        ``dp``, ``mass-cm``), a result JSON path, ``"published:<name>"`` (a published MMG set) or an
        :class:`~shipid.models.mmg.MmgModel`.
    trial : Trial or path
        The measured run (not used for training), with the channels the method needs.
    horizon : float, optional
        Length of the restarted horizons, s (default: the method's ``DEFAULT_HORIZON``; 60 s, and
        10 s for mass-cm's 60-s records).
    **kwargs
        Passed to the method's ``validate_result`` (``stride=``, ``windows=``; mass-cm ``condition=``); an MMG
        model takes ``fmt=``, ``channels=``, ``rudder_sign=`` and ``retime=`` too
        (:func:`shipid.methods.mmg.validate_run.validate`: the run is read as its file says, in the model's
        conventions, and re-timed by the model's offsets).

    Returns
    -------
    shipid.analysis.openloop.Validation
        RMS and maximum errors over 30 s, 60 s, the whole run and restarted horizons, in the
        quantities the method predicts (``Validation.quantities``).

    The method is found from ``Result.method`` through :func:`shipid.registry.for_result`; one
    without a ``validate`` module raises :class:`~shipid.errors.InputError`.
    """
    from shipid.methods._trials import as_trial
    from shipid.methods.mmg import validate_run as _mmg
    from shipid.models import mmg as _mmg_model

    given = model
    if isinstance(model, os.PathLike) or (isinstance(model, str) and not model.startswith("published:")):
        path = os.fspath(model)
        if not os.path.isfile(path):
            raise InputError("no such model file", file=path)
        try:
            with open(path, encoding="utf-8") as fh:
                model = Result.from_json(fh.read())
        except (UnicodeDecodeError, ValueError, KeyError, TypeError) as err:
            raise InputError(f"not a result JSON file ({type(err).__name__}: {err})", file=path) from None
    if (isinstance(model, (str, _mmg_model.MmgModel))
            or (isinstance(model, Result) and (model.model or {}).get("family") == "mmg")):
        spec = os.fspath(given) if isinstance(given, (str, os.PathLike)) else model
        return _mmg.validate(spec, trial, horizon=horizon, **kwargs)
    if not isinstance(model, Result):
        raise InputError("validate: model must be a Result, an MmgModel or a model path")
    info = registry.for_result(model.method)
    if info is None or not info.has_module("validate"):
        raise InputError(f"validate: a {model.method!r} result cannot be validated (methods with an open-loop "
                         f"model: {', '.join(k for k, v in registry.methods().items() if v.has_module('validate'))})")
    mod = info.submodule("validate")
    tr = as_trial(trial, trim_empty_rows=True, interpolate_gaps=1.0, method="shipid.validate",
                  required=list(getattr(mod, "REQUIRED", ())) or None)
    return mod.validate_result(model, tr, horizon=horizon, **kwargs)


def __getattr__(name: str):
    """``METHODS``: method name -> :class:`~shipid.registry.MethodInfo` (paper, options class, trials
    taken); ``simulate``: a packaged vessel through a standard manoeuvre (``shipid simulate VESSEL
    MANOEUVRE``, :func:`shipid.simulate.run.simulate_vessel`)."""
    if name == "METHODS":
        value = registry.identifying()
    elif name == "simulate":
        from shipid.simulate.run import simulate_vessel as value
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


__all__ = ["identify", "validate", "simulate", "METHODS", "MethodInfo"]
