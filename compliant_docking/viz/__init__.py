"""Pictures: the look and the saving of every figure (:mod:`.style`; a run's figures are
:mod:`compliant_docking.run.figures`, those comparing runs :mod:`compliant_docking.results.figures`),
the video of a run (``render=video``, :mod:`.render`) and MuJoCo's viewer (``viewer=true``,
:mod:`.viewer`).

The OpenGL backend they need is chosen before ``import mujoco`` by
:mod:`compliant_docking.gl`, which the package's ``__init__`` runs first.
"""
