"""Estimators: Kalman filters and smoothers, instrumental variables, regression (pure functions)."""
