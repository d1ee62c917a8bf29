"""The D-optimal PRBS: the reported optimum is the argmax of what was computed, the caption and the
comparison with seed 002's Fig. 7 (35°, 105 s) are computed from the map, never written in."""

import numpy as np
import pytest
from known.yoon_rhee2003 import FIG7_OPTIMUM

from shipid.methods.ebm.design import PAPER_FIG7, DesignGrid, design_result, paper_comparison, prbs_grid
from shipid.cli import main


def _grid(sway_seeds, amplitudes=(10.0, 20.0, 35.0), periods=(45.0, 105.0, 150.0)):
    W = np.asarray(sway_seeds, dtype=float)
    return DesignGrid(np.array(amplitudes), np.array(periods), W.mean(axis=2) - 1.0, W.mean(axis=2),
                      tuple(range(W.shape[2])), 1200.0, 1.0, 1.0, "esso-osaka", sway_seeds=W, surge_seeds=W - 1.0)


def _seeds(best, paper_offsets, base=-12.0):
    """Per-seed values: ``base`` everywhere, ``base + 1`` at ``best`` (i, j), the paper point 35/105 shifted."""
    W = np.full((3, 3, len(paper_offsets)), base)
    W[2, 1] = base + np.asarray(paper_offsets)
    W[best] = base + 1.0
    return W


def test_reported_optimum_is_the_argmax_and_the_caption_says_it_differs_from_fig7():
    g = _grid(_seeds((2, 0), [0.0, 0.05, -0.05, 0.02]))        # best at 35° / 45 s, 1.0 above the paper's point
    res = design_result(g)
    i, j = np.unravel_index(np.argmax(g.sway), g.sway.shape)
    assert res.estimates["amplitude"].value == g.amplitudes[i] == 35.0
    assert res.estimates["period"].value == g.periods[j] == 45.0
    assert res.estimates["log10_det_sway"].value == pytest.approx(g.sway.max())
    comp = res.diagnostics["paper_fig7"]
    assert comp["verdict"] == "differs" and comp["difference"] == pytest.approx(1.0 - 0.005)
    title = res.series["contours"]["d_optimal"]["title"]
    assert "optimum 35° / 45 s on this grid" in title and "not the paper's Fig. 7 optimum 35° / 105 s" in title
    assert "periods 45, 105, 150 s" in title


def test_comparison_within_the_realisation_spread():
    g = _grid(_seeds((1, 2), [2.0, -0.5, 1.5, -0.2]))          # 20° / 150 s best on average, noisy seeds
    comp = paper_comparison(g)
    assert comp["optimum"] == [20.0, 150.0]
    d = g.sway_seeds[1, 2] - g.sway_seeds[2, 1]
    assert comp["difference_se"] == pytest.approx(np.std(d, ddof=1) / 2.0)
    assert comp["verdict"] == "within 2 SE" and "does not distinguish" in comp["text"]


def test_comparison_when_the_optimum_is_the_paper_point_or_the_point_is_off_grid():
    g = _grid(_seeds((2, 1), [1.0, 1.0]))
    assert paper_comparison(g)["verdict"] == "same point"
    assert "is the paper's Fig. 7 optimum" in design_result(g).series["contours"]["d_optimal"]["title"]
    g2 = _grid(_seeds((0, 0), [0.0, 0.0]), periods=(45.0, 90.0, 150.0))
    c = paper_comparison(g2)
    assert c["verdict"] == "not on the grid" and c["log10_det_paper"] is None
    assert PAPER_FIG7 == FIG7_OPTIMUM


def test_simulated_grid_optimum_is_argmax_of_the_seed_means():
    g = prbs_grid((10.0, 35.0), (30.0, 105.0), duration=200.0, seeds=(0, 1), dt=2.0)
    assert g.sway_seeds.shape == (2, 2, 2)
    np.testing.assert_allclose(g.sway, g.sway_seeds.mean(axis=2))
    a, T, v = g.optimum("sway")
    i, j = np.unravel_index(np.argmax(g.sway_seeds.mean(axis=2)), (2, 2))
    assert (a, T, v) == (g.amplitudes[i], g.periods[j], g.sway[i, j])
    res = design_result(g)
    assert (res.estimates["amplitude"].value, res.estimates["period"].value) == (a, T)


def test_cli_period_range_syntax(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("SHIPID_NO_PROGRESS", "1")
    assert main(["design", "prbs", "--amplitudes", "10,35", "--periods", "30:105:75", "--duration", "200",
                 "--seeds", "1", "--dt", "2", "--json"]) == 0
    import json
    d = json.loads(capsys.readouterr().out)
    assert d["provenance"]["settings"]["periods_s"] == [30.0, 105.0]
    assert d["diagnostics"]["paper_fig7"]["on_grid"] is True
    assert main(["design", "prbs", "--periods", "30:10:5"]) == 2
    capsys.readouterr()
