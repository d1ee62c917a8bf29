"""Readers of the two real free-running data sets in ``shared/data`` (README there).

* **Esso Osaka 3 m** (Inukai pond, Osaka University; Wakita et al. 2022, Miyauchi et al.
  2022): :func:`read_esso` reads one run by its path relative to ``esso_osaka_3m/data``;
  :data:`SPLITS` are the training/test splits of both papers, as listed in the data
  set's ``README_upstream.md`` ("Correspondence table with the paper").
* **KVLCC2, HSVA** (SIMMAN 2008 free-running zig-zags): :func:`read_kvlcc2` reads one
  run and puts the rudder angle in the MMG convention.

The files are read from :func:`shipid.io.data_root` (or a given ``root``) at run time;
nothing of them is copied into the package.
"""

from __future__ import annotations

from pathlib import Path

from shipid.io.files import read_trial
from shipid.io.paths import data_root
from shipid.io.trial import Trial
from shipid.errors import InputError

# shared/data/esso_osaka_3m/README_upstream.md, "Correspondence table with the paper".
_RND = "random/random_{}.csv"
SPLITS: dict[str, dict[str, list[str]]] = {
    "miyauchi2022": {
        "train": [_RND.format("06-Aug-2020_16_24_25_4"), _RND.format("06-Aug-2020_16_24_25_5"),
                  _RND.format("06-Aug-2020_16_24_25_6"), "turning/turn_cut_14-Sep-2020_16_09_02.csv",
                  "zigzag/zigzag_31-Jul-2020_13_22_52.csv", "zigzag/zigzag_31-Jul-2020_13_50_28.csv"],
        "test": [_RND.format("06-Aug-2020_16_24_25_3"), "turning/turn_14-Sep-2020_14_50_41.csv",
                 "zigzag/zigzag_31-Jul-2020_14_10_05.csv", "berthing/berthing_12-Nov-2020_11_49_21.csv",
                 "berthing/berthing_12-Nov-2020_13_21_03.csv"],
        "train_label": ["Train-TRZ"],
    },
    "wakita2022": {
        "train": [_RND.format(s) for s in ("03-Aug-2020_11_04_37", "06-Aug-2020_16_24_25_1",
                                           "06-Aug-2020_16_24_25_4", "06-Aug-2020_16_24_25_5",
                                           "06-Aug-2020_16_24_25_6", "31-Jul-2020_12_29_58",
                                           "31-Jul-2020_12_48_39", "31-Jul-2020_14_52_18")]
        + [f"turning/turn_{s}.csv" for s in ("14-Oct-2020_14_08_51", "14-Oct-2020_14_17_39",
                                            "14-Oct-2020_14_29_49", "14-Oct-2020_14_39_54",
                                            "14-Oct-2020_14_56_07", "14-Oct-2020_15_21_57",
                                            "14-Sep-2020_13_39_32", "14-Sep-2020_13_51_45",
                                            "14-Sep-2020_14_16_04", "14-Sep-2020_14_50_41",
                                            "14-Sep-2020_15_47_33", "14-Sep-2020_15_58_08",
                                            "cut_14-Sep-2020_15_58_08", "cut_14-Sep-2020_16_09_02")]
        + [f"zigzag/zigzag_31-Jul-2020_{s}.csv" for s in ("13_04_24", "13_14_21", "13_22_52", "13_29_19",
                                                          "13_50_28", "13_57_45", "14_03_39", "14_10_05")]
        + [f"berthing/berthing_12-Nov-2020_{s}.csv" for s in ("11_07_23", "11_14_47", "11_21_46",
                                                             "13_09_11", "13_37_05")],
        "test": [_RND.format("06-Aug-2020_16_24_25_3"), "turning/turn_14-Oct-2020_15_06_53.csv",
                 "zigzag/zigzag_31-Jul-2020_13_42_53.csv", "berthing/berthing_12-Nov-2020_11_38_50.csv",
                 "berthing/berthing_12-Nov-2020_11_49_21.csv", "berthing/berthing_12-Nov-2020_13_21_03.csv"],
        "train_label": ["Train-TZRB+"],
    },
}


def esso_dir(root: Path | None = None) -> Path:
    """The folder of the Esso Osaka runs (``esso_osaka_3m/data`` under :func:`shipid.io.data_root` or ``root``)."""
    root = data_root() if root is None else Path(root)
    d = None if root is None else root / "esso_osaka_3m" / "data"
    if d is None or not d.is_dir():
        raise InputError("the Esso Osaka data (esso_osaka_3m/data) was not found; set SHIPID_DATA")
    return d


def read_esso(rel: str, root: Path | None = None) -> Trial:
    """One Esso Osaka run (empty trailing rows trimmed, as the data set's README allows)."""
    return read_trial(esso_dir(root) / rel, trim_empty_rows=True, method="realdata study")


def read_kvlcc2(name: str, root: Path | None = None) -> Trial:
    """One HSVA zig-zag with the rudder in the MMG convention.

    HSVA records the rudder positive to port: in every run the yaw rate has the sign
    of −δ (checked on all 13 files). The MMG convention (positive δ turns the ship to
    starboard) needs ``δ = −δ_HSVA``; the flip is recorded in ``meta``.
    """
    root = data_root() if root is None else Path(root)
    d = None if root is None else root / "kvlcc2_hsva"
    if d is None or not d.is_dir():
        raise InputError("the KVLCC2 HSVA data (kvlcc2_hsva) was not found; set SHIPID_DATA")
    tr = read_trial(d / name, fmt="kvlcc2", method="realdata study")
    out = tr.with_channels(delta=-tr["delta"])
    out.meta["rudder_sign_flipped"] = "delta = -delta_HSVA (HSVA: positive to port)"
    return out


__all__ = ["SPLITS", "esso_dir", "read_esso", "read_kvlcc2"]
