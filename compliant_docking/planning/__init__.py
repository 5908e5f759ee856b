"""The planners: one module per planner (the ``trajectory`` config group chooses one with
``_target_``). A planner gives the reference (pose, twist, acceleration) at any time and
the table of every control step (:mod:`.base`).
"""
