"""The series convention builders give plain JSON that survives Result JSON round trips."""

import json

import numpy as np
import pytest

from shipid.io.trial import Trial
from shipid.report.convention import contour, history, matrix, overlay, signal, table, trial_summary
from shipid.result import Estimate, Result


def test_builders_are_json_and_round_trip():
    t = np.arange(5) * 0.1
    series = {
        "overlays": {"r": overlay(t, np.sin(t), np.sin(t) + 0.01, "rad/s", label="yaw rate")},
        "histories": {"a": history(t, t, np.full(5, 0.1), "kg", true=0.2)},
        "signals": {"u": signal(t, {"smoothed": t}, "m/s", std={"smoothed": t * 0 + 0.1})},
        "matrices": {"c": matrix(np.eye(2), ["a", "b"])},
        "tables": {"k": table(["model", "κ"], [["full", np.float64(812.0)]], units=["", "-"])},
        "contours": {"cost": contour([0, 1, 2], [0, 1], np.zeros((2, 3)), x_label="m", x_unit="kg",
                                     y_label="z", y_unit="m", points=[{"x": np.float64(1), "y": 0, "label": "est"}])},
    }
    text = json.dumps(series)  # plain types only
    r = Result("dp", {"a": Estimate(1.0, 0.1, "kg")}, series=series)
    back = Result.from_json(r.to_json())
    assert back.series == json.loads(text)
    assert back.series["histories"]["a"]["true"] == 0.2
    assert back.series["overlays"]["r"]["kind"] == "fit"


def test_contour_shape_is_checked():
    with pytest.raises(ValueError, match="len\\(y\\)"):
        contour([0, 1, 2], [0, 1], np.zeros((3, 2)), x_label="m", x_unit="kg", y_label="z", y_unit="m")


def test_trial_summary():
    t = np.arange(0.0, 10.0001, 0.5)
    tr = Trial(t, {"r": np.zeros_like(t), "delta": np.zeros_like(t)}, meta={"source": "zz.csv", "vessel": "v"})
    s = trial_summary(tr, channels=["r"])
    assert s == {"name": "zz.csv", "channels": {"r": "rad/s"}, "n_samples": 21, "duration_s": 10.0,
                 "dt_s": 0.5, "t0_s": 0.0, "vessel": "v"}
