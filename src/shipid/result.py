"""The result every method returns: estimates with uncertainty, diagnostics, provenance.

A :class:`Result` is self-describing so that ``shipid report`` and ``shipid
validate`` can work from its JSON alone: it names the method and model
structure, lists each estimate with its standard error and unit, carries the
covariance of the free parameters, the diagnostics of the estimator (iterations,
convergence, residual checks) and the provenance (inputs, seed, version, time).

It shows itself as the statistical packages do: ``res.summary()`` (a table of every estimate with
its unit, standard error, 95 % interval and verdict, the not-determined ones named, the warnings;
at most 100 columns by 40 lines), a short ``repr``/``print``, ``_repr_html_`` in a notebook,
``res.to_frame()`` (pandas, one row per estimate), ``res.conf_int(alpha)``, ``res.params`` and
``res.bse`` / ``res.std()``. The verdict on each estimate comes from :mod:`shipid.summary`, the
same that the HTML report shows.
"""

from __future__ import annotations

import datetime as _dt
import json
from dataclasses import asdict, dataclass, field
from collections.abc import MutableMapping
from typing import Any, Iterator, Mapping

import numpy as np

import shipid
from shipid import registry
from shipid import summary as _summary
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


_TYPED_DIAGNOSTICS = ("converged", "iterations", "warnings")


@dataclass(eq=False)
class Diagnostics(MutableMapping):
    """What the estimator says about its own run: typed fields, and the method's further entries.

    Reads and writes as the mapping the JSON holds (``d["converged"]``, ``d.get("ridge_k")``,
    ``d.setdefault("warnings", []).append(...)``) and as attributes for the fields every method
    reports.

    Attributes
    ----------
    converged : bool or None
        Whether the estimator met its convergence criterion (None: the method has none).
    iterations : int or None
        Iterations (or filter passes) it took.
    warnings : list of str
        One line per non-convergence, implausible or undetermined estimate, or repair of the data;
        the CLI prints each on stderr and ``--strict`` exits 3 when there is any.
    extra : dict
        The method's own diagnostics (residual checks, noise levels, stage records ...), JSON-able.
    """

    converged: bool | None = None
    iterations: int | None = None
    warnings: list = field(default_factory=list)
    extra: dict = field(default_factory=dict)

    @classmethod
    def coerce(cls, d: Mapping[str, Any] | None) -> "Diagnostics":
        """``d`` as :class:`Diagnostics` (itself when it already is one)."""
        if isinstance(d, Diagnostics):
            return d
        out = cls()
        for k, v in dict(d or {}).items():
            out[k] = v
        return out

    def __getitem__(self, key: str) -> Any:
        if key in _TYPED_DIAGNOSTICS:
            v = getattr(self, key)
            if v is None:
                raise KeyError(key)
            return v
        return self.extra[key]

    def __setitem__(self, key: str, value: Any) -> None:
        if key == "warnings":
            self.warnings = list(value) if value is not None else []
        elif key in _TYPED_DIAGNOSTICS:
            setattr(self, key, value)
        else:
            self.extra[key] = value

    def __delitem__(self, key: str) -> None:
        if key == "warnings":
            self.warnings = []
        elif key in _TYPED_DIAGNOSTICS:
            if getattr(self, key) is None:
                raise KeyError(key)
            setattr(self, key, None)
        else:
            del self.extra[key]

    def __iter__(self) -> Iterator[str]:
        for k in _TYPED_DIAGNOSTICS:
            if k == "warnings" or getattr(self, k) is not None:
                yield k
        yield from self.extra

    def __len__(self) -> int:
        return sum(1 for _ in self)

    def setdefault(self, key: str, default: Any = None) -> Any:
        """As :meth:`dict.setdefault`; for ``"warnings"`` the stored list itself is returned."""
        if key == "warnings":
            return self.warnings
        return super().setdefault(key, default)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Mapping) and self.to_dict() == dict(other.items())

    __hash__ = None  # mutable

    def to_dict(self) -> dict[str, Any]:
        """The plain mapping written to JSON."""
        return {k: self[k] for k in self}


