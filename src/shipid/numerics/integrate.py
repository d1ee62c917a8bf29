"""Integrate ``dx/dt = f(t, x, u, theta)``: fixed-step RK4 and scipy's adaptive solvers.

One dynamics signature everywhere (DESIGN.md practice 3, after python-control
``nlsys``): ``f(t, x, u, theta) -> dx/dt`` with ``x`` shape ``(nx,)``, ``u`` shape
``(nu,)`` and ``theta`` any parameter object.

Inputs ``u`` are given either as

* a sampled signal: an array ``(n, nu)`` on the output time grid, held constant
  over each step (zero-order hold, as a digital controller applies it), or
* a closed-loop callback ``u(t, x) -> (nu,)`` (an autopilot, a zig-zag rule),
  evaluated once at the start of each output step and held over it, so that the
  switching instants lie on the sample grid and the recorded input is exactly
  the one applied.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from shipid.errors import ConvergenceError

Dynamics = Callable[[float, np.ndarray, np.ndarray, Any], np.ndarray]
InputLaw = Callable[[float, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Simulation:
    """Result of :func:`simulate`: states ``x`` (n, nx) and applied inputs ``u`` (n, nu) at times ``t``."""

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray


def rk4_propagate(f: Callable[..., np.ndarray], t: float, x: np.ndarray, h: float, substeps: int = 1,
                  args: tuple = ()) -> np.ndarray:
    """Integrate ``ẋ = f(t, x, *args)`` over ``h`` by ``substeps`` classical Runge–Kutta steps.

    The one RK4 of the package: with ``args = (u, θ)`` it steps the dynamics ``f(t, x, u, θ)`` with
    ``u`` held (:func:`rk4_step`, the simulators, and the continuous–discrete EKF
    :func:`shipid.estimate.cd_ekf.cd_ekf`); :func:`rk4_step_jacobians` steps the variational system
    with it (the state-augmented EKF's discrete map and Φ). ``x`` may carry leading batch axes when
    ``f`` does (e.g. :func:`shipid.models.mmg.simulate_batch`,
    :func:`shipid.methods.mmg.manoeuvres.rows_rk4`). Each compiled twin (numba) is tested against it;
    ``tests/test_one_rk4.py`` lists them and fails on any other RK4 in the package.
    """
    hs = h / substeps
    for _ in range(substeps):
        k1 = f(t, x, *args)
        k2 = f(t + 0.5 * hs, x + 0.5 * hs * k1, *args)
        k3 = f(t + 0.5 * hs, x + 0.5 * hs * k2, *args)
        k4 = f(t + hs, x + hs * k3, *args)
        x = x + (hs / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        t += hs
    return x


def rk4_step_jacobians(f: Dynamics, jac: Callable[..., tuple[np.ndarray, np.ndarray]], t: float,
                       x: np.ndarray, u: np.ndarray, theta: np.ndarray, h: float
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One RK4 step of ``f(t, x, u, θ)`` (``u`` held) and the exact Jacobians of that step.

    :func:`rk4_propagate` steps the variational system ``ẋ = f``, ``Ṡ_x = A S_x``,
    ``Ṡ_θ = A S_θ + B`` (``A, B = jac(t, x, u, θ)``, the derivatives ``∂f/∂x`` (nx, nx) and
    ``∂f/∂θ`` (nx, p)) from ``S_x = I``, ``S_θ = 0``. The RK4 stages of the tangent are the
    chain rule through the stages of the state, so the returned matrices are the derivatives
    of the very map returned (the ``Φ`` the state-augmented EKF of Fossen et al. 1996, Table 1,
    needs for its discretised eq. 15), not of the flow.

    Returns
    -------
    x_next (nx,), ∂x_next/∂x (nx, nx), ∂x_next/∂θ (nx, p)
    """
    x = np.asarray(x, dtype=float)
    theta = np.asarray(theta, dtype=float)
    nx, p = x.size, theta.size
    ix, it = nx + nx * nx, nx + nx * nx + nx * p

    def variational(tt, s, uu, th):
        xs = s[:nx]
        A, B = jac(tt, xs, uu, th)
        return np.concatenate([f(tt, xs, uu, th), (A @ s[nx:ix].reshape(nx, nx)).ravel(),
                               (A @ s[ix:it].reshape(nx, p) + B).ravel()])

    s0 = np.concatenate([x, np.eye(nx).ravel(), np.zeros(nx * p)])
    s1 = rk4_propagate(variational, t, s0, h, 1, (u, theta))
    return s1[:nx], s1[nx:ix].reshape(nx, nx), s1[ix:it].reshape(nx, p)


def rk4_step(f: Dynamics, t: float, x: np.ndarray, u: np.ndarray, theta: Any, h: float) -> np.ndarray:
    """One classical Runge–Kutta step of length ``h`` of ``f(t, x, u, θ)`` with ``u`` held constant."""
    return rk4_propagate(f, t, x, h, 1, (u, theta))


def simulate(f: Dynamics, t: np.ndarray, x0: np.ndarray, u: np.ndarray | InputLaw | None,
             theta: Any = None, *, method: str = "rk4", substeps: int = 1,
             rtol: float = 1e-8, atol: float = 1e-10, progress: Callable[[int], None] | None = None
             ) -> Simulation:
    """Simulate ``f`` on the time grid ``t``.

    Parameters
    ----------
    f : callable
        ``f(t, x, u, theta)``.
    t : ndarray, shape (n,)
        Output times, strictly increasing (need not be uniform).
    x0 : ndarray, shape (nx,)
    u : ndarray (n, nu) or (n,), callable ``u(t, x)``, or None
        Input signal on the grid or closed-loop law; held over each step.
    theta : object
        Parameters passed through to ``f``.
    method : str
        ``"rk4"`` (fixed step, ``substeps`` RK4 steps per output step) or any
        :func:`scipy.integrate.solve_ivp` method (``"RK45"``, ``"DOP853"``,
        ``"LSODA"`` ...), restarted at each output step because the input jumps there.
    progress : callable, optional
        Called with the number of steps done, for progress bars.

    Returns
    -------
    Simulation

    Raises
    ------
    ConvergenceError
        When an adaptive solver fails (step size underflow ...).
    """
    t = np.asarray(t, dtype=float)
    x = np.array(x0, dtype=float)
    n = t.size
    closed_loop = callable(u)
    if u is None:
        u_arr = np.zeros((n, 0))
    elif not closed_loop:
        u_arr = np.asarray(u, dtype=float)
        if u_arr.ndim == 1:
            u_arr = u_arr[:, None]
        if u_arr.shape[0] != n:
            raise ValueError(f"input has {u_arr.shape[0]} samples, time grid has {n}")
    X = np.empty((n, x.size))
    X[0] = x
    u0 = np.atleast_1d(np.asarray(u(t[0], x), dtype=float)) if closed_loop else u_arr[0]
    U = np.empty((n, u0.size))
    U[0] = u0
    if method != "rk4":
        from scipy.integrate import solve_ivp  # scipy.integrate (half a second of start-up) only where it is used
    for k in range(n - 1):
        uk = U[k]
        h = t[k + 1] - t[k]
        if method == "rk4":
            hs = h / substeps
            tk = t[k]
            for _ in range(substeps):
                x = rk4_step(f, tk, x, uk, theta, hs)
                tk += hs
        else:
            sol = solve_ivp(lambda tt, xx: f(tt, xx, uk, theta), (t[k], t[k + 1]), x,
                            method=method, rtol=rtol, atol=atol)
            if not sol.success:  # a ShipidError, so the CLI reports it in one line
                raise ConvergenceError(f"{method} failed at t = {t[k]:.6g} s: {sol.message}")
            x = sol.y[:, -1]
        X[k + 1] = x
        if closed_loop:
            U[k + 1] = np.atleast_1d(np.asarray(u(t[k + 1], x), dtype=float))
        else:
            U[k + 1] = u_arr[k + 1]
        if progress is not None:
            progress(k + 1)
    return Simulation(t=t, x=X, u=U)


__all__ = ["Dynamics", "InputLaw", "Simulation", "rk4_propagate", "rk4_step", "rk4_step_jacobians", "simulate"]
