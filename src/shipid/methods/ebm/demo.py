"""The EBM result of ``shipid demo``'s report step when no real data are at hand (Yoon & Rhee 2003)."""

from __future__ import annotations

from shipid.methods.ebm import estimator as ebm
from shipid.methods.ebm import series as ebm_series
from shipid.methods.ebm import trials as ebm_trials


def fallback(seed: int):
    """Yoon & Rhee (2003): a simulated 20/20 zig-zag and a 35 deg turn of ESSO OSAKA."""
    trials = [ebm_trials.simulate_trial("zigzag-20", 600.0, seed=seed + 1),
              ebm_trials.simulate_trial("turning-35", 600.0, seed=seed + 2)]
    res = ebm_series.with_series(ebm.identify_run(trials))
    res.provenance.setdefault("seed", seed)
    res.provenance.setdefault("command", "shipid demo (report step: simulated ESSO OSAKA trials)")

    # opt-in extras, each a few seconds: held-out validation (Figs 6, 10), coarse D-optimal map (Fig. 7)
    for what, kind, fn in (("validation overlays", "overlays",
                            lambda: ebm_series.validation_overlays(res, seed=seed + 500)),
                           ("Fig. 7 D-optimal map", "contours",
                            lambda: {"d_optimal": ebm_series.coarse_d_optimal()})):
        try:
            res.series.setdefault(kind, {}).update(fn())
        except Exception as err:  # noqa: BLE001 - an extra; say why it is missing
            res.diagnostics.setdefault("warnings", []).append(
                f"demo report: {what} not computed ({type(err).__name__}: {err})")
    return res
