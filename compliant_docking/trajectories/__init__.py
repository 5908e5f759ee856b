"""Planners: one module per ``trajectory=`` option; each gives the reference at time t."""
