"""The asymmetric MMG structure and the KVLCC2 large-angle cross-validation (shipid.methods.mmg.extrapolation)."""

import numpy as np
import pytest

from shipid.io import data_root
from shipid.methods.mmg import candidates as C
from shipid.methods.mmg import extrapolation as E
from shipid.methods.mmg import study as S
from shipid.models import mmg


def need(sub):
    root = data_root()
    if root is None or not (root / sub).is_dir():
        pytest.skip(f"shared data ({sub}/) not found (set SHIPID_DATA)")


def _state(k=50):
    rng = np.random.default_rng(5)
    return (1.1 + 0.05 * rng.standard_normal(k), 0.05 * rng.standard_normal(k), 0.01 * rng.standard_normal(k),
            np.deg2rad(rng.uniform(-35, 35, k)), np.full(k, 10.2))


def test_asymmetric_structure_reduces_to_the_standard_mmg_and_adds_its_terms():
    need("params")
    prior = mmg.load_published("kvlcc2_hsva")
    cand = E.candidates()["full+asym"]
    asym, _ = C.apply_candidate(prior, cand)
    assert asym.structure == "yasukawa2015-asym"
    assert all(asym.coef[c] == 0.0 for m in E.ASYM for c in E.ASYM[m])
    u, v, r, d, n = _state()
    f0 = mmg.forces(prior, u, v, r, d, n)
    f1 = mmg.forces(asym, u, v, r, d, n)
    for a, b in zip(f0, f1):
        assert np.allclose(a, b, rtol=1e-13, atol=0)
    # a propeller side force ∝ thrust, and a rudder force that changes sign with the side
    b = mmg.basis(asym, u, v, r, d, n)
    T = b["aux"]["T"]
    H = b["Y"][0]
    names = mmg.COEFS["yasukawa2015-asym"]["Y"]
    assert np.allclose(H[:, names.index("YP_T")], T)
    assert np.allclose(H[:, names.index("YR_asym")], np.sign(d) * H[:, names.index("YR_gain")])


def test_swapped_gamma_swaps_the_sides():
    need("params")
    prior = mmg.load_published("kvlcc2_hsva")
    p, _ = C.apply_candidate(prior, E.candidates()["full/swapped-gamma_R"])
    assert p.particulars["gamma_R_minus"] == prior.particulars["gamma_R_plus"]
    assert p.particulars["gamma_R_plus"] == prior.particulars["gamma_R_minus"]


def test_extra_candidates_leave_the_frozen_configuration_alone():
    E.candidates()
    assert S.config_fingerprint() == S.FROZEN_FINGERPRINT
    assert not set(E.TRAIN + E.VALIDATE) & set(S.KVLCC2_TEST)


@pytest.mark.slow
def test_large_angle_cv_reads_no_held_out_run(monkeypatch):
    need("kvlcc2_hsva")
    read = E.read_kvlcc2
    seen = []

    def spy(name, root=None):
        seen.append(name)
        return read(name, root)

    monkeypatch.setattr(E, "read_kvlcc2", spy)
    cands = {k: v for k, v in E.candidates().items() if k in ("linear-hull+rudder/symmetric-gamma_R", "full+asym")}
    table = E.cross_validate(cands)
    assert set(seen) == set(E.TRAIN + E.VALIDATE)
    for row in table.values():
        assert np.isfinite(row["score"]) and row["psi_rms_deg"] > 0
