"""Plausibility of a mass-cm estimate (Linder et al. 2015) and its identifiable derived quantities.

:func:`implausible_reasons` is the physical rule of the Table-3 study; :func:`implausible_identifiable` judges
what the data determine (m, zm_bar with their standard errors, the identified roll mode (18) of every dataset).
:func:`judge` applies both to an estimate (the flag, the relabelled entries and the warning lines of a result; used by
:mod:`shipid.methods.masscm.assemble` for Algorithm 1 and by :mod:`shipid.methods.masscm.refine` after a refinement).
:func:`rho_of` is the identifiable moment ratio ``rho = m z_m / (m_c z_c)`` and :func:`dm_dzf` the slope of the
exact-fit family ``m(z_f)`` (:mod:`shipid.methods.masscm.identifiability`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from shipid.methods.masscm.options import I_M, I_ZF, I_ZM
from shipid.models.roll_reduced import CALIBRATION, LOADED, NOMINAL, KnownParams, roll_terms

#: what the nuisance line says the out-of-range split comes from: Algorithm 1's estimate, or a refined one
_NUISANCE_TAIL = {False: ("): K_vdot, K_r, K_delta carry a finite-sample IV bias under sensor noise (module docstring, "
                          "'Known limitations'); m, zm_bar and rho are judged on their own and not flagged"),
                  True: ") after the refinement; m, zm_bar and rho are judged on their own and not flagged"}


def implausible_reasons(theta: np.ndarray, known: KnownParams, conds=(NOMINAL, CALIBRATION, LOADED)) -> list[str]:
    """The documented rule for an implausible (physically impossible) solution.

    Flagged when any of: ``m <= 1e-6 M`` (no load); ``|zm_bar| > 10 m`` (degenerate, load moment ~ 0); ``A_x <= 0``; ``d <= 0`` (no roll damping); ``k - K_vdot g <= 0``
    (the reduced model (26) has no restoring, alpha2 <= 0); ``A2 <= 0`` or ``A1 <= 0`` in any dataset
    (22), (16); any non-finite value.
    """
    why = []
    if not np.all(np.isfinite(theta)):
        return ["non-finite estimate"]
    k, A_x, d, K_r, K_v, K_d, z_f, m, zm = theta
    if m <= 1e-6 * known.M:
        why.append("m <= 0 (or vanishing)")
    if abs(zm) > 10.0:
        why.append("|zm_bar| > 10 m")
    if A_x <= 0:
        why.append("A_x <= 0")
    if d <= 0:
        why.append("d <= 0")
    if k - K_v * known.g <= 0:
        why.append("k - K_vdot g <= 0")
    t = roll_terms(theta, known, list(conds))
    if np.any(t["A2"] <= 0):
        why.append("A2 <= 0")
    if np.any(t["A1"] <= 0):
        why.append("A1 <= 0")
    return why


def implausible_identifiable(theta: np.ndarray, known: KnownParams, conds=(NOMINAL, CALIBRATION, LOADED),
                             std: dict | None = None) -> list[str]:
    """Implausibility judged on what the data determine: the rule of :func:`estimate_mass_cm`'s flag.

    The datasets determine the discrete coefficients ``g_i`` (35) of every dataset, hence its continuous
    coefficients (26) ``alpha1 = d/A2``, ``alpha2 = kp/A2``, ``beta1 = -B/A2``, and (z_f known or with a
    prior) ``m``, ``zm_bar`` and ``rho`` (:mod:`shipid.methods.masscm.identifiability`); they do not
    determine the split of ``A2`` into ``A_x`` and ``K_vdot z_s`` or of ``kp`` into ``k`` and ``K_vdot g`` well
    (finite-sample IV bias of K_vdot under sensor noise, module docstring "Known limitations"). Flagged when
    any of:

    * a non-finite estimate;
    * ``m <= 1e-6 M`` with its ±2-std interval also there (``std["m"]``; the point alone without a std);
    * ``|zm_bar| > 10 m`` beyond two of its standard errors (degenerate, load moment ~ 0);
    * the identified roll mode of any dataset is not that of a ship: the closed-loop roll equation (18),
      ``A1 phi'' + d phi' + k1 phi = ...`` with ``A1 = A2 + B z_s``, ``k1 = kp + B g``, divided by ``A2``:
      ``A1/A2 = 1 - beta1 z_s``, ``d/A2 = alpha1``, ``k1/A2 = alpha2 - beta1 g`` must all be positive
      (a stable, damped roll mode with restoring). These ratios are functions of ``g_i`` alone.

    The physical conditions on the nuisance split (``A_x, d, k - K_vdot g, A1, A2 > 0`` of
    :func:`implausible_reasons`, the Table-3 study's rule) are reported apart (``diagnostics
    ["nuisance_outside_physical"]``), not as a flag on the estimate of m.
    """
    std = std or {}
    if not np.all(np.isfinite(theta)):
        return ["non-finite estimate"]
    m, zm = theta[I_M], theta[I_ZM]
    sm, sz = float(std.get("m", 0.0)), float(std.get("zm_bar", 0.0))
    sm = sm if np.isfinite(sm) else 0.0
    sz = sz if np.isfinite(sz) else 0.0
    why = []
    if m + 2 * sm <= 1e-6 * known.M:
        why.append("m <= 0 (or vanishing) beyond 2 std")
    if abs(zm) - 2 * sz > 10.0:
        why.append("|zm_bar| > 10 m beyond 2 std")
    t = roll_terms(theta, known, list(conds))
    A2 = t["A2"]
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = {"A1/A2": t["A1"] / A2, "d/A2": t["d"] / A2, "k1/A2": t["k1"] / A2}
    for name, v in ratios.items():
        good = np.isfinite(v) & (v > 0)
        if not good.all():
            bad = [c for c, g in zip(conds, good) if not g]
            why.append(f"identified roll mode not physical ({name} <= 0 in {', '.join(sorted(set(bad)))})")
    return why


_MARKED = {"m": "estimated", "zm_bar": "estimated", "rho": "derived"}   # status before mark


@dataclass(frozen=True)
class Judgement:
    """The plausibility of one estimate (:func:`judge`).

    ``reasons``: why it is implausible (:func:`implausible_identifiable`; empty: plausible); ``nuisance``: the
    physical conditions of :func:`implausible_reasons` that the nuisance split violates (reported, not a flag);
    ``refined``: the estimate is a refinement's (the nuisance line says so) rather than Algorithm 1's.
    """

    reasons: list = field(default_factory=list)
    nuisance: list = field(default_factory=list)
    refined: bool = False

    @property
    def implausible(self) -> bool:
        return bool(self.reasons)

    def warnings(self) -> list[str]:
        """The warning lines of this judgement (none, or one: the flag, else the nuisance split)."""
        if self.reasons:
            return ["implausible solution: " + ", ".join(self.reasons)]
        if self.nuisance:
            return ["nuisance coefficients outside their physical range (" + ", ".join(self.nuisance)
                    + _NUISANCE_TAIL[self.refined]]
        return []

    def diagnostics(self) -> dict:
        """``implausible``, ``implausible_reasons``, ``nuisance_outside_physical`` of a result's diagnostics."""
        return {"implausible": self.implausible, "implausible_reasons": list(self.reasons),
                "nuisance_outside_physical": list(self.nuisance)}

    def _why(self) -> str:
        return "implausible solution (" + ", ".join(self.reasons) + "): not an estimate of the load"

    def mark(self, estimates: dict) -> dict:
        """``estimates`` (name -> :class:`~shipid.result.Estimate`) with ``m, zm_bar, rho`` labelled "not
        determined" (the reasons first in their notes) when implausible: an implausible solution is not an
        estimate of the load. A copy; unchanged when plausible."""
        est = dict(estimates)
        if self.reasons:
            why = self._why()
            for n in _MARKED:
                e = est[n]
                est[n] = replace(e, status="not determined", note=f"{why}; {e.note}" if e.note else why)
        return est

    def unmark(self, estimates: dict) -> dict:
        """The inverse of :meth:`mark`: ``m, zm_bar, rho`` that this judgement labelled get back the status
        :func:`~shipid.methods.masscm.assemble.to_result` gives them (``m, zm_bar`` estimated, ``rho`` derived)
        and their notes without the reasons. A copy; entries this judgement did not label are unchanged."""
        est = dict(estimates)
        if self.reasons:
            why = self._why()
            for n, status in _MARKED.items():
                e = est[n]
                if e.status == "not determined" and e.note.startswith(why):
                    est[n] = replace(e, status=status, note=e.note[len(why):].removeprefix("; "))
        return est


