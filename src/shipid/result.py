"""The result every method returns: estimates with uncertainty, diagnostics, provenance.

A :class:`Result` is self-describing so that ``shipid report`` and ``shipid
validate`` can work from its JSON alone: it names the method and model
structure, lists each estimate with its standard error and unit, carries the
covariance of the free parameters, the diagnostics of the estimator (iterations,
convergence, residual checks) and the provenance (inputs, seed, version, time).
"""

from __future__ import annotations

import datetime as _dt
import json
from dataclasses import asdict, dataclass, field
from typing import Any, Mapping

import numpy as np

import shipid
from shipid.outputs import atomic_write_text


@dataclass(frozen=True)
class Estimate:
    """One estimated quantity.

    Attributes
    ----------
    value : float
    std : float
        Standard error (NaN when not available; ``inf`` when not identifiable).
    unit : str
        SI unit, or ``"-"``.
    status : str
        ``"estimated"``, ``"fixed"`` (known input) or ``"derived"``.
    note : str
        Anything a user must know (``"not identifiable: set by z_f"``).
    """

    value: float
    std: float = float("nan")
    unit: str = "-"
    status: str = "estimated"
    note: str = ""

    def ci95(self) -> tuple[float, float]:
        """Normal-approximation 95 % confidence interval."""
        return (self.value - 1.959963984540054 * self.std, self.value + 1.959963984540054 * self.std)


@dataclass
class Result:
    """Output of an identification method.

    Attributes
    ----------
    method : str
        ``"mass-cm"``, ``"dp"``, ``"ebm"`` ...
    model : dict
        Model structure and vessel particulars needed to use the estimates.
    estimates : dict of str to Estimate
    covariance : ndarray or None
        Covariance of the estimates named in ``covariance_names``.
    covariance_names : list of str
    diagnostics : dict
        ``converged``, ``iterations``, residual statistics, warnings ...
    series : dict
        Time histories for plots (parameter histories, smoothed states ...), JSON-able.
    provenance : dict
        Inputs, seed, shipid version, creation time.
    """

    method: str
    estimates: dict[str, Estimate]
    model: dict[str, Any] = field(default_factory=dict)
    covariance: np.ndarray | None = None
    covariance_names: list[str] = field(default_factory=list)
    diagnostics: dict[str, Any] = field(default_factory=dict)
    series: dict[str, Any] = field(default_factory=dict)
    provenance: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.provenance.setdefault("shipid_version", shipid.__version__)
        self.provenance.setdefault("created", _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"))

    def value(self, name: str) -> float:
        return self.estimates[name].value

    def std(self, name: str) -> float:
        return self.estimates[name].std

    def to_dict(self) -> dict[str, Any]:
        return {
            "method": self.method,
            "model": _jsonable(self.model),
            "estimates": {k: asdict(v) for k, v in self.estimates.items()},
            "covariance": None if self.covariance is None else _jsonable(self.covariance),
            "covariance_names": list(self.covariance_names),
            "diagnostics": _jsonable(self.diagnostics),
            "series": _jsonable(self.series),
            "provenance": _jsonable(self.provenance),
        }

    def to_json(self, indent: int | None = 2) -> str:
        return json.dumps(self.to_dict(), indent=indent, allow_nan=True)

    def write_json(self, path, *, force: bool = False):
        return atomic_write_text(path, self.to_json(), force=force)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "Result":
        cov = d.get("covariance")
        return cls(
            method=d["method"],
            estimates={k: Estimate(**v) for k, v in d.get("estimates", {}).items()},
            model=dict(d.get("model", {})),
            covariance=None if cov is None else np.asarray(cov, dtype=float),
            covariance_names=list(d.get("covariance_names", [])),
            diagnostics=dict(d.get("diagnostics", {})),
            series=dict(d.get("series", {})),
            provenance=dict(d.get("provenance", {})),
        )

    @classmethod
    def from_json(cls, text: str) -> "Result":
        return cls.from_dict(json.loads(text))


def _jsonable(x: Any) -> Any:
    """Convert numpy containers and scalars to plain JSON types (NaN kept as NaN)."""
    if isinstance(x, Mapping):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, (np.floating,)):
        return float(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.bool_,)):
        return bool(x)
    return x
