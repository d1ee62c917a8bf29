"""``shipid study mmg-covariance {kvlcc2,esso}``: which parameter covariance is honest on real runs.

The split-half check of :func:`shipid.methods.mmg.covariance.split_half_z` on the training
runs of the frozen studies (KVLCC2: the ten HSVA training zig-zags, candidate
``full/symmetric-gamma_R``; Esso: the 35 Wakita-split training runs, candidate
``hull+rudder+thrust/nondimensional``, the ones their studies chose); no held-out run is read.
"""

from __future__ import annotations

import click

from shipid.cli import CONTEXT, study
from shipid.cli._common import emit, out_options

_CASES = {"kvlcc2": ("yasukawa2015", "full/symmetric-gamma_R"),
          "esso": ("esso-lowspeed", "hull+rudder+thrust/nondimensional")}


@study.command("mmg-covariance", context_settings=CONTEXT)
@click.argument("case", type=click.Choice(sorted(_CASES)))
@click.option("--splits", default=10, show_default=True, type=int, help="Random half-splits of the runs.")
@click.option("--seed", default=0, show_default=True, type=int, help="Seed of the splits and bootstraps.")
@click.option("--draws", default=100, show_default=True, type=int, help="Bootstrap resamples per half.")
@out_options(json_help="Print the table as JSON.")
def mmg_covariance_cmd(case, splits, seed, draws, as_json, out, force):
    """Which MMG parameter covariance is honest: split-half check on real training runs.

    The runs are split at random into halves, each fitted, and every coefficient's
    difference divided by the std each covariance (ridge, HAC, run bootstrap) states:
    RMS z near 1 is honest."""
    from shipid.io.basins import SPLITS, read_esso, read_kvlcc2
    from shipid.methods.mmg import covariance as C
    from shipid.methods.mmg import estimator as R
    from shipid.methods.mmg.candidates import CANDIDATES, apply_candidate, candidate_config
    from shipid.methods.mmg.study import KVLCC2_TRAIN
    from shipid.models import mmg

    structure, cname = _CASES[case]
    if case == "kvlcc2":
        files, trials, prior = list(KVLCC2_TRAIN), [read_kvlcc2(f) for f in KVLCC2_TRAIN], "kvlcc2_hsva"
    else:
        files = list(SPLITS["wakita2022"]["train"])
        trials, prior = [read_esso(f) for f in files], "esso_osaka_3m"
    cand = CANDIDATES[structure][cname]
    cp, free = apply_candidate(mmg.load_published(prior), cand)
    runs = [R.smooth_run(t) for t in trials]
    z = C.split_half_z(runs, cp, free, candidate_config(R.FitConfig(), cand), splits=splits, seed=seed, draws=draws)
    payload = {"case": case, "candidate": cname, "runs": files, "splits": splits, "seed": seed, "draws": draws,
               "z": z}

    def text():
        click.echo(f"{case}: {len(runs)} training runs, candidate '{cname}', {splits} random half-splits, "
                   f"seed {seed}; z = (theta_A - theta_B) / sqrt(sd_A^2 + sd_B^2)")
        click.echo(f"  {'covariance':<14} {'RMS z':>7} {'median |z|':>11} {'n':>5}   (honest: RMS z ~ 1, "
                   "median |z| ~ 0.67)")
        for k, v in z.items():
            click.echo(f"  {k:<14} {v['rms_z']:7.2f} {v['median_abs_z']:11.2f} {v['n']:5d}")

    emit(payload, as_json=as_json, out=out, force=force, indent=1, text=text)