@dataclass(frozen=True)
class Covariance:
    """Covariance of the free estimates, with the names of its rows.

    Attributes
    ----------
    names : tuple of str
    matrix : ndarray, shape (n, n)
    """

    names: tuple
    matrix: np.ndarray

    def std(self) -> dict[str, float]:
        """Standard errors by name (square roots of the diagonal)."""
        d = np.sqrt(np.clip(np.diag(self.matrix), 0.0, None))
        return dict(zip(self.names, map(float, d)))

    def correlation(self) -> np.ndarray:
        """The correlation matrix (NaN where a variance is zero)."""
        d = np.sqrt(np.diag(self.matrix))
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.matrix / np.outer(d, d)

    def sub(self, names) -> "Covariance":
        """The block of the named estimates, in the order given."""
        idx = [self.names.index(n) for n in names]
        return Covariance(tuple(names), self.matrix[np.ix_(idx, idx)])


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
    diagnostics : Diagnostics
        ``converged``, ``iterations``, ``warnings`` and the method's own entries (a dict given
        here is converted).
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
    diagnostics: Diagnostics = field(default_factory=Diagnostics)
    series: dict[str, Any] = field(default_factory=dict)
    provenance: dict[str, Any] = field(default_factory=dict)

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "diagnostics":
            value = Diagnostics.coerce(value)
        object.__setattr__(self, name, value)

    def __post_init__(self) -> None:
        self.provenance.setdefault("shipid_version", shipid.__version__)
        self.provenance.setdefault("created", _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"))

    def value(self, name: str) -> float:
        """The estimate called ``name``."""
        return self.estimates[name].value

    def std(self, name: str | None = None):
        """The standard error of ``name``; without a name, every one as a pandas Series (as :attr:`bse`)."""
        if name is None:
            return self.bse
        return self.estimates[name].std

    # -- the faces of statistical packages (verdicts from :mod:`shipid.summary`) ----------------------

    def summary(self) -> str:
        """The table of every estimate (unit, SE, 95 % interval, verdict), the verdict and the warnings.

        At most 100 columns and 40 lines for any method: long lists are folded with a count
        (:meth:`to_frame` has every row). Not-determined quantities are named, never shown with a value.
        """
        return _summary.summary_text(self)

    def __repr__(self) -> str:
        return _summary.short_repr(self)

    __str__ = __repr__

    def _repr_html_(self) -> str:
        return _summary.html_repr(self)

    def to_frame(self, alpha: float = 0.05):
        """pandas DataFrame, one row per estimate, indexed by name.

        Columns ``value, std, unit, status, note`` (the stored estimate: :meth:`from_frame` rebuilds
        the estimates from them), ``estimate, lower, upper`` (the value and its ``1 - alpha``
        normal interval, NaN when not determined), ``rel_se`` and ``verdict``
        (:func:`shipid.summary.grade`).
        """
        return _summary.frame(self, alpha)

    @staticmethod
    def estimates_from_frame(df) -> dict[str, Estimate]:
        """The estimates of a :meth:`to_frame` table (its ``value, std, unit, status, note`` columns)."""
        return {k: Estimate(**v) for k, v in _summary.estimates_from_frame(df).items()}

    def conf_int(self, alpha: float = 0.05):
        """``1 - alpha`` normal-approximation intervals (DataFrame ``lower``, ``upper``; NaN when not
        determined or without SE)."""
        return self.to_frame(alpha)[["lower", "upper"]]

    @property
    def params(self):
        """Estimates as a pandas Series (NaN where not determined: those are not estimates)."""
        s = self.to_frame()["estimate"]
        s.name = "estimate"
        return s

    @property
    def bse(self):
        """Standard errors as a pandas Series (NaN where not determined)."""
        f = self.to_frame()
        s = f["std"].where(f["estimate"].notna())
        s.name = "std"
        return s

    @property
    def verdict(self) -> "_summary.Verdict":
        """One verdict per estimate (:func:`shipid.summary.verdict`), as the report and summary show it."""
        return _summary.verdict(self)

    @property
    def cov(self) -> Covariance | None:
        """:attr:`covariance` with its names, as a :class:`Covariance` (None when there is none)."""
        if self.covariance is None:
            return None
        return Covariance(tuple(self.covariance_names), np.asarray(self.covariance, dtype=float))

    @property
    def converged(self) -> bool | None:
        """``diagnostics.converged``."""
        return self.diagnostics.converged

    @property
    def warnings(self) -> list:
        """``diagnostics.warnings``: the lines the CLI prints on stderr."""
        return self.diagnostics.warnings

    def with_series(self, **kwargs) -> "Result":
        """This result with the report series its method computes on request.

        Calls ``with_series(result, **kwargs)`` of the method's ``series`` module (found through
        :mod:`shipid.registry`); a method without one returns the result unchanged.
        """
        info = registry.for_result(self.method)
        if info is None or not info.has_module("series"):
            return self
        fn = getattr(info.submodule("series"), "with_series", None)
        return fn(self, **kwargs) if callable(fn) else self

    def to_dict(self) -> dict[str, Any]:
        return {
            "method": self.method,
            "model": _jsonable(self.model),
            "estimates": {k: asdict(v) for k, v in self.estimates.items()},
            "covariance": None if self.covariance is None else _jsonable(self.covariance),
            "covariance_names": list(self.covariance_names),
            "diagnostics": _jsonable(self.diagnostics.to_dict()),
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


_PLAIN = frozenset((float, int, str, bool, type(None)))


def _jsonable(x: Any) -> Any:
    """Convert numpy containers and scalars to plain JSON types (NaN kept as NaN)."""
    if type(x) in _PLAIN:             # the bulk of a result (its series): returned before the abstract-class checks
        return x
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
