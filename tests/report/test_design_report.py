"""The D-optimality map (Yoon & Rhee 2003 Fig. 7) in ``shipid report``: the full map of
``shipid design prbs --out`` and the captioned coarse preview of ``identify ebm --figures`` / the demo."""

import re

from shipid.methods.ebm.design import design_result, prbs_grid
from shipid.cli import main


def test_report_renders_the_design_map(tmp_path, capsys):
    res = design_result(prbs_grid((10.0, 35.0), (30.0, 105.0), duration=200.0, seeds=(0,), dt=2.0),
                        command="test")
    src = tmp_path / "design.json"
    res.write_json(src)
    out = tmp_path / "design.html"
    assert main(["report", str(src), "--out", str(out)]) == 0
    html = out.read_text(encoding="utf-8")
    figs = re.findall(r"<figure>.*?</figure>", html, re.S)
    fig7 = [f for f in figs if "Fig. 7" in f and "<img" in f]
    assert fig7, "no <img> captioned with Fig. 7"
    assert "data:image/png;base64," in fig7[0] and "amplitude × clock period" in fig7[0]
    assert "D-optimal PRBS input design" in html      # the method's own title, not the generic fallback


def test_coarse_map_caption_says_coarse_and_points_to_the_full_map():
    from shipid.methods.ebm.series import coarse_d_optimal

    c = coarse_d_optimal(amplitudes=(10.0, 35.0), periods=(30.0, 105.0), duration=200.0)
    assert c["paper"] == "Fig. 7"
    assert "COARSE" in c["title"] and "2 × 2 grid" in c["title"] and "200 s runs" in c["title"]
    assert "shipid design prbs --out" in c["title"] and "35° / 105 s" in c["title"]
    assert c["points"][0]["label"] == "coarse-grid optimum"
