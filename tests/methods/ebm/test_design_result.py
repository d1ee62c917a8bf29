"""``design_result``: the D-optimality map (Yoon & Rhee 2003 §5.1.4, Fig. 7) as a shipid Result."""

import numpy as np
import pytest

from shipid.methods.ebm.design import design_result, prbs_grid
from shipid.result import Result


@pytest.fixture(scope="module")
def small_grid():
    # 2 x 3 grid of 200-s runs at dt = 2 s: six noise-free simulations, about a second
    return prbs_grid((10.0, 35.0), (30.0, 60.0, 105.0), duration=200.0, seeds=(0,), dt=2.0)


def test_result_carries_the_full_grid_and_marks_the_argmax(small_grid):
    res = Result.from_json(design_result(small_grid, command="shipid design prbs (test)").to_json())
    assert res.method == "ebm-design"
    c = res.series["contours"]["d_optimal"]
    z = np.asarray(c["z"])
    assert z.shape == (2, 3)                          # len(y) = amplitudes rows x len(x) = periods cols
    assert c["x"] == [30.0, 60.0, 105.0] and c["y"] == [10.0, 35.0] and c["paper"] == "Fig. 7"
    np.testing.assert_allclose(z, small_grid.sway)
    i, j = np.unravel_index(np.argmax(z), z.shape)
    assert c["points"][0]["x"] == c["x"][j] and c["points"][0]["y"] == c["y"][i]
    assert res.value("amplitude") == c["y"][i] and res.value("period") == c["x"][j]
    assert res.value("log10_det_sway") == pytest.approx(z.max())
    assert "grid spacing" in res.estimates["period"].note and res.estimates["period"].unit == "s"
    # the grid values as a table, one row per amplitude
    t = res.series["tables"]["d_optimal_grid"]
    assert [r[0] for r in t["rows"]] == [10.0, 35.0]
    np.testing.assert_allclose([r[1:] for r in t["rows"]], small_grid.sway)
    p = res.provenance
    assert p["command"] == "shipid design prbs (test)" and p["prbs_seeds"] == [0]
    assert p["settings"]["duration_s"] == 200.0 and p["settings"]["dt_s"] == 2.0


def test_optimum_on_the_grid_edge_is_warned(small_grid):
    res = design_result(small_grid)
    per = res.value("period")
    edge = per in (30.0, 105.0)
    assert any("edge of the grid" in w for w in res.diagnostics["warnings"]) == edge
