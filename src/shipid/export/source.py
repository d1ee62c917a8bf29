"""The model an export starts from: a packaged vessel, a published set, or an identified result.

:func:`load_source` reads what a user names on the command line or passes in Python and returns a
:class:`Source`: the model object of its family (a :class:`shipid.models.dp.DPVessel`, a
:class:`shipid.models.mmg.MmgModel` or a :class:`shipid.models.abkowitz.AbkowitzParams`), the names,
values, units and covariance of its coefficients, and where they come from. The model objects are
built by the loaders the methods themselves use (``validate.vessel_from_result``,
``validate.params_from_result``, ``validate.model_from_result``), so an exported model is the model
``shipid validate`` simulates.

Accepted specifications:

* a :class:`shipid.result.Result`, its ``to_dict()``, or a MODEL.json path written by ``shipid identify
  dp | ebm | mmg``;
* ``published:NAME``: a published MMG set (``esso_osaka_3m``, ``kvlcc2_L7``, ``kvlcc2_hsva``);
* a packaged vessel name: ``supply`` (the DP model with the identified θ of eqs. 48–49 of Fossen,
  Sagatun & Sørensen 1996) or ``esso-osaka`` (the modified Abkowitz model with the coefficients of
  Yoon & Rhee 2003, Table 3);
* (through :func:`shipid.export.loading.load`) a parameter file written by
  :func:`shipid.export.params.write_params` (``.toml``, ``.yaml``).

Covariance: the result's ``covariance`` over ``covariance_names`` where it has one; else the
squared standard errors of the estimates on a diagonal (EBM records no correlation between
coefficients; :attr:`Source.cov_note` says so); packaged and published sets have none.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from shipid.errors import InputError
from shipid.methods.dp import validate as dp_validate
from shipid.methods.ebm import validate as ebm_validate
from shipid.methods.mmg import imo as mmg_imo
from shipid.methods.mmg import validate as mmg_validate
from shipid.models import abkowitz as ab
from shipid.models import dp
from shipid.models import mmg
from shipid.result import Result
from shipid.vessels import load_vessel

#: Model families an export knows.
FAMILIES = ("dp", "mmg", "abkowitz")


@dataclass(frozen=True)
class Source:
    """A model to export, with its coefficients and their uncertainty.

    Attributes
    ----------
    family : {"dp", "mmg", "abkowitz"}
    model : DPVessel or MmgModel or AbkowitzParams
    name : str
    coef : dict of str to float
        The coefficients that carry the model's uncertainty (θ1..θ9, the MMG coefficients of
        :data:`shipid.models.mmg.COEFS`, the 26 of eq. 13 of Yoon & Rhee 2003).
    std : dict of str to float
        Their standard errors (NaN where none is known).
    status : dict of str to str
        ``estimated``, ``not determined``, ``fixed``, ``published`` ...
    cov_names : tuple of str
        The coefficients :attr:`cov` is over (empty: no covariance).
    cov : ndarray or None
    cov_note : str
        Where the covariance came from.
    units : dict of str to str
    sources : dict of str to str
        Where the numbers come from.
    conditions : dict
        Recorded test conditions (MMG ``training_conditions``; approach speed and propeller rate).
    origin : str
        What was loaded (a file, ``published:NAME``, a vessel name).
    method : str
        The identification method of a result (empty for packaged and published sets).
    coef_sources : dict of str to str
        Where each coefficient comes from (a table or equation, or the identification).
    """

    family: str
    model: Any
    name: str
    coef: dict = field(default_factory=dict)
    std: dict = field(default_factory=dict)
    status: dict = field(default_factory=dict)
    cov_names: tuple = ()
    cov: np.ndarray | None = None
    cov_note: str = "no covariance"
    units: dict = field(default_factory=dict)
    sources: dict = field(default_factory=dict)
    conditions: dict = field(default_factory=dict)
    origin: str = ""
    method: str = ""
    coef_sources: dict = field(default_factory=dict)

    @property
    def length(self) -> float:
        """Ship length L (m)."""
        if self.family == "dp":
            return float(self.model.bis.L)
        if self.family == "mmg":
            return float(self.model.particulars["L"])
        return float(self.model.L)

    def with_coefficients(self, values: Mapping[str, float]) -> "Source":
        """This source with some coefficients replaced (for the delta method and Monte Carlo draws)."""
        coef = dict(self.coef)
        coef.update({k: float(v) for k, v in values.items()})
        return replace(self, coef=coef, model=model_with(self.family, self.model, coef))


def model_with(family: str, model: Any, coef: Mapping[str, float]) -> Any:
    """``model`` of ``family`` with the coefficients ``coef`` (all of the family's names)."""
    if family == "dp":
        return model.with_theta(np.array([coef[k] for k in dp.THETA_NAMES]))
    if family == "mmg":
        return model.with_coef({k: coef[k] for k in coef if k in model.coef})
    return model.with_theta([coef[k] for k in ab.THETA_X_NAMES], [coef[k] for k in ab.THETA_Y_NAMES],
                            [coef[k] for k in ab.THETA_N_NAMES])


def coefficient_names(family: str, model: Any) -> tuple[str, ...]:
    """The names of the family's coefficients, in the model's order."""
    if family == "dp":
        return dp.THETA_NAMES
    if family == "mmg":
        return tuple(c for m in mmg.MODES for c in mmg.COEFS[model.structure][m])
    return ab.THETA_X_NAMES + ab.THETA_Y_NAMES + ab.THETA_N_NAMES


def coefficient_values(family: str, model: Any) -> dict[str, float]:
    """The model's coefficients by name."""
    names = coefficient_names(family, model)
    if family == "dp":
        vals = model.theta
    elif family == "mmg":
        vals = [model.coef[c] for c in names]
    else:
        vals = list(model.theta_X) + list(model.theta_Y) + list(model.theta_N)
    return {k: float(v) for k, v in zip(names, vals)}


def coefficient_unit(family: str, name: str) -> str:
    """SI unit of a coefficient (``-`` for the non-dimensional ones)."""
    if family == "dp":
        return "- (bis)"
    if family == "mmg":
        return mmg.COEF_UNITS.get(name, "-")
    return "-"


def steering_limits(vessel: str) -> dict[str, float]:
    """Rudder limit (rad) and rate limit (rad/s) of a packaged vessel's ``[steering]`` (empty if none)."""
    v = load_vessel(vessel)
    if "steering" not in v.sections:
        return {}
    S = v.values("steering")
    return {"rudder_limit": float(np.deg2rad(S["rudder_limit"])),
            "rudder_rate_limit": float(np.deg2rad(S["rudder_rate_limit"]))}


def _covariance(result: Result, names: tuple[str, ...]) -> tuple[tuple, np.ndarray | None, str]:
    """(names, covariance, note) of the estimates of ``result`` among ``names``."""
    if result.covariance is not None and result.covariance_names:
        keep = [n for n in result.covariance_names if n in names]
        if keep:
            C = np.asarray(result.covariance, float)
            idx = [list(result.covariance_names).index(n) for n in keep]
            return tuple(keep), C[np.ix_(idx, idx)], "the result's covariance"
    keep = [n for n in names if n in result.estimates and np.isfinite(result.estimates[n].std)
            and result.estimates[n].status != "fixed"]
    if not keep:
        return (), None, "no covariance: the result records no standard errors"
    d = np.array([result.estimates[n].std for n in keep]) ** 2
    return tuple(keep), np.diag(d), ("the squared standard errors on a diagonal: the result records no "
                                     "correlation between coefficients")


def from_result(result: Result | Mapping[str, Any], origin: str = "result", *, form_term: bool = True) -> Source:
    """A :class:`Source` from an identified result (``Result`` or its dict).

    ``form_term``: for an MMG model identified with step 2's differential form, the covariance is
    ``Σ + δδᵀ`` with ``δ`` the difference from the integral form (one standard deviation of model-form
    error, :func:`shipid.methods.mmg.imo.form_delta`), as ``shipid imo`` draws its bands.
    """
    doc = result.to_dict() if isinstance(result, Result) else dict(result)
    res = result if isinstance(result, Result) else Result.from_dict(doc)
    fam_of_model = (doc.get("model") or {}).get("family")
    if fam_of_model == "mmg":
        family, model = "mmg", mmg_validate.model_from_result(doc)
        conditions = dict((doc.get("model") or {}).get("training_conditions") or {})
    elif res.method == "dp":
        family, model, conditions = "dp", dp_validate.vessel_from_result(res), {}
    elif res.method == "ebm":
        family, model = "abkowitz", ebm_validate.params_from_result(res)
        conditions = {"speed": float(model.U0), "rps": float(model.n0), **steering_limits(res.model["vessel"])}
    else:
        raise InputError(f"method {res.method!r} has no exportable model (dp, ebm and mmg results do)",
                         file=origin)
    names = coefficient_names(family, model)
    coef = coefficient_values(family, model)
    std = {k: float(res.estimates[k].std) if k in res.estimates else float("nan") for k in names}
    status = {k: res.estimates[k].status if k in res.estimates else "fixed" for k in names}
    units = {k: res.estimates[k].unit if k in res.estimates else coefficient_unit(family, k) for k in names}
    cn, cov, note = _covariance(res, names)
    if family == "mmg" and form_term and cov is not None:
        d = mmg_imo.form_delta(doc, list(cn))
        if d is not None and np.any(d):
            cov = cov + np.outer(d, d)
            note += (" plus the model-form term dd^T (difference of step 2's differential and integral forms, "
                     "as shipid imo)")
            std.update({k: float(np.sqrt(cov[i, i])) for i, k in enumerate(cn)})
    src = {"identified": f"shipid identify {res.method} ({origin})"}
    src.update({f"model {k}": str(v) for k, v in (getattr(model, "sources", None) or {}).items()})
    per = {k: f"shipid identify {res.method}" if status[k] != "fixed" else "fixed (not identified)" for k in names}
    return Source(family, model, str(getattr(model, "name", None) or res.model.get("vessel", res.method)),
                  coef, std, status, cn, cov, note, units, src, conditions, origin, res.method, per)


def from_model(family: str, model: Any, *, origin: str, sources: Mapping[str, str] | None = None,
               conditions: Mapping[str, Any] | None = None, status: str = "published",
               std: Mapping[str, float] | None = None, coef_sources: Mapping[str, str] | None = None) -> Source:
    """A :class:`Source` of a model object without a covariance (packaged and published sets)."""
    names = coefficient_names(family, model)
    sd = {k: float((std or {}).get(k, float("nan"))) for k in names}
    return Source(family, model, str(getattr(model, "name", origin)), coefficient_values(family, model), sd,
                  {k: status for k in names}, (), None, "no covariance: a published set",
                  {k: coefficient_unit(family, k) for k in names}, dict(sources or {}),
                  dict(conditions or {}), origin, "", dict(coef_sources or {}))


def _packaged(name: str) -> Source:
    if name in ("supply", "supply-vessel", "fss1996"):
        v = load_vessel("supply")
        per = {k: f"{v.section('identified')['A_h' if i < 5 else 'K'].source} ({dp.THETA_MEANING[k]})"
               for i, k in enumerate(dp.THETA_NAMES)}
        return from_model("dp", dp.dp_vessel(v), origin=name,
                          sources={k: str(s) for k, s in v.sources.items()}, coef_sources=per)
    if name in ("esso-osaka", "esso_osaka", "essoosaka", "esso-osaka-278k"):
        v = load_vessel("esso-osaka")
        p = ab.params_from_vessel(v)
        per = {k: e.source for k, e in v.section("abkowitz").items()}
        return from_model("abkowitz", p, origin=name, sources={k: str(s) for k, s in v.sources.items()},
                          coef_sources=per,
                          conditions={"speed": float(p.U0), "rps": float(p.n0), **steering_limits(v.name)})
    raise InputError(f"no exportable model called {name!r}: give a MODEL.json of 'shipid identify dp|ebm|mmg', "
                     "published:NAME (an MMG set), a parameter file, or a packaged vessel (supply, esso-osaka)")


def load_source(spec: Any, *, form_term: bool = True) -> Source:
    """A :class:`Source` from a result, a MODEL.json path, ``published:NAME``, a parameter file or a vessel."""
    if isinstance(spec, Source):
        return spec
    if isinstance(spec, (Result, Mapping)):
        return from_result(spec, form_term=form_term)
    s = str(spec)
    if s.startswith("published:"):
        model = mmg.load_published(s.split(":", 1)[1])
        origin = model.sources.get("coefficients", model.sources.get("all", s))
        return from_model("mmg", model, origin=s, sources=dict(model.sources),
                          coef_sources={k: origin for k in coefficient_names("mmg", model)})
    path = Path(s)
    if path.suffix.lower() == ".json":
        if not path.is_file():
            raise InputError("no such model file", file=s)
        try:
            doc = json.loads(path.read_text(encoding="utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as err:
            raise InputError(f"not a JSON model file ({err})", file=s) from None
        if not isinstance(doc, dict) or "method" not in doc:
            raise InputError("not a MODEL.json of 'shipid identify' (no 'method')", file=s)
        try:
            return from_result(doc, origin=s, form_term=form_term)
        except (KeyError, TypeError, ValueError) as err:
            raise InputError(f"malformed model ({type(err).__name__}: {err})", file=s) from None
    return _packaged(s)


__all__ = ["FAMILIES", "Source", "load_source", "from_result", "from_model", "model_with", "coefficient_names",
           "coefficient_values", "coefficient_unit"]
