"""``shipid.methods.ebm.identify``: the common entry shape around :func:`shipid.methods.ebm.estimator.identify`."""

from __future__ import annotations

from shipid.methods._trials import as_list, as_trial
from shipid.methods.ebm import estimator
from shipid.methods.ebm.estimator import REQUIRED, EbmConfig
from shipid.result import Result


def identify(trials, *, vessel: str | None = None, options: EbmConfig | None = None, **kw) -> Result:
    """Abkowitz coefficients by Estimation-Before-Modelling (Yoon & Rhee 2003).

    Parameters
    ----------
    trials : sequence
        Trials (objects or paths) with the channels of :data:`REQUIRED`.
    vessel : str, optional
        Packaged ship whose particulars are known (default ``esso-osaka``).
    options : EbmConfig, optional
    **kw
        Passed to :func:`shipid.methods.ebm.estimator.identify`.
    """
    vessel = vessel or "esso-osaka"
    data = [as_trial(x, required=list(REQUIRED), method="ebm", vessel=vessel) for x in as_list(trials)]
    return estimator.identify(data, vessel, config=options or EbmConfig(), **kw)