def judge(theta: np.ndarray, known: KnownParams, conds, std: dict, *, refined: bool = False) -> Judgement:
    """Judge the estimate ``theta`` of (30) (all nine, ``z_f`` included) of the datasets ``conds``:
    :func:`implausible_identifiable` with the standard errors ``std`` (``m``, ``zm_bar``) for the flag and
    :func:`implausible_reasons` (less "non-finite estimate", which the flag already says) for the nuisance split."""
    reasons = implausible_identifiable(theta, known, conds, std)
    nuisance = [w for w in implausible_reasons(theta, known, conds) if w != "non-finite estimate"]
    return Judgement(reasons, nuisance, refined)


def rho_of(theta: np.ndarray, known: KnownParams) -> float:
    """Moment ratio ``rho = m z_m / (m_c z_c)`` with z measured from the centre of rotation (24)."""
    z_f, m, zm = theta[I_ZF], theta[I_M], theta[I_ZM]
    return m * (zm + z_f) / (known.m_c * (known.zc_bar + z_f))


def dm_dzf(theta: np.ndarray, known: KnownParams) -> float:
    """Slope of the exact-fit family ``m(z_f) = rho m_c (zc_bar + z_f)/(zm_bar + z_f)`` at the estimate."""
    z_f, zm = theta[I_ZF], theta[I_ZM]
    rho = rho_of(theta, known)
    return rho * known.m_c * (zm - known.zc_bar) / (zm + z_f) ** 2


__all__ = ["implausible_reasons", "implausible_identifiable", "Judgement", "judge", "rho_of", "dm_dzf"]
