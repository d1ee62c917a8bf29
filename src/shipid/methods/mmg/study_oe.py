"""Esso Osaka held-out study on the 9-run split, with the output-error refinement chosen by training-run CV.

Split (:func:`heldout9_split`): the test runs are the union of both papers' test runs
(:data:`shipid.io.basins.SPLITS`, 8 runs) plus one random run — 9 runs; the other 32
runs of the data set are the training runs. The ninth run (:data:`NINTH`): ``"issue"``
(default) ``random_03-Aug-2020_11_04_37``, the split of issue 19, recognised by the
published set's figure the issue quotes (12.20° / 0.842 m: only this ninth run gives it;
the identified models were not evaluated to find it); ``"seeded"`` a draw with
:data:`RANDOM_SEED` from the random runs not among the eight (``random_06-Aug-2020_16_24_25_6``),
the split this study was first run on; ``"bench"`` the ninth run of
``benchmarks/bench_mmg_cv.py`` (``random_31-Jul-2020_14_52_18``).

Protocol, all on the 32 training runs before any test run is read:

1. the structure is chosen among the frozen candidates by the regression CV of
   :func:`shipid.methods.mmg.pipeline.select_structure` (``folds``-fold, 60-s restarted
   horizons, score RMS ψ/10° + RMS position/1 m);
2. :func:`cv_refinement` compares, on the same folds, the regression estimate with the
   regression estimate refined by output error
   (:mod:`shipid.methods.mmg.output_error`), each fitted without the fold's runs and
   scored on them; pooled RMS and the mean over left-out runs of their per-run RMS;
3. the final model is the chosen structure fitted on all 32 runs, refined when step 2
   says so (lower pooled score).

The held-out side (:func:`heldout9_evaluate`) then reads the 9 test runs once and
reports, per run and as the mean over runs of the per-run RMS over 60-s horizons
restarted every 60 s at 10 Hz, the identified and the published model.

Settings of the refinement tried by the same 4-fold CV on the 32 training runs (before
the held-out evaluation; score = pooled RMS ψ/10° + pooled RMS position/1 m; then pooled
RMS ψ [deg] / position [m]; then the mean over the 32 left-out runs of their RMS)::

    hull+rudder+thrust/nondimensional
      regression                                          2.000   12.20 / 0.779    9.80 / 0.799
      output error (OEConfig defaults)                    1.554    8.86 / 0.669    7.24 / 0.706
      ... Jacobian by Broyden updates                     1.589    9.04 / 0.684    7.37 / 0.716
      ... horizons weighted per run                       1.593    9.01 / 0.692    7.33 / 0.724
    hull+rudder+4-quadrant-propeller/nondimensional
      regression                                          1.988   12.01 / 0.787    9.64 / 0.807
      output error (OEConfig defaults)                    1.589    9.13 / 0.675    7.41 / 0.714
      ... astern-propeller polynomials refined too        1.614    9.20 / 0.694    7.65 / 0.735
    hull-only/nondimensional
      regression                                          2.276   13.88 / 0.888   11.34 / 0.879
      output error (OEConfig defaults)                    2.187   13.30 / 0.856   11.11 / 0.872

Up to 8 iterations instead of 4: on the first fold the relative-decrease test stops it
after 5, at a cost 0.04 % lower; not pursued. Freeing more coefficients (the astern
polynomials) lowers the training cost by 13–23 % and raises the CV error: over-fitting.

Result on the ``"seeded"`` split, computed once after the configuration was frozen (commit
14ab57f) with ``shipid study esso-osaka-heldout9`` (then the only split): the regression CV chose
``hull+rudder+4-quadrant-propeller/nondimensional`` (1.988), the refinement CV
``hull+rudder+thrust/nondimensional`` with output error (1.554); on the 9 test runs, mean
over runs of the 60-s restarted-horizon RMS, identified **8.22° / 0.655 m** against the
published set's 12.26° / 0.854 m. The target (≤ 6.5° / ≤ 0.55 m) is NOT met: the CV gain
of the refinement (mean over left-out training runs 9.80° / 0.799 m → 7.24° / 0.706 m)
did not carry over to the test runs in the same proportion. Per run (identified /
published, deg and m)::

    random_06-Aug-2020_16_24_25_3     8.20 / 0.417     8.93 / 0.450
    turn_14-Sep-2020_14_50_41         4.55 / 0.384    13.40 / 1.003
    zigzag_31-Jul-2020_14_10_05      13.01 / 0.614    12.22 / 0.573
    berthing_12-Nov-2020_11_49_21     9.84 / 0.299    15.18 / 0.503
    berthing_12-Nov-2020_13_21_03    12.64 / 1.091     8.31 / 1.078
    turn_14-Oct-2020_15_06_53         4.93 / 0.922    22.52 / 1.889
    zigzag_31-Jul-2020_13_42_53       4.75 / 0.835    14.40 / 1.055
    berthing_12-Nov-2020_11_38_50     7.32 / 0.776     6.06 / 0.614
    random_06-Aug-2020_16_24_25_6     8.77 / 0.557     9.29 / 0.519

For comparison only (computed after the result above, changing nothing): the regression
estimate of the same structure without the refinement gives 8.48° / 0.674 m on the
same 9 runs; the refinement is better on the turning runs and zig-zag 13_42_53 and worse
on zig-zag 14_10_05 (13.0 vs 4.2°) and berthing 11_38_50 (7.3 vs 1.0°) and 13_21_03.

On the ``"issue"`` split (``shipid study esso-osaka-heldout9``, the default; run once, same
frozen configuration; random_03-Aug-2020_11_04_37 was among the training runs of the CV
that compared the refinement settings above, so this split is not as clean as
``"seeded"``): the regression CV chose ``hull+rudder+thrust/nondimensional`` (2.010), the
refinement CV the same with output error (1.561; mean over left-out runs 9.81° / 0.822 m
→ 7.22° / 0.711 m); held-out mean over runs identified **8.18° / 0.637 m**, published
12.20° / 0.842 m (the issue's 12.20 / 0.842: the same split). Target NOT met.

Port/starboard terms (``asymmetry=True``, the default since; :mod:`shipid.methods.mmg.candidates_asym`).
Diagnosis from the 4-fold CV residuals of the training runs only (regression + output error,
``hull+rudder+thrust/nondimensional``): 27 of the 28 straight-running 60-s horizons (mean yaw
rate below 0.5°/s, before the turn) of the 13 training turning runs end with the predicted
heading to starboard of the measured one (+2 … +19°; rudder within a few degrees of zero, n ≈ 8–10 1/s):
a yaw moment at zero rudder that the low-speed model lacks; the random and zig-zag runs show
per-run heading drifts of either sign (−20 … +7° mean end error), which no constant term
removes. After the refinement CV of step 2, the candidate it ranks best is also scored with
the ahead-propeller side force/moment, a rudder neutral offset, or both (first written with the
variants of the best *regression* candidate; on the ``"seeded"`` split that is the 4-quadrant
one, whose variants, 1.574–1.579, did not reach the symmetric ``hull+rudder+thrust`` output-error
1.554: the variants belong to the candidate the refinement CV prefers; on the ``"issue"`` split
both rules pick the same base, so its choice and held-out score below are unchanged). Same 4-fold CV on the
32 training runs of the ``"issue"`` split (pooled score; pooled RMS ψ / pos; mean over left-out
runs ψ / pos)::

    hull+rudder+thrust/nondimensional  output error        1.561   8.84 / 0.677   7.22 / 0.711
    ... + prop-side (YP_n, NP_n)       output error        1.551   8.78 / 0.673   6.99 / 0.702  <- chosen
    ... + rudder-offset (YR_0, NR_0)   output error        1.555   8.78 / 0.677   7.07 / 0.713
    ... + both                         output error        1.556   8.74 / 0.682   7.09 / 0.722
    hull+rudder+4-quadrant-propeller/nondimensional  OE    1.583   9.00 / 0.683   7.35 / 0.714

The output-error horizon, tried on the base candidate before the held-out evaluation: 30 s
1.627, 120 s 1.596, against 1.561 at 60 s: kept at 60 s. Fitted on all 32 runs, NP_n =
−0.0037 ± 0.0013 (estimated), YP_n not determined. Held-out (read once, after this choice):
mean over the 9 runs **7.79° / 0.613 m** (published 12.20° / 0.842 m; before the port/starboard
terms 8.18° / 0.637 m). Target (≤ 6.5° / ≤ 0.55 m) NOT met. Rerun end to end with the final rule
(``shipid study esso-osaka-heldout9``): the same table, choice and 7.79° / 0.613 m. On the
``"seeded"`` split (``--ninth seeded``; its ninth run was a training run of the diagnosis above, so
this split is not clean) the same rule scores the variants of ``hull+rudder+thrust/nondimensional``
(output error 1.554): prop-side 1.557, rudder-offset 1.551 (chosen), both 1.562; held-out mean
over runs 7.70° / 0.623 m (published 12.26° / 0.854 m; before 8.22° / 0.655 m).

Surge, slipstream-rudder and wind terms (``surge=True``, the default since;
:mod:`shipid.methods.mmg.candidates_surge`, structure ``esso-lowspeed-ext``). Diagnosis from the
4-fold CV residuals of the training runs (the chosen ``+prop-side`` output-error model): the 60-s
position error is 0.3–0.8 m at n ≤ 10 1/s and 1.0–2.8 m in the four zig-zags at n ≈ 14–16 1/s;
pooled it is as much along-track (0.45 m) as cross-track (0.50 m), and in the fast zig-zags mostly
cross-track (heading errors 12–17°). After the asymmetry step the candidate ranked best so far is
scored with the variants of :data:`shipid.methods.mmg.candidates_surge.SURGE_TERMS`. Same 4-fold CV
on the 32 training runs of the ``"issue"`` split (output error; pooled score; pooled RMS ψ / pos;
mean over left-out runs ψ / pos; the regression rows in the commit message)::

    hull+rudder+thrust/nondimensional+prop-side           1.551   8.78 / 0.673   6.99 / 0.702
    ... + surge-hull (X_vv, X_rr)                         1.543   8.71 / 0.672   6.99 / 0.704
    ... + rudder-drag (XR_D)                              1.549   8.75 / 0.674   6.97 / 0.704
    ... + rudder-slipstream (XR_s, YR_s, NR_s)            1.569   8.88 / 0.682   7.14 / 0.709
    ... + surge-hull + rudder-slipstream                  1.565   8.85 / 0.680   7.15 / 0.712
    ... + surge-hull + rudder-drag + rudder-slipstream    1.571   8.88 / 0.683   7.15 / 0.716
    ... + wind-gain (XW_g, YW_g, NW_g)                    1.345   7.60 / 0.584   6.10 / 0.621  <- chosen
    ... + surge-hull + wind-gain                          1.354   7.56 / 0.598   6.17 / 0.638

(the wind gains were added to the list after the first five variants had been scored, before any
test run was read). Fitted on all 32 runs: YW_g = −0.31 ± 0.07, NW_g = −0.55 ± 0.08 (Fujiwara's
side force and yaw moment too large for this model), XW_g not determined, NP_n = −0.0018 ± 0.0008.
Held-out (read once, after this choice): mean over the 9 runs **7.12° / 0.556 m** (published
12.20° / 0.842 m; before these terms 7.79° / 0.613 m). Target (≤ 6.5° / ≤ 0.55 m) NOT met.
Rerun end to end with this rule (``shipid study esso-osaka-heldout9``): the same tables, choice and
7.12° / 0.556 m; 17.6 CPU-min (12 output-error CVs) with the reference simulation.

Bound on a per-run yaw-moment bias (training runs only, diagnosis, not part of the pipeline):
with each left-out training run's own ``NP_n`` fitted by output error on that run's own horizons
(in sample, so an upper bound on what a bias estimated from a run's data can give), the mean over
the 32 left-out runs goes from 7.22° / 0.711 m to 5.93° / 0.635 m: the heading part of the target
is within reach of a per-run moment, the position part is not (it is dominated by the fastest
zig-zags, n ≈ 15 1/s, 13_57_45 2.9 m, 13_14_21 1.4 m, 14_03_39 1.0 m even with the bias).

Timing repair (``retime=True``, the default since; :mod:`shipid.methods.mmg.timing`). On the 32
training runs the body velocities disagree with the position derivative by a sway error that
grows with the speed (``v − v_pos ≈ −0.68 U r``): the heading (0.9 s), the body velocities
(0.6 s) and the yaw rate (0.9 s) lag the position, in every class of run; a lever arm would give
a slope independent of the speed. Re-timing ψ, u, v, r onto the position clock (a data repair,
the same offsets for every run, estimated on training runs only) gives every restarted horizon
a consistent initial state; the heading error is then measured against the raw heading samples
0.9 s later, the position error against the same raw position samples. Decision rule of
the rule of ``docs/validation/mmg.md`` (written before the scores), 4-fold output-error CV of
the base ``hull+rudder+thrust/nondimensional+prop-side+wind-gain``, offsets estimated on each
fold's training runs (0.9 / 0.6–0.7 / 0.9 s in every fold); pooled score, per-fold scores,
pooled RMS ψ / pos, mean over left-out runs ψ / pos::

    base (as recorded)             1.345  0.966 1.502 1.403 1.370  7.60 / 0.584  6.10 / 0.621
    ... + rudder-yaw-inflow        1.342  0.971 1.485 1.413 1.365  7.58 / 0.584  6.13 / 0.617
    ... + prop-walk-J              1.357  0.977 1.510 1.397 1.412  7.62 / 0.595  6.26 / 0.636
    ... + wind-arm                 1.344  0.969 1.489 1.417 1.368  7.58 / 0.586  6.07 / 0.622
    base, runs re-timed            1.288  0.929 1.434 1.330 1.306  7.60 / 0.528  5.86 / 0.565  <- kept

(better in 4 of 4 folds, mean fold difference −0.060 against its SE 0.008; the three
``esso-lowspeed-ext2`` variants pass none of the three rules, so no union was scored). The study
then runs every step above on the re-timed training runs. End to end, training side only
(``shipid study esso-osaka-heldout9 --retime --train-only``; no test run read; 777 s user CPU,
33 min wall at a load of about 8, max RSS 414 MB): offsets 0.9 / 0.6 / 0.9 s; the regression CV
chose ``hull+rudder+4-quadrant-propeller/nondimensional`` (1.897); output error (pooled score;
pooled RMS ψ / pos; mean over left-out runs ψ / pos)::

    hull+rudder+4-quadrant-propeller/nondimensional       1.476   8.69 / 0.607   6.83 / 0.639
    hull+rudder+thrust/nondimensional                     1.454   8.52 / 0.602   6.68 / 0.633
    ... + prop-side                                       1.450   8.48 / 0.602   6.47 / 0.631
    ... + rudder-offset                                   1.447   8.43 / 0.604   6.49 / 0.639
    ... + prop-side + rudder-offset                       1.452   8.46 / 0.606   6.59 / 0.648
    ... + rudder-offset + surge-hull                      1.449   8.43 / 0.606   6.54 / 0.645
    ... + rudder-offset + rudder-drag                     1.447   8.43 / 0.605   6.49 / 0.640
    ... + rudder-offset + rudder-slipstream               1.462   8.52 / 0.610   6.61 / 0.642
    ... + rudder-offset + surge-hull + rudder-slipstream  1.460   8.49 / 0.611   6.65 / 0.647
    ... + rudder-offset + surge-hull + drag + slipstream  1.458   8.49 / 0.609   6.64 / 0.647
    ... + rudder-offset + wind-gain                       1.277   7.46 / 0.531   5.86 / 0.569  <- chosen
    ... + rudder-offset + surge-hull + wind-gain          1.296   7.54 / 0.542   5.90 / 0.583

(on the runs as recorded the same steps chose ``+prop-side+wind-gain``, 1.345, 7.60 / 0.584,
6.10 / 0.621; prop-side and rudder-offset are within 0.003 of each other in both). Fitted on
the 32 re-timed runs: YW_g = −0.35 ± 0.06, NW_g = −0.51 ± 0.09, NR_0 = −0.011 ± 0.004; XW_g and
YR_0 not determined. Held-out (read once, after this choice; ``shipid study esso-osaka-heldout9``, the
default ``--retime``; the identified model scored on the test runs re-timed by the training offsets, the
published model on the runs as recorded): mean over the 9 runs **7.09° / 0.527 m** (published 12.20° /
0.842 m; as recorded, before the repair, 7.12° / 0.556 m). Position target (≤ 0.55 m) met, heading
(≤ 6.5°) NOT met. 146 s user CPU, 2 min 13 s wall at a load of about 1, max RSS 392 MB (the compiled
row simulation of :mod:`shipid.models.mmg_kernels`; 1047 s CPU with the reference simulation).
Where the gain comes from (diagnosis after the choice, same folds): the base fitted and refined on
the runs as recorded but scored on its fold's re-timed left-out runs gives 1.288 (7.58 / 0.530;
5.92 / 0.566), as much as fitting on re-timed runs too: the gain is the consistent initial state
of each restarted horizon (the position part is on the same samples), not a different fit.

Input offsets (``input_lags=True``, the default since; :mod:`shipid.methods.mmg.timing_inputs`,
rule and table there). On the state-re-timed training runs, least squares of the yaw and surge
accelerations on the lagged inputs put the rudder angle 0.8 s behind the position clock
(per-run median 0.75 s, SE 0.06), the propeller rate −0.4 s (median −0.20, SE 0.18: not well
determined) and the wind at the 1.5-s end of the grid (not determined; the study prints a line).
4-fold output-error CV of the base, offsets from each fold's training runs: 1.288 → 1.248
(4 of 4 folds, pooled 7.60 / 0.528 → 7.30 / 0.518): kept. Training side end to end
(``shipid study esso-osaka-heldout9 --train-only``; no test run read; 134 s user CPU, 2 min 18 s
wall, max RSS 417 MB): the regression CV chose ``hull+rudder+4-quadrant-propeller/nondimensional``
(1.859); the output-error CV chose ``hull+rudder+thrust/nondimensional+rudder-offset+wind-gain``
again, 1.237 (pooled 7.22 / 0.515; mean over left-out runs 5.75 / 0.557), against 1.277 (7.46 /
0.531; 5.86 / 0.569) with the state re-timing alone. Held-out (read once, after this choice;
``shipid study esso-osaka-heldout9``, the defaults; 164 s user CPU, 2 min 32 s wall, max RSS 357 MB;
the test runs re-timed by the training offsets, states and inputs, for the identified model, the
published model scored on the runs as recorded): mean over the 9 runs **6.56° / 0.493 m** (published
12.20° / 0.842 m; 7.09° / 0.527 m with the state re-timing alone, 7.12° / 0.556 m as recorded).
Position target (≤ 0.55 m) met; heading (≤ 6.5°) NOT met, by 0.06°.

Input-offset grid up to 3 s (2026-12-04; rule and CV in :mod:`shipid.methods.mmg.timing_inputs`): the
wind offset is 1.8 s on all 32 training runs, inside the grid, so the study no longer prints the
grid-end line. ``shipid study esso-osaka-heldout9`` (the defaults; 162 s user CPU, 2 min 17 s wall):
the output-error CV chose the same candidate, 1.233 (pooled 7.15° / 0.518 m; mean over left-out runs
5.74° / 0.562 m). Held-out (read once after that choice): **6.51° / 0.489 m**, heading better than
the published model's on 9 of 9 runs. Heading target NOT met, by 0.01°.

Overlapping training horizons (2026-12-04, training runs only, no test run read; rule of
``docs/validation/mmg.md`` fixed before the scores): the chosen candidate refined on
60-s horizons restarted every 30 s (``OEConfig(stride=30.0)``, twice the shooting nodes, sandwich
clustered by run) against every 60 s, same 4-fold re-timed CV:
pooled score 1.2334 against 1.2335 (pooled 7.12° / 0.521 m against 7.18° / 0.515 m), 2 of 4 folds
better: no gain, not adopted; the held-out runs were not scored for it.

Wind-driven current (2026-12-06, training runs only, rule in ``docs/validation/mmg.md``
fixed before the scores): the runs moved into the water frame of a current ``c`` times the low-passed true
wind (deleted; ``docs/validation/mmg.md``), ``c`` 0.01-0.03, time constant 60 or 300 s, same 4-fold re-timed
CV of the chosen candidate. Best c = 0.01, τ = 60 s: 1.2295 against 1.2335, 2 of 4 folds better, gain 0.004
below the rule's 0.02: not adopted; 2-3 % make every fold worse (table in ``docs/validation/mmg.md``). The held-out runs
were not scored for it.

Reversed-propeller side force (2026-12-06, same CV; ``docs/validation/mmg.md``, rule
and diagnosis there: horizons with the propeller reversed 40 % of the time or more carry 40 % of the training
CV's heading error). Freeing its yaw-moment terms gives 1.2426, with the side-force terms too 1.2467,
against 1.2335: not adopted; the held-out runs were not scored for it.

Huber-weighted horizons (2026-12-06; ``OEConfig.robust``, the default since; rule, diagnosis and table in
``docs/validation/mmg.md``, scored on the target's own metric, the mean over left-out
runs: 1.124 → 1.102, 4 of 4 folds). The worst 25 of the 197 training-CV horizons carried 69 % of the heading
error's sum of squares; least squares bent the coefficients towards them. Training side end to end
(``shipid study esso-osaka-heldout9 --train-only``; 2 min 33 s wall on 2 cores with the rows integrated in
two threads, 4 min 8 s CPU): the regression CV chose ``hull+rudder+4-quadrant-propeller/nondimensional``
(1.813); the output-error CV chose ``hull+rudder+thrust/nondimensional+rudder-offset+wind-gain`` again, 1.218
(pooled 7.11° / 0.507 m; mean over left-out runs 5.63° / 0.546 m), against 1.233 with least squares.
Held-out (read once after that choice; ``shipid study esso-osaka-heldout9``, 2 min 31 s wall): mean over the
9 runs **6.498° / 0.492 m** (published 12.20° / 0.842 m; least squares 6.51° / 0.489 m). Per run (identified
ψ [deg] / position [m], published)::

    random_06-Aug-2020_16_24_25_3     7.82 / 0.285     8.93 / 0.450
    turn_14-Sep-2020_14_50_41         3.75 / 0.359    13.40 / 1.003
    zigzag_31-Jul-2020_14_10_05       8.91 / 0.457    12.22 / 0.573
    berthing_12-Nov-2020_11_49_21    12.34 / 0.332    15.18 / 0.503
    berthing_12-Nov-2020_13_21_03     6.80 / 0.858     8.31 / 1.078
    turn_14-Oct-2020_15_06_53         2.69 / 0.546    22.52 / 1.889
    zigzag_31-Jul-2020_13_42_53       7.02 / 0.860    14.40 / 1.055
    berthing_12-Nov-2020_11_38_50     1.97 / 0.479     6.06 / 0.614
    random_03-Aug-2020_11_04_37       7.19 / 0.255     8.77 / 0.415

Both targets (≤ 6.5°, ≤ 0.55 m) are met, the heading one by 0.002°: far less than any one modelling choice
moves it, on a split that has been read after each of seven adopted changes (8.18, 7.79, 7.12, 7.09, 6.56,
6.51, 6.50°), each chosen on the training runs first.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from shipid.io.basins import SPLITS, esso_dir, read_esso
from shipid.io.trial import Trial
from shipid.errors import InputError
from shipid.methods.mmg import estimator as R
from shipid.methods.mmg import output_error as OE
from shipid.methods.mmg import pipeline as P
from shipid.methods.mmg import timing as TM
from shipid.methods.mmg import timing_inputs as TI
from shipid.methods.mmg import validate as V
from shipid.methods.mmg.candidates_asym import asym_variants
from shipid.methods.mmg.candidates_surge import BASE_STRUCTURES as SURGE_BASES
from shipid.methods.mmg.candidates_surge import surge_variants
from shipid.models import mmg

#: Seed of the ``"seeded"`` draw of the ninth (random-manoeuvre) test run.
RANDOM_SEED = 19
#: The ninth test run of each named split (module docstring); ``"seeded"`` is drawn.
NINTH = {"issue": "random/random_03-Aug-2020_11_04_37.csv", "seeded": None,
         "bench": "random/random_31-Jul-2020_14_52_18.csv"}


def heldout9_split(root: Path | None = None, ninth: str = "issue") -> dict[str, list[str]]:
    """``{"train": 32 runs, "test": 9 runs}`` (module docstring), as paths relative to the data folder."""
    if ninth not in NINTH:
        raise InputError(f"unknown ninth-run choice '{ninth}' (choose from {', '.join(NINTH)})")
    d = esso_dir(root)
    allruns = sorted(str(p.relative_to(d)) for p in d.glob("*/*.csv"))
    test: list[str] = []
    for sp in ("miyauchi2022", "wakita2022"):
        test += [f for f in SPLITS[sp]["test"] if f not in test]
    rnd = [f for f in allruns if f.startswith("random/") and f not in test]
    test.append(NINTH[ninth] or rnd[int(np.random.default_rng(RANDOM_SEED).integers(len(rnd)))])
    return {"train": [f for f in allruns if f not in test], "test": test, "ninth": ninth}


def _scores(model: mmg.MmgModel, trials: Sequence[Trial], decimate: int) -> list[dict[str, float]]:
    """Per run: horizon count and squared-RMS of heading (deg) and position (m)."""
    out = []
    for tr in trials:
        h = V.validate(model, R.subsample(tr, decimate), horizon=60.0, windows=(), whole=False).horizons
        if h["count"]:
            out.append({"count": h["count"], "psi": h["psi"]["rms"], "pos": h["pos"]["rms"]})
    return out


def _summarise(rows: Sequence[dict[str, float]]) -> dict[str, float]:
    w = np.array([r["count"] for r in rows], float)
    out = {}
    for q in ("psi", "pos"):
        v = np.array([r[q] for r in rows])
        out[f"{q}_rms"] = float(np.sqrt(np.sum(w * v * v) / np.sum(w))) if np.all(np.isfinite(v)) else float("inf")
        out[f"{q}_mean_of_runs"] = float(np.mean(v))
    out["score"] = R.horizon_score({"psi": out["psi_rms"], "pos": out["pos_rms"]})
    out["runs"] = len(rows)
    return out


#: Per-run horizon counts and RMS of a model on runs, and their pooled summary (public names of the two helpers).
horizon_rows = _scores
summarise_rows = _summarise


def cv_refinement(trials: Sequence[Trial], runs: Sequence[R.SmoothedRun], prior: mmg.MmgModel,
                  candidates: Sequence[str], *, folds: int = 4, decimate: int = 2,
                  oe_config: OE.OEConfig = OE.OEConfig(), pool: Mapping[str, Mapping] | None = None,
                  progress: Callable[[str], None] | None = None, per_fold: bool = False) -> dict[str, dict[str, Any]]:
    """``folds``-fold CV over the TRAINING runs of each candidate, regression vs regression + output error.

    Returns ``{candidate + "/regression" | "/output-error": summary}`` with the pooled RMS
    (``psi_rms`` deg, ``pos_rms`` m), the CV ``score`` and the mean over left-out runs of
    their per-run RMS (``*_mean_of_runs``). ``pool``: where the candidate names are looked up
    (default :data:`shipid.methods.mmg.candidates.CANDIDATES` of the prior's structure).
    ``per_fold``: each summary also has ``"fold_scores"``, the score of each fold's left-out runs pooled.
    """
    say = progress or (lambda s: None)
    cands = R.CANDIDATES[prior.structure] if pool is None else pool
    groups = R.fold_groups(len(runs), folds)
    rows: dict[str, list] = {}
    fold_rows: dict[str, list] = {}
    for cname in candidates:
        cprior, free = R.apply_candidate(prior, cands[cname])
        cfg = R.candidate_config(R.FitConfig(), cands[cname])
        for gi, g in enumerate(groups):
            tr_idx = [i for i in range(len(runs)) if i not in g]
            f = R.fit([runs[i] for i in tr_idx], cprior, free, cfg)
            test = [trials[i] for i in g]
            f2, oe = OE.refined_fit(f, [trials[i] for i in tr_idx], oe_config)
            for key, model in ((cname + "/regression", f.model), (cname + "/output-error", f2.model)):
                sc = _scores(model, test, decimate)
                rows.setdefault(key, []).extend(sc)
                fold_rows.setdefault(key, []).append(sc)
            say(f"cv {cname} fold {gi + 1}/{len(groups)}: output-error cost {oe.cost0:.4g} -> {oe.cost:.4g} "
                f"in {oe.iterations} iterations")
    out = {k: _summarise(v) for k, v in rows.items()}
    if per_fold:
        for k, v in fold_rows.items():
            out[k]["fold_scores"] = [_summarise(fr)["score"] for fr in v]
    return out


def heldout9_train(*, root: Path | None = None, ninth: str = "issue", folds: int = 4, refine_candidates: int = 2,
                   oe_config: OE.OEConfig = OE.OEConfig(), asymmetry: bool = True, surge: bool = True,
                   retime: bool = True, input_lags: bool = True,
                   progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Training side (module docstring, steps 1–3). Reads no test run.

    ``refine_candidates``: how many of the best regression candidates :func:`cv_refinement` compares.
    ``asymmetry``: then :func:`cv_refinement` also scores the port/starboard variants
    (:func:`shipid.methods.mmg.candidates_asym.asym_variants`) of the candidate (low-speed hull) that
    the first refinement CV ranks best, and the choice is among all.
    ``surge``: then it also scores the surge and slipstream-rudder variants
    (:func:`shipid.methods.mmg.candidates_surge.surge_variants`) of the candidate ranked best so far
    (if it is on a low-speed hull), and the choice is among all.
    ``retime``: before anything else, the channel offsets of :func:`shipid.methods.mmg.timing.estimate_lags`
    are estimated on the training runs and every training run is re-timed by them
    (:func:`shipid.methods.mmg.timing.retime`); the offsets are returned as ``"retime"`` and
    :func:`heldout9_evaluate` re-times the test runs by the same offsets.
    ``input_lags`` (with ``retime``): the offsets of the rudder angle, propeller rate and wind
    (:func:`shipid.methods.mmg.timing_inputs.estimate_input_lags` on the state-re-timed training runs)
    are added, and the inputs re-timed in the same step; the estimate with its per-run spread is
    returned as ``"retime_inputs"``.
    """
    say = progress or (lambda s: None)
    sp = heldout9_split(root, ninth)
    leak = set(sp["train"]) & set(sp["test"])
    if leak:
        raise ValueError(f"test runs in the training set: {sorted(leak)}")
    say(f"heldout9: reading {len(sp['train'])} training runs")
    trials = [read_esso(f, root) for f in sp["train"]]
    lags = ilags = None
    if retime:
        lags = TM.estimate_lags(trials)
        say(f"heldout9: channel offsets behind the position (training runs): heading {lags.psi:.2f} s, "
            f"velocities {lags.uv:.2f} s, yaw rate {lags.r:.2f} s")
        if input_lags:
            ilags = TI.estimate_input_lags([TM.retime(tr, lags) for tr in trials])
            lags = TI.with_inputs(lags, ilags)
            say(f"heldout9: input offsets (training runs; per-run median, se): rudder {ilags.delta:.2f} s "
                f"({ilags.delta_median:.2f}, {ilags.delta_se:.2f}), propeller {ilags.n:.2f} s ({ilags.n_median:.2f}, "
                f"{ilags.n_se:.2f}), wind {ilags.wind:.2f} s ({ilags.wind_median:.2f}, {ilags.wind_se:.2f})")
        trials = [TM.retime(tr, lags) for tr in trials]
        say("heldout9: training runs re-timed")
    prior = mmg.load_published("esso_osaka_3m", root)
    runs = [R.smooth_run(tr) for tr in trials]
    best, table = P.select_structure(trials, runs, prior, folds=folds)
    ranked = sorted(table, key=lambda c: table[c]["score"])[:refine_candidates]
    pool = dict(R.CANDIDATES[prior.structure])
    say(f"heldout9: regression CV chose '{best}'; output-error CV on {', '.join(ranked)}")
    ref = cv_refinement(trials, runs, prior, ranked, folds=folds, oe_config=oe_config, pool=pool, progress=say)
    if asymmetry:
        # the port/starboard variants of the candidate the first refinement CV ranks best (on the low-speed hull)
        base = next(k.rsplit("/", 1)[0] for k in sorted(ref, key=lambda k: ref[k]["score"])
                    if pool[k.rsplit("/", 1)[0]].get("structure", prior.structure) == "esso-lowspeed")
        extra = asym_variants(base, pool[base])
        pool.update(extra)
        say(f"heldout9: output-error CV of the port/starboard variants of '{base}'")
        ref.update(cv_refinement(trials, runs, prior, list(extra), folds=folds, oe_config=oe_config, pool=pool,
                                 progress=say))
    if surge:
        # the surge / slipstream-rudder variants of the candidate ranked best so far (on a low-speed hull)
        best = min(ref, key=lambda k: ref[k]["score"]).rsplit("/", 1)[0]
        if pool[best].get("structure", prior.structure) in SURGE_BASES:
            extra = surge_variants(best, pool[best])
            pool.update(extra)
            say(f"heldout9: output-error CV of the surge / slipstream-rudder variants of '{best}'")
            ref.update(cv_refinement(trials, runs, prior, list(extra), folds=folds, oe_config=oe_config, pool=pool,
                                     progress=say))
    choice = min(ref, key=lambda k: ref[k]["score"])
    structure, criterion = choice.rsplit("/", 1)
    res = P.identify(trials, prior, structure=structure, select=False, candidates=pool,
                     refine="output-error" if criterion == "output-error" else "none", oe_config=oe_config,
                     name="esso-osaka-3m-heldout9",
                     extra_provenance={"split": "heldout9", "test_runs_never_used": sp["test"]})
    return {"split": sp, "regression_cv": table, "refinement_cv": ref, "chosen": choice,
            "result": res.to_dict(), "retime": None if lags is None else lags.to_dict(),
            "retime_inputs": None if ilags is None else
            dict(ilags.to_dict(), not_determined=TI.at_bound(ilags))}


def heldout9_evaluate(trained: dict[str, Any], *, root: Path | None = None) -> dict[str, Any]:
    """Held-out side: identified and published models on the 9 test runs (10 Hz, 60-s horizons every 60 s).

    With ``trained["retime"]`` the identified model is scored on the test runs re-timed by those
    offsets (estimated on the training runs; heading error against the raw heading samples that
    much later), the published model on the runs as recorded.
    """
    ident = V.model_from_result(trained["result"])
    pub = mmg.load_published("esso_osaka_3m", root)
    test = [read_esso(f, root) for f in trained["split"]["test"]]
    lags = trained.get("retime")
    moved = test if not lags else [TM.retime(tr, TM.Lags(**lags)) for tr in test]
    out: dict[str, Any] = {"per_run": {}}
    for name, m, runs in (("identified", ident, moved), ("published", pub, test)):
        rows = _scores(m, runs, 1)
        out["per_run"][name] = dict(zip(trained["split"]["test"], rows))
        out[name] = _summarise(rows)
    return out


def format_heldout9(st: dict[str, Any]) -> str:
    """The two CV tables of :func:`heldout9_train` and the choice."""
    lines = [f"Esso Osaka 9-run held-out split ('{st['split'].get('ninth', 'issue')}'): "
             f"{len(st['split']['train'])} training runs, "
             f"test runs {', '.join(st['split']['test'])}",
             "  regression CV (training runs): candidate, score, pooled RMS psi [deg] / pos [m]"]
    for c, r in st["regression_cv"].items():
        lines.append(f"    {c:<56} {r['score']:7.3f} {r['psi_rms']:7.2f} {r['pos_rms']:7.3f}")
    lines.append("  refinement CV (training runs): pooled score, pooled RMS psi / pos, mean over left-out runs psi / pos")
    for c, r in st["refinement_cv"].items():
        mark = " <- chosen" if c == st["chosen"] else ""
        lines.append(f"    {c:<56} {r['score']:7.3f} {r['psi_rms']:7.2f} {r['pos_rms']:7.3f} "
                     f"{r['psi_mean_of_runs']:7.2f} {r['pos_mean_of_runs']:7.3f}{mark}")
    return "\n".join(lines)


def format_heldout9_test(st: dict[str, Any]) -> str:
    """The held-out table of :func:`heldout9_evaluate` (``st["heldout"]``)."""
    lines = []
    if "heldout" in st:
        ev = st["heldout"]
        lines.append("  held-out (read once, after the choice): run, identified psi [deg] / pos [m], published")
        for run in st["split"]["test"]:
            a, b = ev["per_run"]["identified"].get(run), ev["per_run"]["published"].get(run)
            if a and b:
                lines.append(f"    {run:<50} {a['psi']:7.2f} {a['pos']:7.3f}   {b['psi']:7.2f} {b['pos']:7.3f}")
        i, p = ev["identified"], ev["published"]
        lines.append(f"  mean over runs: identified {i['psi_mean_of_runs']:.2f} deg / {i['pos_mean_of_runs']:.3f} m, "
                     f"published {p['psi_mean_of_runs']:.2f} deg / {p['pos_mean_of_runs']:.3f} m")
    return "\n".join(lines)


__all__ = ["RANDOM_SEED", "NINTH", "heldout9_split", "horizon_rows", "summarise_rows", "cv_refinement",
           "heldout9_train", "heldout9_evaluate", "format_heldout9", "format_heldout9_test"]
