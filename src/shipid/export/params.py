"""Parameter files: a model's numbers in plain TOML (or YAML), with units and sources, read back by shipid.

:func:`write_params` writes a :class:`shipid.export.source.Source` as::

    [model]         family (mmg | abkowitz | dp), structure (MMG), name, method, origin, shipid_version
    [sources]       where the numbers come from
    [particulars]   every constant of the model: { value = ..., unit = "..." }
    [coefficients]  every coefficient: { value, unit, std, status }
    [conditions]    recorded test conditions (MMG training conditions, approach speed and rate)
    [steering]      rudder limit and rate (abkowitz)

in the layout of shipid's packaged vessel files (``src/shipid/vessels/data/*.toml``). Floats are written
with ``repr`` (the shortest text that reads back to the same double), so a model read back by
:func:`read_params` simulates bit-identically to the model written. YAML (``.yaml``/``.yml``) holds the
same mapping and needs PyYAML.

:func:`simulate_params` runs a parameter file through a standard manoeuvre, as ``shipid simulate``
runs the model the file came from: MMG models at the conditions of
:func:`shipid.methods.mmg.manoeuvres.resolve_conditions` (the recorded training conditions, or
``speed``/``rps``/``rudder_rate``), the Abkowitz model in calm water with its propeller rate scaled with
the speed (as :func:`shipid.models.abkowitz.ship_model`), the DP model by
:func:`shipid.models.dp.ship_model`.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import fields, replace
from pathlib import Path
from typing import Any, Mapping

import numpy as np

import shipid
from shipid.errors import InputError, ShipidError
from shipid.export.source import Source, coefficient_names, from_model, load_source
from shipid.io.trial import Trial
from shipid.methods.mmg import manoeuvres as MM
from shipid.models import abkowitz as ab
from shipid.models import dp
from shipid.models import mmg
from shipid.models.bis import Bis
from shipid.outputs import atomic_write_text
from shipid.simulate.manoeuvres import parse_manoeuvre, run_manoeuvre
from shipid.models.ship_model import ShipModel

SUFFIXES = (".toml", ".yaml", ".yml")

#: Units of MMG particulars (SI); anything not listed is non-dimensional.
MMG_UNITS = {"L": "m", "B": "m", "d": "m", "rho": "kg/m^3", "m": "kg", "x_G": "m", "m_x": "kg", "m_y": "kg",
             "J_z": "kg*m^2", "I_zG": "kg*m^2", "D_p": "m", "H_R": "m", "A_R": "m^2", "x_R": "m", "x_H": "m",
             "rho_air": "kg/m^3", "A_T": "m^2", "A_L": "m^2", "AOD": "m^2", "LCW": "m", "LCBR": "m", "HBR": "m",
             "HC": "m", "SBW": "m"}
#: Units of the Abkowitz particulars (:class:`shipid.models.abkowitz.AbkowitzParams`).
AB_UNITS = {"L": "m", "rho": "kg/m^3", "m": "kg", "x_G": "m", "I_z": "kg*m^2", "X_udot": "kg", "Y_vdot": "kg",
            "Y_rdot": "kg*m", "N_vdot": "kg*m", "N_rdot": "kg*m^2", "D": "m", "w": "-", "kt": "-", "U0": "m/s",
            "n0": "1/s", "c0": "m/s", "current_speed": "m/s", "current_dir": "rad", "yaw_rudder_variant": "-"}
CONDITION_UNITS = {"speed": "m/s", "rps": "1/s", "rps_ahead": "1/s", "rps_astern": "1/s", "rps_rate": "1/s^2",
                   "rudder_rate": "rad/s", "speed_p95": "m/s", "water_depth": "m", "water_depth_runs": "-",
                   "runs": "-", "rudder_limit": "rad", "rudder_rate_limit": "rad/s"}


def is_params_file(spec: str) -> bool:
    """True when ``spec`` names a parameter file (by its suffix)."""
    return Path(str(spec)).suffix.lower() in SUFFIXES


# ----------------------------------------------------------------------------- the document
def _num(x: Any) -> Any:
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x)
    if isinstance(x, np.ndarray):
        return _num(x.tolist())
    if isinstance(x, (list, tuple)):
        return [_num(v) for v in x]
    return x


def _entry(value: Any, unit: str, **extra: Any) -> dict[str, Any]:
    out = {"value": _num(value), "unit": unit}
    out.update({k: _num(v) for k, v in extra.items() if v is not None and v != ""})
    return out


def document(src: Source) -> dict[str, Any]:
    """The mapping :func:`write_params` writes (module docstring)."""
    model: dict[str, Any] = {"family": src.family, "name": src.name, "method": src.method or "none",
                             "origin": src.origin, "shipid_version": shipid.__version__}
    part: dict[str, Any] = {}
    steering: dict[str, Any] = {}
    if src.family == "mmg":
        model["structure"] = src.model.structure
        part = {k: _entry(v, MMG_UNITS.get(k, "-")) for k, v in src.model.particulars.items()}
    elif src.family == "abkowitz":
        p = src.model
        part = {f.name: _entry(getattr(p, f.name), AB_UNITS.get(f.name, "-")) for f in fields(p)
                if f.name not in ("theta_X", "theta_Y", "theta_N")}
        lim = src.conditions.get("rudder_limit", np.deg2rad(35.0))
        rate = src.conditions.get("rudder_rate_limit", np.deg2rad(2.33))
        steering = {"rudder_limit": _entry(lim, "rad"), "rudder_rate_limit": _entry(rate, "rad/s")}
    else:
        v = src.model
        model["vessel"] = v.name
        part = {"L": _entry(v.bis.L, "m"), "m": _entry(v.bis.m, "kg"), "g": _entry(v.bis.g, "m/s^2"),
                "M": _entry(v.M, "- (bis, eq. 30)"), "arms": _entry(v.arms, "- (bis length, eq. 29)"),
                "p0": _entry(v.p0, "- (pitch ratio, eq. 1)")}
    coefs = {}
    for k in coefficient_names(src.family, src.model):
        sd = src.std.get(k, float("nan"))
        coefs[k] = _entry(src.coef[k], src.units.get(k, "-"), std=sd, status=src.status.get(k, ""),
                          source=src.coef_sources.get(k, ""))
    cond = {k: _entry(v, CONDITION_UNITS.get(k, "-")) for k, v in src.conditions.items()
            if isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)
            and k not in ("rudder_limit", "rudder_rate_limit")}
    out = {"model": model, "sources": {k: str(v) for k, v in src.sources.items()}, "particulars": part,
           "coefficients": coefs, "conditions": cond}
    if steering:
        out["steering"] = steering
    if src.cov is not None and src.cov_names:
        out["covariance"] = {"names": list(src.cov_names), "matrix": _num(np.asarray(src.cov)),
                             "note": src.cov_note}
    return out


# ----------------------------------------------------------------------------- TOML text
def _toml_key(k: str) -> str:
    return k if k.replace("_", "a").replace("-", "a").isalnum() and k.isascii() else _toml_str(k)


def _toml_str(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return _toml_str(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, Mapping):
        return "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def to_toml(doc: Mapping[str, Any]) -> str:
    """TOML text of :func:`document` (one table per section, one line per entry)."""
    lines = ["# shipid parameter file (shipid export params): a model's numbers with units and sources.",
             "# Read back by `shipid simulate FILE MANOEUVRE` and shipid.export.params.read_params.", ""]
    for sec, body in doc.items():
        lines.append(f"[{sec}]")
        for k, v in body.items():
            lines.append(f"{_toml_key(k)} = {_toml_value(v)}")
        lines.append("")
    return "\n".join(lines)


def write_params(src: Source, path: str | Path, *, force: bool = False) -> Path:
    """Write ``src`` as a parameter file (``.toml``; ``.yaml``/``.yml`` with PyYAML)."""
    path = Path(path)
    doc = document(src)
    suffix = path.suffix.lower()
    if suffix == ".toml":
        text = to_toml(doc)
    elif suffix in (".yaml", ".yml"):
        try:
            import yaml
        except ImportError:
            raise ShipidError("writing YAML needs PyYAML (pip install pyyaml); .toml needs nothing") from None
        text = ("# shipid parameter file (shipid export params): a model's numbers with units and sources.\n"
                + yaml.safe_dump(doc, sort_keys=False, allow_unicode=True, width=120))
    else:
        raise InputError(f"a parameter file ends in .toml, .yaml or .yml, got {path.name!r}")
    return atomic_write_text(path, text, force=force)


# ----------------------------------------------------------------------------- reading back
def _load_doc(path: Path) -> dict[str, Any]:
    if not path.is_file():
        raise InputError("no such parameter file", file=str(path))
    text = path.read_text(encoding="utf-8")
    try:
        if path.suffix.lower() == ".toml":
            return tomllib.loads(text)
        try:
            import yaml
        except ImportError:
            raise ShipidError("reading YAML needs PyYAML (pip install pyyaml)") from None
        doc = yaml.safe_load(text)
    except (tomllib.TOMLDecodeError, ValueError) as err:
        raise InputError(f"not a parameter file ({err})", file=str(path)) from None
    except Exception as err:  # noqa: BLE001 - yaml.YAMLError without importing yaml at module level
        raise InputError(f"not a parameter file ({type(err).__name__}: {err})", file=str(path)) from None
    if not isinstance(doc, dict):
        raise InputError("not a parameter file (no tables)", file=str(path))
    return doc


def _values(section: Mapping[str, Any]) -> dict[str, Any]:
    return {k: (v["value"] if isinstance(v, Mapping) else v) for k, v in section.items()}


def _floats(d: Mapping[str, Any]) -> dict[str, Any]:
    return {k: float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else v for k, v in d.items()}


def read_params(path: str | Path) -> Source:
    """The :class:`Source` of a parameter file written by :func:`write_params`."""
    path = Path(path)
    doc = _load_doc(path)
    try:
        info = doc["model"]
        family = info["family"]
        part = _values(doc.get("particulars", {}))
        coef_sec = doc.get("coefficients", {})
        coef = _floats(_values(coef_sec))
        cond = _values(doc.get("conditions", {}))
        cond.update(_values(doc.get("steering", {})))
        sources = {k: str(v) for k, v in doc.get("sources", {}).items()}
        name = str(info.get("name", path.stem))
        if family == "mmg":
            model = mmg.MmgModel(info["structure"], _floats(part), coef, name=name, sources=sources)
        elif family == "abkowitz":
            kw = {k: part[k] for k in part}
            kw["kt"] = tuple(float(x) for x in kw["kt"])
            kw["yaw_rudder_variant"] = bool(kw.get("yaw_rudder_variant", False))
            kw.update(theta_X=tuple(coef[k] for k in ab.THETA_X_NAMES), theta_Y=tuple(coef[k] for k in ab.THETA_Y_NAMES),
                      theta_N=tuple(coef[k] for k in ab.THETA_N_NAMES))
            model = ab.AbkowitzParams(**{k: (float(v) if isinstance(v, (int, float)) and not isinstance(v, bool)
                                             else v) for k, v in kw.items()})
        elif family == "dp":
            theta = np.array([coef[k] for k in dp.THETA_NAMES])
            A_h, K = dp.matrices_from_theta(theta)
            model = dp.DPVessel(M=np.asarray(part["M"], float), A_h=A_h, K=K, arms=np.asarray(part["arms"], float),
                                p0=np.asarray(part["p0"], float),
                                bis=Bis(L=float(part["L"]), m=float(part["m"]), g=float(part["g"])),
                                name=str(info.get("vessel", name)))
        else:
            raise InputError(f"unknown model family {family!r} (mmg, abkowitz, dp)", file=str(path))
    except (KeyError, TypeError, ValueError) as err:
        raise InputError(f"malformed parameter file ({type(err).__name__}: {err})", file=str(path)) from None
    std = {k: float(v.get("std", float("nan"))) for k, v in coef_sec.items() if isinstance(v, Mapping)}
    src = from_model(family, model, origin=str(path), sources=sources, conditions=cond, status="", std=std)
    status = {k: str(v.get("status", "")) for k, v in coef_sec.items() if isinstance(v, Mapping)}
    per = {k: str(v["source"]) for k, v in coef_sec.items() if isinstance(v, Mapping) and "source" in v}
    cov = doc.get("covariance")
    extra = {"status": status, "method": str(info.get("method", "")), "coef_sources": per}
    if isinstance(cov, Mapping) and cov.get("names"):
        extra.update(cov_names=tuple(cov["names"]), cov=np.asarray(cov["matrix"], float),
                     cov_note=f"{cov.get('note', 'covariance')} (read from {path.name})")
    else:
        extra["cov_note"] = f"no covariance in {path.name}"
    return _replace(src, **extra)


def _replace(src: Source, **kw) -> Source:
    return replace(src, **kw)


def load(spec: Any, *, form_term: bool = True) -> Source:
    """:func:`read_params` for a parameter file, else :func:`shipid.export.source.load_source` (``form_term``
    there)."""
    if isinstance(spec, (str, Path)) and is_params_file(str(spec)):
        return read_params(spec)
    return load_source(spec, form_term=form_term)


# ----------------------------------------------------------------------------- simulating it
def abkowitz_ship_model(p: ab.AbkowitzParams, *, name: str, rudder_limit: float, rudder_rate_limit: float) -> ShipModel:
    """The :class:`ShipModel` of Abkowitz parameters in calm water (as :func:`shipid.models.abkowitz.ship_model`)."""
    p = p.with_current(0.0, 0.0)
    return ShipModel(name=name, f=ab.make_dynamics(p), theta=p, state_names=ab.STATE_NAMES, input_names=("delta", "n"),
                     x0=lambda s: np.array([float(s), 0.0, 0.0, 0.0, 0.0, 0.0]),
                     outputs=lambda t, X, U, _p=p: ab.outputs(t, X, U, _p), service_speed=p.U0, heading_index=5,
                     rudder_limit=float(rudder_limit), rudder_rate_limit=float(rudder_rate_limit),
                     u0=lambda s: np.array([0.0, p.n0 * float(s) / p.U0]))


def simulate_params(path: str | Path, manoeuvre: str, *, duration: float | None = None, dt: float = 0.1,
                    seed: int = 0, speed: float | None = None, rps: float | None = None,
                    rudder_rate: float | None = None, water_depth: float | None = None
                    ) -> tuple[Trial, list[str], list[str]]:
    """Simulate the model of a parameter file through ``manoeuvre`` (module docstring).

    Returns
    -------
    (Trial, notes, warnings)
        The record, lines saying which conditions were used, and warnings (one line each).
    """
    src = read_params(path)
    return simulate_source(src, manoeuvre, duration=duration, dt=dt, seed=seed, speed=speed, rps=rps,
                           rudder_rate=rudder_rate, water_depth=water_depth)


def simulate_source(src: Source, manoeuvre: str, *, duration: float | None = None, dt: float = 0.1,
                    seed: int = 0, speed: float | None = None, rps: float | None = None,
                    rudder_rate: float | None = None, water_depth: float | None = None
                    ) -> tuple[Trial, list[str], list[str]]:
    """Simulate the model of a :class:`Source` through ``manoeuvre`` as :func:`simulate_params` does."""
    parse_manoeuvre(manoeuvre)                   # an unknown manoeuvre is refused first
    if src.family != "mmg" and (rps is not None or rudder_rate is not None or water_depth is not None):
        raise InputError("--rps, --rudder-rate and --water-depth apply to MMG models only")
    if src.family == "mmg":
        d = {"model": {"training_conditions": dict(src.conditions)}} if src.conditions else None
        trial, cond = MM.simulate_model(src.model, d, manoeuvre, duration=duration, dt=dt, seed=seed, speed=speed,
                                        rps=rps, rudder_rate=rudder_rate, water_depth=water_depth)
        return trial, list(cond.notes), list(cond.warnings)
    if src.family == "abkowitz":
        c = src.conditions
        sm = abkowitz_ship_model(src.model, name=src.name, rudder_limit=c.get("rudder_limit", np.deg2rad(35.0)),
                                 rudder_rate_limit=c.get("rudder_rate_limit", np.deg2rad(2.33)))
        notes = ["calm water (the current of the file is not simulated)"] if src.model.current_speed else []
    else:
        sm = dp.ship_model(src.model)
        notes = []
    trial = run_manoeuvre(sm, manoeuvre, duration=duration, dt=dt, seed=seed, speed=speed)
    return trial, notes, []

__all__ = ["SUFFIXES", "is_params_file", "document", "to_toml", "write_params", "read_params", "load",
           "simulate_params", "simulate_source", "abkowitz_ship_model"]
