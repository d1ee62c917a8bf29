"""The compiled Esso MMG simulation (shipid.models.mmg_kernels.rows_rk4_kernel) against the Python reference.

The compiled twin ``rows_rk4_kernel`` is checked against the package's one RK4
(:func:`shipid.numerics.integrate.rk4_propagate`) on the reference dynamics.

Reference: :func:`shipid.methods.mmg.cv_fast.simulate_rows` with ``compiled=False`` (RK4 of
:func:`shipid.methods.mmg.manoeuvres.rows_deriv`, i.e. :func:`shipid.models.mmg.basis`) and
:func:`shipid.models.mmg.simulate_batch` with ``compiled=False``. Rows are drawn to visit every branch
of the force model: ahead and astern propeller (n from −15 to 15 1/s, and exactly 0), forward and
backward surge, both rudder sides, low speed (U < 1e-5), and a true wind from any side. Agreement is
required to 1e-12 of each state's scale: the two differ only in the order of the coefficient sum
and in the last bits of atan2 / hypot / pow (numpy's SIMD versions against libm's), ~1e-16 per step.
"""

import numpy as np
import pytest

from shipid.io import data_root
from shipid.methods.mmg import cv_fast
from shipid.models import mmg, mmg_kernels
from shipid.models.mmg_esso_ext import EXT_COEFS

ROOT = data_root()
EXTRA = {"YP_n": -0.004, "NP_n": -0.002, "YR_0": 0.01, "NR_0": -0.005, "X_vv": -0.05, "X_rr": 0.02, "XR_D": 0.3,
         "XR_s": 0.2, "YR_s": -0.3, "NR_s": 0.25, "XW_g": 0.1, "YW_g": -0.3, "NW_g": -0.5}
CUBIC = {"R_0": 0.02, "X_vv": -0.04, "X_vr": 0.002, "X_rr": 0.01, "X_vvvv": 0.3, "Y_v": -0.3, "Y_r": 0.05,
         "Y_vvv": -1.5, "Y_vvr": 0.4, "Y_vrr": -0.4, "Y_rrr": 0.01, "N_v": -0.1, "N_r": -0.05, "N_vvv": -0.02,
         "N_vvr": -0.3, "N_vrr": 0.05, "N_rrr": -0.01}


@pytest.fixture(scope="module")
def published():
    if ROOT is None or not (ROOT / "params").is_dir():
        pytest.skip("shared data (params/) not found (set SHIPID_DATA)")
    return mmg.load_published("esso_osaka_3m")


def _model(pub, structure):
    coef = dict(pub.coef)
    coef.update(CUBIC if structure == "esso-cubic-hull" else EXTRA)
    return mmg.MmgModel(structure, pub.particulars, coef, name=structure)


def _rows(seed, B=96, L=41):
    rng = np.random.default_rng(seed)
    x0 = np.zeros((B, 6))
    x0[:, 2] = rng.uniform(-np.pi, np.pi, B)
    x0[:, 3] = rng.uniform(-0.3, 0.8, B)
    x0[:, 4] = rng.uniform(-0.15, 0.15, B)
    x0[:, 5] = rng.uniform(-0.1, 0.1, B)
    x0[:4, 3:] = 0.0                                          # at rest: U < 1e-5
    U = np.empty((B, L, 4))
    side = np.sign(np.sin(np.arange(L) / 7.0 + rng.uniform(0, 6, (B, 1))))
    U[..., 0] = np.deg2rad(rng.uniform(-35, 35, (B, 1))) * side
    U[..., 1] = rng.uniform(-15, 15, (B, 1)) + 0.0 * U[..., 0]
    U[::9, :, 1] = 0.0                                        # propeller stopped
    U[..., 2] = rng.uniform(0, 3, (B, 1))
    U[..., 3] = rng.uniform(0, 2 * np.pi, (B, 1)) + 0.02 * np.arange(L)
    h = np.full((B, L - 1), 0.1) * rng.uniform(0.5, 2.0, (B, 1))
    return x0, U, h


@pytest.mark.parametrize("structure", sorted(mmg_kernels.CODES))
def test_compiled_rows_equal_the_reference(published, structure):
    model = _model(published, structure)
    x0, U, h = _rows(3)
    rng = np.random.default_rng(4)
    Th = {m: model.theta(m)[None] * (1 + 0.1 * rng.standard_normal((x0.shape[0], model.theta(m).size)))
          for m in mmg.MODES}
    a = cv_fast.simulate_rows(model, Th, x0, U, h)
    b = cv_fast.simulate_rows(model, Th, x0, U, h, compiled=False)
    fin = np.isfinite(b)
    assert np.array_equal(fin, np.isfinite(a))
    assert fin.mean() > 0.9                                   # the comparison is about finite predictions
    scale = np.max(np.abs(np.where(fin, b, 0.0)), axis=(0, 1))
    err = np.max(np.abs(np.where(fin, a - b, 0.0)), axis=(0, 1)) / scale
    assert np.all(err < 1e-12), err
    if structure == "esso-lowspeed-ext":
        assert len(EXT_COEFS["X"]) + 10 == model.theta("X").size


