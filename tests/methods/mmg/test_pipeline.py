"""``shipid.methods.mmg.pipeline``: the lines a result says about itself (undetermined, no straight-line equilibrium)."""

import pytest

from shipid.io import data_root
from shipid.methods.mmg.pipeline import undetermined_note


def test_undetermined_note_gives_the_numbers_that_decide():
    assert undetermined_note(-0.05, 0.01) == ""
    assert undetermined_note(0.958, 1.62) == ("; SE 1.62 not below |value| 0.958: not determined by the data "
                                             "(the value is kept in the model)")
    assert undetermined_note(-0.5, 0.5).startswith("; SE 0.5 not below |value| 0.5:")      # equal is not below
    assert undetermined_note(0.1, float("inf")).startswith("; SE not finite:")
    assert undetermined_note(0.1, float("nan")).startswith("; SE not finite:")


@pytest.mark.skipif(not (data_root() / "params").exists(), reason="shared data (Esso Osaka params) absent")
def test_equilibrium_line_says_when_the_identified_surge_model_cannot_run_straight():
    """The published Esso model runs straight at 10 rev/s (no line); with its resistance turned into thrust
    (X_0F, X_0A > 0) and the propeller's thrust cut it has no equilibrium below Froude number 3, and the line
    says so and names the propeller rate."""
    from shipid.methods.mmg.pipeline import equilibrium_line
    from shipid.models import mmg

    d = mmg.load_published("esso_osaka_3m").to_dict()
    assert equilibrium_line(dict(d, training_conditions={"rps_ahead": 10.0})) is None
    assert equilibrium_line(dict(d, training_conditions={"rps_ahead": None})) is None
    assert equilibrium_line(d) is None
    bad = mmg.load_published("esso_osaka_3m").to_dict()
    bad["coefficients"] = dict(bad["coefficients"], X_0F=0.05, X_0A=0.05, X_vr=0.0)
    line = equilibrium_line(dict(bad, training_conditions={"rps_ahead": 10.0}))
    assert line is not None and line.startswith("implausible surge model") and "10 rev/s" in line
    assert "--speed" in line
