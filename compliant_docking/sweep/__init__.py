"""Sweeps (``-m``): the Hydra callback, console progress, the end-of-sweep summary and
outcome, resuming an interrupted sweep, and the launcher presets (joblib, submitit).
"""
