"""The configuration: typed schemas of every config group, their registration in Hydra's
ConfigStore, and :func:`load_config` to compose a config in Python.

This layer imports nothing else of the package (only its paths): everything above it
reads the composed config. Units are SI (m, rad, N, N·m, s) unless a field name says
otherwise (``_deg``).
"""

from compliant_docking.config.enums import (
    Cone,
    ForceSource,
    FrictionComp,
    Integrator,
    NullSpaceMetric,
    SE3Formulation,
)
from compliant_docking.config.resolvers import register as _register_resolvers
from compliant_docking.config.store import load_config, register_schemas

_register_resolvers()  # ${job_dir:…} in conf/config.yaml, in every process that imports the config

__all__ = [
    "Cone",
    "ForceSource",
    "FrictionComp",
    "Integrator",
    "NullSpaceMetric",
    "SE3Formulation",
    "load_config",
    "register_schemas",
]
