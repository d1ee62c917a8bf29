"""``shipid.methods.mmg.identify``: the common entry shape around :func:`shipid.methods.mmg.pipeline.identify`."""

from __future__ import annotations

from shipid.errors import InputError
from shipid.methods._trials import as_list, as_trial
from shipid.methods.mmg import pipeline
from shipid.methods.mmg.estimator import FitConfig
from shipid.methods.mmg.validate import load_model
from shipid.models import mmg as mmg_model
from shipid.result import Result


def identify(trials, *, vessel: str | None = None, options: FitConfig | None = None, prior=None,
             **kw) -> Result:
    """An MMG model from free-running model tests (EBM applied to the MMG structure).

    Parameters
    ----------
    trials : sequence
        Measured runs (objects or paths); files are read with empty rows trimmed and gaps of up to
        1 s interpolated (each repair is reported).
    vessel, prior : str or MmgModel
        The prior: a published set (``"esso_osaka_3m"``, ``"kvlcc2_hsva"``, ``"published:<name>"``) or
        an identified model JSON; ``vessel`` is accepted as the same argument.
    options : FitConfig, optional
    **kw
        ``structure=``, ``folds=``, ``refine=`` ... of :func:`shipid.methods.mmg.pipeline.identify`;
        ``refine`` defaults to ``"auto"`` (see :func:`shipid.methods.mmg.pipeline.identify`).
    """
    data = [as_trial(x, trim_empty_rows=True, interpolate_gaps=1.0, method="shipid.identify mmg")
            for x in as_list(trials)]
    prior = prior or vessel
    if prior is None:
        raise InputError("mmg: prior= is required (a published set such as 'esso_osaka_3m' or 'kvlcc2_hsva', "
                         "or an identified model JSON)")
    if isinstance(prior, str):
        prior = (load_model(prior) if prior.endswith(".json")
                 else mmg_model.load_published(prior.replace("published:", "")))
    if options is not None:
        kw["fit_config"] = options
    kw.setdefault("refine", "auto")
    return pipeline.identify(data, prior, **kw)
