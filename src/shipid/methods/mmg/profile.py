"""Data profiles of MMG runs: how a run is read, its rudder sign, the prior it implies, and the checks.

Every face of ``identify mmg`` and ``validate`` (``shipid.identify("mmg", ...)``, ``shipid identify mmg``,
``shipid.validate``, ``shipid validate``) reads runs through :func:`read_run` and turns them into MMG's
conventions here, so that the same files give the same model whichever face is used.

A *data profile* is what the reader recognised in a file (``trial.meta["profile"]``): ``"esso"`` for the
Esso Osaka 3 m CSV logs, ``"kvlcc2"`` for the HSVA KVLCC2 ``.dat`` files. Each profile names its published
prior and the sign of its rudder relative to MMG's (MMG: a positive rudder angle turns the ship to
starboard; HSVA logs the rudder positive to port) in :data:`PROFILE_DEFAULTS`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Iterable, Sequence

from shipid.errors import InputError
from shipid.io.files import read_trial
from shipid.io.trial import Trial
from shipid.methods.mmg import timing as TM
from shipid.methods.mmg import timing_inputs as TI
from shipid.methods.mmg.validate import first_step_yaw_sign, load_model
from shipid.models import mmg

#: Per data profile: the published prior and the sign of the file's rudder relative to MMG's.
PROFILE_DEFAULTS = {"kvlcc2": ("kvlcc2_hsva", -1), "esso": ("esso_osaka_3m", 1)}
#: How ``identify`` and ``validate`` read runs (recorded in MODEL.json's ``model.validate``).
READ_SETTINGS = {"trim_empty_rows": True, "interpolate_gaps": 1.0}
#: Data profiles whose runs are re-timed by default (``retime="auto"``): the Esso Osaka logs, whose heading,
#: body velocities, yaw rate and inputs lag the position (training-run CV of the held-out study:
#: docs/validation/mmg.md).
RETIME_PROFILES = ("esso",)
#: The prior used when neither the caller nor the files' profile names one.
FALLBACK_PRIOR = "esso_osaka_3m"


def read_run(path, fmt: str | None = None, channels=None, *, method: str = "shipid identify/validate mmg",
             required: Sequence[str] | None = None) -> Trial:
    """A run read with :data:`READ_SETTINGS` (empty rows trimmed, gaps up to 1 s interpolated and recorded)."""
    kw = {} if required is None else {"required": list(required)}
    return read_trial(path, fmt=fmt, channel_map=channels, method=method, **READ_SETTINGS, **kw)


def with_meta(tr: Trial, **meta) -> Trial:
    """A copy of ``tr`` whose metadata has ``meta`` added (the caller's trial is left as it is)."""
    return Trial(tr.t, dict(tr.channels), tr.units, {**tr.meta, **meta})


def as_run(x, fmt: str | None = None, channels=None, **kw) -> Trial:
    """``x`` itself when it is a :class:`Trial`, else the file read by :func:`read_run`."""
    return x if isinstance(x, Trial) else read_run(x, fmt, channels, **kw)


def profile_sign(profile: str | None) -> int:
    """The rudder sign of a data profile (+1 when the profile is unknown)."""
    return PROFILE_DEFAULTS.get(profile, (None, 1))[1]


def rudder_sign_of(trials: Iterable[Trial], rudder_sign: int | None = None) -> tuple[int, str]:
    """The rudder sign of training runs and where it came from: ``rudder_sign`` as given, else their profile.

    Raises :class:`~shipid.errors.InputError` for runs of profiles with different signs.
    """
    if rudder_sign is not None:
        if rudder_sign not in (1, -1):
            raise InputError("rudder_sign must be 1 or -1")
        return int(rudder_sign), "given"
    signs = {profile_sign(tr.meta.get("profile")) for tr in trials if not tr.meta.get("rudder_sign_flipped")}
    if len(signs) > 1:
        raise InputError("training runs with different rudder conventions: give the rudder sign (--rudder-sign)")
    return (signs.pop() if signs else 1), "data profile"


def flip(tr: Trial, sign: int) -> Trial:
    """``tr`` with its rudder multiplied by ``sign`` (once: a run already flipped is returned as it is)."""
    if sign == -1 and "delta" in tr and not tr.meta.get("rudder_sign_flipped"):
        return Trial(tr.t, {**tr.channels, "delta": -tr["delta"]}, tr.units,
                     {**tr.meta, "rudder_sign_flipped": True})
    return tr


def convention_warning(tr: Trial, sign: int, against: str) -> tuple[dict, str | None]:
    """The first-rudder-step yaw sign of a run (rudder already multiplied by ``sign``) and a warning if it
    contradicts MMG's convention (``against`` names what it contradicts)."""
    st = first_step_yaw_sign(tr)
    if st["sign"] >= 0:
        return st, None
    return st, (f"{tr.meta.get('source', 'run')}: the yaw response to the first rudder step (t = {st['t_step']:.1f} s, "
                f"rudder {st['delta_step_deg']:+.1f} deg with rudder sign {sign:+d}, yaw rate change "
                f"{st['dr_deg_s']:+.2f} deg/s) contradicts {against}; the run's rudder sign is probably the "
                f"opposite (--rudder-sign {-sign:+d})")


def choose_prior(spec, profiles: Iterable[str | None], notes: list[str]):
    """The prior model and how it was chosen: ``spec`` (a name, ``published:NAME``, a model JSON or an
    :class:`~shipid.models.mmg.MmgModel`), else the data profile, else :data:`FALLBACK_PRIOR` with a
    warning appended to ``notes``."""
    if isinstance(spec, mmg.MmgModel):
        return spec, {"spec": spec.name, "name": spec.name, "chosen_by": "given"}
    if spec is None:
        known = {p for p in profiles if p in PROFILE_DEFAULTS}
        if len(known) > 1:
            raise InputError(f"training runs of different ships ({', '.join(sorted(known))}): give the prior")
        if known:
            prof = known.pop()
            spec, how = PROFILE_DEFAULTS[prof][0], f"data profile {prof}"
        else:
            spec, how = FALLBACK_PRIOR, "default (no prior given, and the files' format names no ship)"
            notes.append("no prior given and the training files' format names no ship: the Esso Osaka 3 m "
                         "prior (structure, masses, fixed constants) is used; give the prior (--prior) for another ship")
    else:
        spec, how = str(spec), "given"
    if spec.endswith(".json"):
        return load_model(spec), {"spec": spec, "chosen_by": how}
    pm = mmg.load_published(spec.replace("published:", ""))
    return pm, {"spec": spec, "name": pm.name, "chosen_by": how}


# ----------------------------------------------------------------------------- runs read for a model
#: The format a file's extension says (as :func:`shipid.io.files.read_trial` reads it without ``fmt``).
OWN_FORMAT = {".csv": "csv", ".txt": "csv", ".parquet": "parquet", ".pq": "parquet", ".dat": "kvlcc2"}


def _own_format(path) -> str | None:
    """The format a file's extension says it has; None when it does not say."""
    return OWN_FORMAT.get(Path(path).suffix.lower())


def _compatible(recorded: str | None, own: str | None) -> bool:
    """Whether a model's recorded format applies to a file whose own format is ``own``."""
    if recorded is None or own is None:
        return True
    return recorded == own or (recorded == "esso" and own == "csv")


def read_for_model(x, mv: dict, *, fmt: str | None = None, channels=None, rudder_sign: int | None = None,
                   method: str = "shipid validate mmg", required: Sequence[str] | None = None
                   ) -> tuple[Trial, dict, list[str]]:
    """A run read as the file says, in MMG's conventions, for a model whose reading settings are ``mv``.

    ``mv`` is MODEL.json's ``model.validate`` (``format``, ``channels``, ``profiles``, ``rudder_sign``).
    The model's format and column map apply only to a file of the same kind (a CSV is not read as an
    HSVA ``.dat`` because the model was trained on those); its rudder sign applies only to a run of one of
    its training runs' profiles, and a run of another profile takes its own profile's sign. ``fmt``,
    ``channels`` and ``rudder_sign`` given by the caller win. Returns the run (rudder flipped to MMG's
    convention), the settings used and the warning lines (a conflict is one line).
    """
    notes: list[str] = []
    differs: list[str] = []          # what the file says against the model's settings: one line at the end
    use_fmt, use_ch = fmt, channels
    if not isinstance(x, Trial) and fmt is None:
        rec_fmt, own = mv.get("format"), _own_format(x)
        if _compatible(rec_fmt, own):
            use_fmt = rec_fmt
            if use_ch is None:
                use_ch = mv.get("channels")
        else:
            differs.append(f"format {own}, not the model's {rec_fmt}"
                           + (" and its column map" if mv.get("channels") and channels is None else ""))
    elif fmt is not None and fmt == mv.get("format") and use_ch is None:
        use_ch = mv.get("channels")
    tr = as_run(x, use_fmt, use_ch, method=method, required=required)
    profile = tr.meta.get("profile")
    model_profiles = list(mv.get("profiles") or [])
    same = not model_profiles or profile in model_profiles
    if rudder_sign is None:
        if "rudder_sign" in mv and same:
            rudder_sign, sign_from = int(mv["rudder_sign"]), "model"
        else:
            rudder_sign, sign_from = profile_sign(profile), "data profile"
            if "rudder_sign" in mv and int(mv["rudder_sign"]) != rudder_sign:
                differs.append(f"rudder sign {rudder_sign:+d} of its data profile ({profile or 'none named'}), not "
                               f"the {int(mv['rudder_sign']):+d} of the model's training runs "
                               f"({', '.join(model_profiles)})")
    else:
        if rudder_sign not in (1, -1):
            raise InputError("rudder_sign must be 1 or -1")
        sign_from = "given"
        if "rudder_sign" in mv and same and int(mv["rudder_sign"]) != rudder_sign:
            notes.append(f"rudder sign {rudder_sign:+d} differs from the rudder sign of the model's training runs "
                         f"({int(mv['rudder_sign']):+d})")
    if differs:
        notes.insert(0, f"{tr.meta.get('source', 'run')}: read as the file says, not with the model's reading "
                        f"settings: {'; '.join(differs)}")
    tr = flip(tr, rudder_sign)
    settings = {"format": use_fmt, "channels": use_ch, "profile": profile, "rudder_sign": rudder_sign,
                "rudder_sign_from": sign_from}
    return tr, settings, notes


# ----------------------------------------------------------------------------- re-timing
def wants_retime(retime, profiles: Iterable[str | None]) -> bool:
    """Whether runs of ``profiles`` are re-timed: ``retime`` True/False as given; ``"auto"`` for runs all of
    a profile in :data:`RETIME_PROFILES`."""
    if retime in (True, False):
        return bool(retime)
    if retime != "auto":
        raise InputError(f"retime must be 'auto', True or False, got {retime!r}")
    ps = set(profiles)
    return bool(ps) and ps <= set(RETIME_PROFILES)


def estimate_retime(trials: Sequence[Trial]) -> dict:
    """Offsets of the state channels (:func:`shipid.methods.mmg.timing.estimate_lags`) and of the inputs
    (:func:`shipid.methods.mmg.timing_inputs.estimate_input_lags`, on the state-re-timed runs) behind the
    position, estimated on the training runs; the dict MODEL.json records as ``model["retime"]``."""
    lags = TM.estimate_lags(trials)
    ilags = TI.estimate_input_lags([TM.retime(tr, lags) for tr in trials])
    lags = TI.with_inputs(lags, ilags)
    return {**lags.to_dict(), "not_determined": TI.at_bound(ilags)}


def apply_retime(tr: Trial, retime: dict) -> Trial:
    """``tr`` re-timed onto its position clock by the offsets ``retime`` (MODEL.json's ``model["retime"]``);
    the reader's repairs are kept, the re-timing is said by :func:`retime_line` instead of per run."""
    keys = ("psi", "uv", "r", "mismatch_before", "mismatch_after", "runs", "delta", "n", "wind")
    out = TM.retime(tr, TM.Lags(**{k: retime[k] for k in keys if k in retime}))
    return Trial(out.t, out.channels, out.units, {**out.meta, "repairs": list(tr.meta.get("repairs", []) or [])})


def retime_line(retime: dict, what: str) -> str:
    """The one data-repair line of a re-timing of ``what`` (e.g. "the 32 training runs")."""
    line = (f"data repaired: heading, body velocities and yaw rate (advanced by {retime['psi']:.2f} s, "
            f"{retime['uv']:.2f} s, {retime['r']:.2f} s) and rudder angle, propeller rate and wind (advanced by "
            f"{retime['delta']:.2f} s, {retime['n']:.2f} s, {retime['wind']:.2f} s) of {what} re-timed onto the "
            f"position clock (offsets estimated on the {retime['runs']} training runs; --no-retime to refuse)")
    for name in retime.get("not_determined") or ():
        line += f"; the {name} offset is on the end of its search grid (not determined within it, used as found)"
    return line


__all__ = ["PROFILE_DEFAULTS", "READ_SETTINGS", "FALLBACK_PRIOR", "read_run", "with_meta", "as_run", "profile_sign",
           "rudder_sign_of", "flip", "convention_warning", "choose_prior", "read_for_model",
           "RETIME_PROFILES", "wants_retime", "estimate_retime", "apply_retime", "retime_line"]
