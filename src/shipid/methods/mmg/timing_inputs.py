"""Time offsets of the input channels (rudder angle, propeller rate, relative wind) against the position clock.

After :func:`shipid.methods.mmg.timing.retime` the heading, body velocities and yaw rate of a
run are on the position's clock; the inputs are not moved. If the rudder angle is logged
``τ_δ`` late, every predicted yaw response starts ``τ_δ`` early relative to the measured one
(and the other way round); the same for the propeller rate in surge and for the wind.

Estimate (:func:`estimate_input_lags`, training runs only, after the state re-timing): over a
grid of lags, least squares of the yaw acceleration ``ṙ`` (derivative of the re-timed yaw rate,
all columns smoothed by the centred moving average of :mod:`shipid.methods.mmg.timing`, which
delays nothing) on a per-run constant, ``u r``, ``u v``, ``|r| r``, ``|v| v`` and the lagged rudder
``δ(t + τ_δ)`` times ``u²``, ``u n`` and ``n²`` (the rudder normal force of the MMG model,
Yasukawa & Yoshimura 2015 eq. 27–31, in the rudder-inflow speed expanded in ``u`` and ``n``);
``τ_δ`` minimises the pooled residual sum of squares. The propeller rate ``τ_n`` likewise from
the surge acceleration ``u̇`` on a per-run constant, ``u|u|``, ``v r``, ``δ² u²`` and the lagged
``n²``, ``u n`` (thrust, eq. 34–36); the relative wind ``τ_w`` from the yaw equation with the
rudder at ``τ_δ`` and the air moment columns ``V_A² sin γ_A``, ``V_A² sin 2γ_A`` (Fujiwara et al.
1998) lagged. How well determined: the per-run argmin of each lag, its median and the standard
error ``sd / √runs`` across runs, reported with the pooled estimate.
:func:`retime_inputs` advances the input channels by the offsets, ``δ'(t) = δ(t + τ_δ)``, drops
the samples that would need extrapolation at either end, and adds one repair line.

Decision rule (written before any lag was estimated and before any CV score was computed)
----------------------------------------------------------------------------------------
Score: the 4-fold output-error CV of :func:`shipid.methods.mmg.study_ext2.cv_retimed` on the
32 training runs of the 9-run split (same folds, same
:class:`~shipid.methods.mmg.output_error.OEConfig`, same base candidate
:func:`shipid.methods.mmg.candidates_ext2.base_candidate`); in each fold the state offsets AND
the input offsets come from that fold's own training runs. Base: the same CV with the input
offsets zero (the current re-timing), recomputed by the same code. The input re-timing is kept
only if all of the rules of :mod:`shipid.methods.mmg.candidates_ext2` hold:

1. pooled ``S(input-lagged) ≤ S(base) − 0.02``;
2. better in at least 3 of the 4 folds;
3. the mean paired fold difference below minus its standard error;

AND its pooled position RMS is not above the base's. One variant is scored (all estimated
input offsets together; no per-input subsets, no second grid), and its score is reported
whether or not it passes.
"""
