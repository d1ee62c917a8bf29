"""Simulation: integrators, manoeuvres, noise and disturbance generators."""
