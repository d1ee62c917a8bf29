"""The real-data MMG result of ``shipid demo``'s report step: KVLCC2 HSVA zig-zags, one held out."""

from __future__ import annotations

from shipid.io.basins import read_kvlcc2
from shipid.io.paths import data_root
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import pipeline as P
from shipid.methods.mmg import validate as V
from shipid.models import mmg
from shipid.report.convention import overlay, table, trial_summary

#: Real-data run (KVLCC2 HSVA zig-zags): trained on two, validated on a third (Figs 6/10 analogue).
KVLCC2_TRAIN = ("HSVA_CPMC_KVLCC2_Z_10_10_P.dat", "HSVA_CPMC_KVLCC2_Z_20_05.dat")
KVLCC2_TEST = "HSVA_CPMC_KVLCC2_Z_20_10_S.dat"


def real_data(seed: int):
    """EBM with the MMG model on real KVLCC2 model tests, or None without the data.

    Trained on two HSVA zig-zags; the third run is held out and simulated open loop with the
    identified model: its heading and yaw rate become validation overlays (Yoon & Rhee 2003, Figs 6, 10).
    """
    root = data_root()
    if root is None or not (root / "kvlcc2_hsva").is_dir():
        return None
    train = [read_kvlcc2(n) for n in KVLCC2_TRAIN]
    res = P.identify(train, mmg.load_published("kvlcc2_hsva"), structure=None, select=True,
                     extra_provenance={"command": "shipid demo (report step: real KVLCC2 HSVA zig-zags)",
                                       "seed": seed})
    test = read_kvlcc2(KVLCC2_TEST)
    v = V.validate(V.model_from_result(res.to_dict()), test)
    cols = {c: i for i, c in enumerate(mmg.STATE_NAMES)}
    ov = {}
    for ch, label, unit in (("psi", "heading ψ", "rad"), ("r", "yaw rate r", "rad/s"), ("v", "sway v", "m/s")):
        ov[f"{ch}_validation"] = overlay(v.t - v.t[0], v.measured[:, cols[ch]], v.predicted[:, cols[ch]], unit,
                                         label=f"{label} ({KVLCC2_TEST}, held out)", kind="validation")
    res.series.setdefault("overlays", {}).update(ov)
    rows = []
    for win, qs in v.windows.items():
        for q, st in qs.items():
            if isinstance(st, dict) and "rms" in st:
                rows.append([win, q, st["rms"], st.get("max"), st.get("unit", "")])
    if rows:
        res.series.setdefault("tables", {})["validation_errors"] = table(
            ["window", "quantity", "RMS error", "max error", "unit"], rows, paper="Figs 6, 10",
            title=f"open-loop simulation of the held-out run {KVLCC2_TEST} with the identified model")
    res.provenance["inputs"] = ([trial_summary(tr, note="training run") for tr in train]
                                + [trial_summary(test, note="held out: validation only")])
    return res


real_data.what = "real-data MMG identification (KVLCC2 HSVA zig-zags)"
