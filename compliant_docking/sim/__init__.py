"""The simulated world and the loop: the scene (robot MJCF + plug + socket, assembled with
MjSpec), the parametric interface geometry, the Pinocchio arm model, the F/T sensor, the
task's poses, the misalignment of the true socket, the loop and its telemetry.

Heavy objects (MjModel, Pinocchio model) are built inside a job by
:func:`compliant_docking.sim.simulate.prepare`, never at import time. It reads the run's
config once, as typed settings (:mod:`compliant_docking.sim.settings`); the modules below
it take those, never the config.
"""
