"""Diagnostic (not a timing benchmark): where the bias of K_vdot under sensor noise comes from.

Fishing vessel, three 300-s datasets per realisation (``SeedSequence([4242, i])``), z_f known, default noise
model, the reference path with the explicit instrument matrix (``compute="reference", explicit_moments=True``).
Per noise setting, Algorithm 1 is run twice on the same data:

* ``as is``: the IV moments of :func:`shipid.methods.masscm.moments.build_moments` (no intercept);
* ``intercept``: the same moments with the prefiltered instruments, regressand and regressors demeaned over
  the window used (IV with a constant in both the regressors and the instruments, by Frisch-Waugh): the
  constant a gyro bias ``b_1`` leaves in the equation error, ``(1 + alpha1 + alpha2) b_1`` (Linder et al. 2015,
  (9), (35)), is then projected out instead of meeting the finite-sample mean of the instruments.

Printed: mean ± spread of K_vdot (true 0.1), its mean reported std, K_r (true -0.5), K_delta (true -0.405), m
(true 0.4) with spread and reported std. The second variant is injected by replacing
``shipid.methods.masscm.iteration.build_moments`` in this process only; nothing in the package changes.

Usage:  python benchmarks/diag_masscm_kvdot_bias.py [SETTINGS=gyro_bias,sensors,both] [N=3] [NOISE_MODEL=auto]
        SETTINGS from: none, gyro_bias, acc_bias, gyro_noise, acc_noise, sensors, waves, both
        python benchmarks/diag_masscm_kvdot_bias.py --smoke     (gyro_bias, one realisation)
"""

import sys
import warnings

import numpy as np

import shipid.methods.masscm.iteration as iteration
from shipid.estimate.iv import iv_compress
from shipid.methods.masscm import moments
from shipid.methods.masscm.data import first_row
from shipid.methods.masscm.estimator import MassCMOptions, estimate_mass_cm
from shipid.models.roll_reduced import KnownParams
from shipid.models.roll_sim import NoiseSpec, simulate_datasets

SETTINGS = {"none": NoiseSpec(), "gyro_bias": NoiseSpec(gyro_bias=0.001), "acc_bias": NoiseSpec(acc_bias=0.01),
            "gyro_noise": NoiseSpec(gyro_std=0.002), "acc_noise": NoiseSpec(acc_std=0.02),
            "sensors": NoiseSpec(gyro_std=0.002, acc_std=0.02, gyro_bias=0.001, acc_bias=0.01),
            "waves": NoiseSpec(wave_roll_deg=0.5), "both": NoiseSpec.combined()}
_INTERCEPT = [False]


def _moments(prep, L, y_hats, a_hats, options):
    """The explicit-path moments of build_moments, optionally with everything demeaned over the window."""
    s = first_row(options)
    out = []
    for ds, Li, yh, ah in zip(prep, L, y_hats, a_hats):
        Z = moments.instruments(ds, yh, ah, ds.r_hat0, Li, options)
        yf, Pf = (Li.prefilter(ds.y)[s:], Li.prefilter(ds.Phi)[s:]) if Li is not None else (ds.y[s:], ds.Phi[s:])
        k = moments.transient_length(Li, yf.size, options)
        Z, yf, Pf = Z[k:], yf[k:], Pf[k:]
        if _INTERCEPT[0]:
            Z, yf, Pf = Z - Z.mean(0), yf - yf.mean(), Pf - Pf.mean(0)
        out.append(iv_compress(Z, yf, Pf))
    return out


def main():
    argv = sys.argv[1:] if "--smoke" not in sys.argv else ["gyro_bias", "1"]
    settings = (argv[0] if len(argv) > 0 else "gyro_bias,sensors,both").split(",")
    n = int(argv[1]) if len(argv) > 1 else 3
    nm = argv[2] if len(argv) > 2 else "auto"
    warnings.simplefilter("ignore")
    iteration.build_moments = _moments
    known = KnownParams.from_vessel("fishing-vessel")
    opts = MassCMOptions(noise_model=nm, compute="reference", explicit_moments=True)
    print(f"K_vdot bias, 3 x 300 s, z_f known, noise model {nm}, {n} realisations per setting (true K_vdot 0.1, "
          "K_r -0.5, K_delta -0.405, m 0.4)")
    for w in settings:
        data = [list(simulate_datasets("fishing-vessel", seed=np.random.SeedSequence([4242, i]), duration=300.0,
                                       noise=SETTINGS[w]).items()) for i in range(n)]
        for icpt in (False, True):
            _INTERCEPT[0] = icpt
            rs = [estimate_mass_cm(d, known, z_f=-0.028, noise_check=False, options=opts) for d in data]
            a = np.array([[r.value("K_vdot"), r.std("K_vdot"), r.value("K_r"), r.value("K_delta"), r.value("m"),
                           r.std("m")] for r in rs])
            sd = a.std(axis=0, ddof=1) if n > 1 else np.full(a.shape[1], np.nan)
            print(f"  {w:10s} {'intercept' if icpt else 'as is':9s}: K_vdot {a[:, 0].mean():.3f} ± {sd[0]:.3f} "
                  f"(reported std {a[:, 1].mean():.3f})  K_r {a[:, 2].mean():.3f}  K_delta {a[:, 3].mean():.3f}  "
                  f"m {a[:, 4].mean():.4f} ± {sd[4]:.4f} (reported std {a[:, 5].mean():.4f})", flush=True)


if __name__ == "__main__":
    main()
