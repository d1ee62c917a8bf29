"""Readers of the two real free-running data sets in ``shared/data`` (README there).

* **Esso Osaka 3 m** (Inukai pond, Osaka University; Wakita et al. 2022, Miyauchi et al.
  2022): :func:`read_esso` reads one run by its path relative to ``esso_osaka_3m/data``
  (the papers' training/test splits are listed in ``studies/esso_runs.py``).
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


__all__ = ["esso_dir", "read_esso", "read_kvlcc2"]
