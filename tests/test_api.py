"""shipid.identify / validate / simulate: the Python face runs each method as the method's own function."""

import numpy as np
import pytest

import shipid
from shipid.errors import InputError
from shipid.methods.ebm import estimator as ebm
from shipid.methods.masscm.estimator import estimate_mass_cm
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import simulate_datasets
from shipid.vessels import load_vessel


def test_public_names():
    for name in ("identify", "validate", "simulate", "read_trial", "Trial", "Result", "load_vessel"):
        assert name in shipid.__all__ and callable(getattr(shipid, name))
    assert shipid.simulate.manoeuvres.run_manoeuvre    # the subpackage is still there
    assert set(shipid.METHODS) == {"mass-cm", "dp", "ebm", "mmg"}


def test_identify_mass_cm_equals_the_method():
    d = simulate_datasets("fishing-vessel", seed=3)
    known = KnownParams.from_vessel("fishing-vessel")
    z_f = float(load_vessel("fishing-vessel").value("general", "z_f"))
    res = shipid.identify("mass-cm", {k: d[k] for k in ("nominal", "calibration", "loaded")}, known=known, z_f=z_f)
    ref = estimate_mass_cm(list(d.items()), known, z_f=z_f, init="linear")
    assert res.method == "mass-cm"
    for k, e in ref.estimates.items():
        assert res.estimates[k].value == e.value
        assert res.estimates[k].std == e.std or (np.isnan(e.std) and np.isnan(res.estimates[k].std))


def test_identify_ebm_equals_the_method_and_is_thread_count_free():
    tr = shipid.simulate("esso-osaka", "zigzag-20", duration=200.0, noise=True, seed=4)
    res = shipid.identify("ebm", [tr], vessel="esso-osaka")
    ref = ebm.identify([tr], "esso-osaka")
    assert res.estimates["Y_v"].value == ref.estimates["Y_v"].value
    assert np.isfinite(res.estimates["N_r"].std)


def test_identify_refuses_what_it_cannot_do():
    with pytest.raises(InputError, match="unknown method"):
        shipid.identify("kalman", [])
    with pytest.raises(InputError, match="no azimuth trials"):
        shipid.identify("dp", {"surge": ["a.csv"], "sway-yaw": ["b.csv"]})
    with pytest.raises(InputError, match="known= is required"):
        shipid.identify("mass-cm", {"nominal": "a", "calibration": "b", "loaded": "c"})
    with pytest.raises(InputError, match="'kalman' result cannot be validated"):
        shipid.validate(shipid.Result(method="kalman", estimates={}), "x.csv")
