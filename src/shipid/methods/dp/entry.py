"""``shipid.methods.dp.identify``: the common entry shape around :func:`identify_dp`."""

from __future__ import annotations

from shipid.methods._trials import as_trial, grouped
from shipid.methods.dp.estimator import DPOptions, identify_dp
from shipid.models.dp import dp_vessel
from shipid.result import Result
from shipid.vessels import load_vessel

#: Channels of a DP trial (Fossen et al. 1996 §4: positions, heading, pitch ratios, azimuth angle).
REQUIRED = ("x", "y", "psi", "p1", "p2", "p3", "p4", "p5", "p6", "alpha6")


def identify(trials, *, vessel: str | None = None, options: DPOptions | None = None, **kw) -> Result:
    """DP low-frequency model by the parallel state-augmented EKF (Fossen, Sagatun & Sørensen 1996).

    Parameters
    ----------
    trials : mapping
        ``{"surge": [...], "sway-yaw": [...], "azimuth": [...]}``: trials (objects or paths) per stage.
    vessel : str, optional
        Packaged vessel whose particulars (mass, length, thruster layout) are known (default ``supply``).
    options : DPOptions, optional
    **kw
        Passed to :func:`identify_dp`.
    """
    groups = grouped(trials, ("surge", "sway-yaw", "azimuth"), "dp")
    v = dp_vessel(load_vessel(vessel or "supply"))
    t = {g: [as_trial(x, required=list(REQUIRED), manoeuvre=f"dp-{g}") for x in ts] for g, ts in groups.items()}
    return identify_dp(t["surge"], t["sway-yaw"], t["azimuth"], v, options or DPOptions(), **kw)
