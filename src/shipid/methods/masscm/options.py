"""Options and constants of Algorithm 1 of Linder et al. (2015): the tuning dataclass, the channels a
dataset needs and the default initial values of the nine parameters (30)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shipid.models.roll_reduced import THETA_NAMES

REQUIRED = ("p", "a_s", "r", "delta")


I_ZF, I_M, I_ZM = THETA_NAMES.index("z_f"), THETA_NAMES.index("m"), THETA_NAMES.index("zm_bar")


#: Default initial values (a rough, physically plausible guess; Table 3 shows the method tolerates much worse).
DEFAULT_THETA0 = np.array([10.0, 0.1, 0.2, -0.5, 0.1, -0.4, 0.0, 0.3, -0.15])


@dataclass(frozen=True)
class MassCMOptions:
    """Tuning of Algorithm 1 (defaults: §5 of the paper where it says, our choice otherwise)."""

    n_y: int = 16
    n_as: int = 16
    n_r: int = 16
    n_delta: int = 2
    arx_na: int = 4
    arx_nb: int = 5
    arma_na: int = 4
    arma_nc: int = 4
    prefilter: bool = True          # False: plain iterative IV without the ARMA prefilters (comparison)
    max_iter: int = 50
    min_iter: int = 2
    tol: float = 1e-5
    instruments: str = "lags"       # "lags": (45) with n_y, n_as, n_r, n_delta; "regressors": noise-free (37)
    transient_tol: float = 0.01      # prefilter start-up: drop samples until the slowest pole decays to this
    transient_max: float = 0.2       # ... but at most this fraction of the record
    noise_model: str = "auto"        # "auto" (= "bj"): AR(ar_order) of eps/(1 - c q^-2)^k with (c, k), k <= 2, chosen by
    #                                 the innovation likelihood among noise_bj.BJ_CANDIDATES (c = 0 is "ar"); "ar": AR(ar_order)
    #                                 of the residuals, prefilter = FIR A(q); "ar-structured": AR(ar_order) of
    #                                 eps/(1 - c q^-2), c = initial_c, L = A/(1 - c q^-2); "arma": structured ARMA;
    #                                 "bj": Box-Jenkins eps = (1 - c q^-2)^k / A(q) e, (c, k) with k <= 2 chosen by
    #                                 the innovation likelihood among noise_bj.BJ_CANDIDATES (see noise_bj)
    ar_order: int = 40
    zm_bound: float = 2.0           # |zm_bar| bound (m) of the search
    initial_c: float = 0.99         # first-iteration prefilter 1/(1 - c q^-2); 0 = the paper's L = 1
    cycle_after: int = 10           # (*) from this iteration on, not yet converged: steps (b)-(c) at the mean of
    #                                 the last four iterates instead of two (damps period-4 cycles); 0 = never
    explicit_moments: bool = False  # how (not what): True forms the instrument matrix Z of an IIR prefilter
    #                                 explicitly (the reference of filtered_lag_moments; O(n n_z^2), n x n_z memory)
    compute: str = "reference"      # how (not what): "reference" the numpy/scipy path; "fast" numba kernels (estimator)
    refine: str = "auto"            # "auto": refine (engine masscm.refine.auto_engine) only where the data show sensor
    #                                 noise and a wave structure (the rule of masscm.refine); "pem": always the
    #                                 maximum-likelihood refinement on the state-space model; "whittle": the same in
    #                                 the frequency domain (auto's engine beyond 10 min); "none": Algorithm 1 alone


__all__ = ["REQUIRED", "I_ZF", "I_M", "I_ZM", "DEFAULT_THETA0", "MassCMOptions"]