@pytest.mark.parametrize("substeps", [1, 3])
def test_simulate_batch_compiled_equals_reference(published, substeps):
    model = _model(published, "esso-lowspeed-ext")
    x0, U, _ = _rows(5, B=12, L=61)
    t = np.cumsum(np.r_[0.0, np.full(60, 0.1)])
    a = mmg.simulate_batch(model, t, x0, U, substeps=substeps)
    b = mmg.simulate_batch(model, t, x0, U, substeps=substeps, compiled=False)
    fin = np.isfinite(b)
    assert np.array_equal(fin, np.isfinite(a))
    scale = np.max(np.abs(np.where(fin, b, 0.0)), axis=(0, 1))
    assert np.all(np.max(np.abs(np.where(fin, a - b, 0.0)), axis=(0, 1)) / scale < 1e-12)


def test_diverging_rows_become_nan_at_the_same_step(published):
    """An unstable model (yaw damping of the wrong sign, 30x): both paths turn the row NaN at the same step."""
    model = _model(published, "esso-lowspeed").with_coef({"N_r": 30 * abs(published.coef["N_r"])})
    x0, U, _ = _rows(6, B=8, L=400)
    t = 0.2 * np.arange(400)
    a = mmg.simulate_batch(model, t, x0, U)
    b = mmg.simulate_batch(model, t, x0, U, compiled=False)
    first = lambda P: np.argmax(~np.all(np.isfinite(P), axis=-1), axis=1)   # noqa: E731
    assert np.any(~np.isfinite(b))
    np.testing.assert_array_equal(first(a), first(b))


def test_other_structures_use_the_reference(published):
    """A structure without a compiled copy (the standard MMG) is integrated by the reference loop."""
    if ROOT is None or not (ROOT / "params" / "kvlcc2_L7_mmg_shipmmg.yml").is_file():
        pytest.skip("KVLCC2 parameters not found")
    model = mmg.load_published("kvlcc2_L7")
    assert not mmg_kernels.supported(model.structure)
    t = 0.5 * np.arange(50)
    U = np.zeros((50, 4))
    U[:, 0], U[:, 1] = 0.2, 10.0
    x0 = np.array([[0, 0, 0, 1.0, 0, 0]])
    assert np.array_equal(mmg.simulate_batch(model, t, x0, U), mmg.simulate_batch(model, t, x0, U, compiled=False))


def test_threads_give_every_row_the_same_numbers(published, monkeypatch):
    """Rows are independent: a batch split over 1, 2 or 3 threads gives bit-identical predictions (the
    same seed gives the same result with any number of threads)."""
    model = _model(published, "esso-lowspeed-ext")
    x0, U, h = _rows(8, B=3 * mmg_kernels.MIN_ROWS_PER_THREAD + 5, L=31)
    rng = np.random.default_rng(9)
    Th = {m: model.theta(m)[None] * (1 + 0.05 * rng.standard_normal((x0.shape[0], model.theta(m).size)))
          for m in mmg.MODES}
    out = {}
    for n in ("1", "2", "3"):
        monkeypatch.setenv("SHIPID_THREADS", n)
        assert mmg_kernels.threads(x0.shape[0]) == int(n)
        out[n] = cv_fast.simulate_rows(model, Th, x0, U, h)
    assert np.array_equal(out["1"], out["2"], equal_nan=True) and np.array_equal(out["1"], out["3"], equal_nan=True)


def test_thread_count_follows_the_batch_and_the_environment(monkeypatch):
    monkeypatch.setenv("SHIPID_THREADS", "8")
    assert mmg_kernels.threads(10 * mmg_kernels.MIN_ROWS_PER_THREAD) == 8
    assert mmg_kernels.threads(2 * mmg_kernels.MIN_ROWS_PER_THREAD) == 2     # no thread with fewer rows
    assert mmg_kernels.threads(3) == 1
    monkeypatch.setenv("SHIPID_THREADS", "zero")                             # not a count: the default
    assert 1 <= mmg_kernels.threads(10 ** 6) <= mmg_kernels.MAX_THREADS


def _child_simulates(conn, model, Th, x0, U, h):
    conn.send(cv_fast.simulate_rows(model, Th, x0, U, h))
    conn.close()


def test_a_forked_child_starts_its_own_threads(published, monkeypatch):
    """After the parent has used its thread pool, a forked child (its threads are not copied) simulates a
    threaded batch to the same numbers instead of waiting on the parent's dead workers."""
    import multiprocessing

    model = _model(published, "esso-lowspeed-ext")
    x0, U, h = _rows(10, B=2 * mmg_kernels.MIN_ROWS_PER_THREAD, L=11)
    Th = {m: np.broadcast_to(model.theta(m), (x0.shape[0], model.theta(m).size)) for m in mmg.MODES}
    monkeypatch.setenv("SHIPID_THREADS", "2")
    parent = cv_fast.simulate_rows(model, Th, x0, U, h)
    ctx = multiprocessing.get_context("fork")
    a, b = ctx.Pipe(duplex=False)
    p = ctx.Process(target=_child_simulates, args=(b, model, Th, x0, U, h))
    p.start()
    ready = a.poll(60)
    got = a.recv() if ready else None
    p.join(10)
    if p.is_alive():
        p.kill()
    assert ready, "the forked child did not finish its threaded simulation"
    assert np.array_equal(got, parent, equal_nan=True)
