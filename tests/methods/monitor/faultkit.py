"""Sensor faults injected into a simulated monitor stream (:mod:`shipid.simulate.masscm_stream`)."""

import numpy as np

CH = ("p", "a_s", "r", "delta")


def inject(stream, rng, *, gap_short=150.0, nan_burst=200.0, clock_jump=250.0, frozen=320.0, gap_long=450.0,
           n_spikes=10, dup=0.01, swap=0.01, spike_window=(130.0, 600.0)):
    """Arrays ``t, X (n, 4)`` of ``stream`` with the faults of the monitor issue, and what was injected.

    Gap 0.5 s at ``gap_short``; NaN burst of 2 s in p at ``nan_burst``; a +30-s clock jump at ``clock_jump``;
    roll rate frozen for 60 s from ``frozen``; gap of 120 s from ``gap_long``; ``n_spikes`` 5-sigma spikes
    (sigma: the channel's std) on p, a_s, r; ``dup`` of the samples repeated, ``swap`` of them swapped with
    the next one. A time of None leaves that fault out."""
    t = np.asarray(stream.t, dtype=float).copy()
    X = np.column_stack([np.asarray(stream[c], dtype=float) for c in CH])
    sd = X.std(axis=0)
    keep = np.ones(t.size, dtype=bool)
    faults = []

    def idx(s):
        return int(np.searchsorted(t, s))
    if gap_short is not None:
        keep[idx(gap_short):idx(gap_short + 0.5)] = False
        faults.append(("gap", gap_short))
    if gap_long is not None:
        keep[idx(gap_long):idx(gap_long + 120.0)] = False
        faults.append(("gap", gap_long))
    if nan_burst is not None:
        X[idx(nan_burst):idx(nan_burst + 2.0), 0] = np.nan
        faults.append(("p", nan_burst))
    if frozen is not None:
        a = idx(frozen)
        X[a:idx(frozen + 60.0), 0] = X[a, 0]
        faults.append(("frozen", frozen))
    lo, hi = idx(spike_window[0]), idx(spike_window[1])
    clear = keep.copy()                     # spikes away from the other faults (2 s either side)
    for start, length in ((gap_short, 0.5), (gap_long, 120.0), (nan_burst, 2.0), (frozen, 60.0),
                          (clock_jump, 0.0)):
        if start is not None:
            clear[idx(start - 2.0):idx(start + length + 2.0)] = False
    cand = np.flatnonzero(clear[lo:hi]) + lo
    spikes = np.sort(rng.choice(cand, n_spikes, replace=False)) if n_spikes else np.array([], int)
    for j, i in enumerate(spikes):
        c = j % 3
        X[i, c] += 5.0 * sd[c] * rng.choice([-1.0, 1.0])
        faults.append(("spike", float(t[i])))
    if clock_jump is not None:
        t[idx(clock_jump):] += 30.0
        faults.append(("clock", clock_jump))
    t, X = t[keep], X[keep]
    n = t.size
    order = np.arange(n)
    sw = rng.choice(n - 2, int(swap * n), replace=False)
    for i in np.sort(sw):
        order[i], order[i + 1] = order[i + 1], order[i]
    order = list(order)
    dups = set(rng.choice(n, int(dup * n), replace=False).tolist())
    out = []
    for i in order:
        out.append(i)
        if i in dups:
            out.append(i)
    out = np.array(out)
    return t[out], X[out], faults
