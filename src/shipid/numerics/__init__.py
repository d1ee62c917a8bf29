"""Shared numerics below the models: the one RK4 and the ODE integrator, careful linear algebra and the
compiled (numba) helpers that the models, the simulator and the estimators all use.

* :mod:`shipid.numerics.integrate`: ``dx/dt = f(t, x, u, theta)`` by the one fixed-step RK4
  (:func:`~shipid.numerics.integrate.rk4_propagate`) or scipy's adaptive solvers;
* :mod:`shipid.numerics.linalg`: Joseph-form update, symmetrisation, positive-definiteness checks;
* :mod:`shipid.numerics.numba_linalg`: allocation-free Cholesky kernels for compiled filters;
* :mod:`shipid.numerics.iir_kernels`: the compiled rational filter (``scipy.signal.lfilter``'s numbers).
"""
