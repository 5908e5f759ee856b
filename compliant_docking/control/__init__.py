"""The controllers: one module per control law (``controller=…`` names its class with
``_target_``), their shared pieces (:mod:`.base`), the momentum observer and the Lie-group
maths of the SE(3) impedance (:mod:`.lie`). Controllers never see the config: they get
their parameters and a :class:`~compliant_docking.sim.context.ControlContext`.
"""
