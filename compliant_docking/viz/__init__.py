"""Pictures of a run: per-run figures (:mod:`.plotting`), the video (``render=video``,
:mod:`.render`) and MuJoCo's viewer (``viewer=true``, :mod:`.viewer`).

The OpenGL backend they need is chosen before ``import mujoco`` by
:mod:`compliant_docking.gl`, which the package's ``__init__`` runs first.
"""
