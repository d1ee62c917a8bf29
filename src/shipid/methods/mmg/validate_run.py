"""``shipid validate`` of an MMG model: the run read as its file says, simulated open loop, the warning lines.

:func:`validate_with_run` is what ``shipid validate MODEL --trial RUN`` and ``shipid.validate`` call for an MMG
model (re-exported by :mod:`shipid.methods.mmg.entry`). It lives apart from the identification so that
validating a model loads none of the identification modules (start-up, ``benchmarks/bench_cli_startup.py``).
"""

from __future__ import annotations

from shipid.errors import InputError
from shipid.warning_lines import one_line, repair_warnings, unconverged_model_line
from shipid.methods.mmg import profile as PF
from shipid.methods.mmg import validate as V
from shipid.methods.mmg.manoeuvres import depth_check
from shipid.models import mmg as mmg_model
from shipid.result import Result


def validate(model, trial, *, horizon: float | None = None, fmt: str | None = None, channels=None,
             rudder_sign: int | None = None, retime: bool = True, **kw):
    """Open-loop prediction of a measured run by an MMG model (:func:`validate_with_run` without the run)."""
    return validate_with_run(model, trial, horizon=horizon, fmt=fmt, channels=channels, rudder_sign=rudder_sign,
                             retime=retime, **kw)[0]


def validate_with_run(model, trial, *, horizon: float | None = None, fmt: str | None = None, channels=None,
                      rudder_sign: int | None = None, retime: bool = True, **kw):
    """Open-loop prediction of a measured run by an MMG model, the run read as its file says.

    Parameters
    ----------
    model : str, MmgModel, Result or dict
        MODEL.json path, ``"published:<name>"``, an :class:`~shipid.models.mmg.MmgModel`, an
        ``identify("mmg", ...)`` result or its dict.
    trial : Trial or path
        The measured run; read by :func:`shipid.methods.mmg.profile.read_for_model` (the model's reading
        settings and rudder sign apply to a run of its training runs' kind only).
    horizon : float, optional
        Restarted-horizon length, s (default: the model's, else 60 s).
    fmt, channels, rudder_sign : optional
        Reading settings that override the model's.
    retime : bool
        Re-time the run by the model's offsets (``model["retime"]``, estimated on its training runs) when it
        has them and the run is of its training runs' kind (one data-repair line); False: refuse (one line).
    **kw
        ``stride=``, ``windows=`` of :func:`shipid.methods.mmg.validate.validate`.

    Returns
    -------
    Validation, Trial
        The validation, with ``settings`` holding how the run was read and ``settings["warnings"]`` the warning lines
        (non-converged model, a reading conflict, a contradicted rudder convention, a depth change, data
        repairs); and the run as it was simulated (MMG's conventions).
    """
    if isinstance(model, Result):
        doc, label = model.to_dict(), "the model"
        m = V.model_from_result(doc)
    elif isinstance(model, dict):
        doc, label = model, "the model"
        m = V.model_from_result(doc)
    elif isinstance(model, mmg_model.MmgModel):
        m, doc, label = model, None, model.name
    else:
        m, doc = V.load_model_document(model)
        label = str(model)
    if horizon is not None and not horizon > 0:
        raise InputError("the horizon must be positive")
    mv = dict(((doc or {}).get("model") or {}).get("validate") or {})
    notes = unconverged_model_line(doc, label)
    tr, settings, more = PF.read_for_model(trial, mv, fmt=fmt, channels=channels, rudder_sign=rudder_sign)
    notes += more
    rt = ((doc or {}).get("model") or {}).get("retime")
    kinds = list(mv.get("profiles") or [])
    settings["retimed"] = False
    if rt and (not kinds or settings["profile"] in kinds):
        if retime:
            tr = PF.apply_retime(tr, rt)
            notes.append(PF.retime_line(rt, str(tr.meta.get("source", "the run"))))
            settings["retimed"] = True
        else:
            notes.append("not re-timed (--no-retime): the model was identified from runs re-timed onto their "
                         "position clock, this run is compared as recorded")
    rs = settings["rudder_sign"]
    st, w = PF.convention_warning(tr, rs, "the model's convention (rudder positive turns to starboard"
                                  + (f", as in its training runs with rudder sign {int(mv['rudder_sign']):+d})"
                                     if "rudder_sign" in mv else ")"))
    if w:
        notes.append(w)
    if tr.meta.get("water_depth") is not None:       # the run's depth against the model's training depth
        tc = ((doc or {}).get("model") or {}).get("training_conditions") or {}
        notes += depth_check(float(m.particulars["d"]), tc.get("water_depth"), float(tr.meta["water_depth"]))[1]
    if horizon is None:
        horizon = float(mv.get("horizon_s", V.DEFAULT_HORIZON))
    v = V.validate(m, tr, horizon=horizon, **kw)
    warns: list[str] = []
    for line in [*repair_warnings([tr]), *notes]:
        line = one_line(line)
        if line not in warns:
            warns.append(line)
    v.settings.update(settings, horizon_s=horizon, first_step_yaw_sign=st, warnings=warns)
    return v, tr


__all__ = ["validate", "validate_with_run"]
