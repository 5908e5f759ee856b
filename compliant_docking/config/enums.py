"""Enumerations of the configuration: the allowed values of the settings that take a name.

OmegaConf checks an enum-typed field at composition, so a value outside the set fails
with a message naming the key and the allowed values.
"""

from __future__ import annotations

from enum import Enum


class Precision(Enum):
    """The floating-point width of the saved time series (``output.precision``)."""

    float64 = "float64"  # the simulation's own values, bit for bit
    float32 = "float32"  # about 7 significant digits: half the bytes before compression


class Integrator(Enum):
    """MuJoCo integrators (``mjtIntegrator``)."""

    euler = 0
    rk4 = 1
    implicit = 2
    implicitfast = 3


class Cone(Enum):
    """MuJoCo friction cones (``mjtCone``)."""

    pyramidal = 0
    elliptic = 1


class FrictionComp(Enum):
    """Friction feed-forward mode (docs/control_laws.md, shared conventions)."""

    torque = "torque"  # f·tanh(2·τ_pre/f) + b·v: follows the commanded torque, no dead zone at v = 0
    velocity = "velocity"  # f·tanh(v/0.01) + b·v: classic velocity-sign compensation
    # f·tanh(2·(τ_pre − h)/f) + b·v: the torque mode on the command minus the model's bias
    # torques h = C v + g, so a gravity-holding torque does not set the sign
    # (docs/controllers/friction.md)
    torque_unbiased = "torque_unbiased"
    # torque_unbiased, switched off on a joint that moves against it (fully from |v| =
    # 0.02 rad/s, linearly below): never pushes against a motion the contact drives
    # (docs/controllers/friction.md)
    yielding = "yielding"


class ForceSource(Enum):
    """Where a force-aware controller reads the contact wrench."""

    sensor = "sensor"  # the wrist force/torque sensor
    observer = "observer"  # sensorless: the generalised-momentum observer


class NullSpaceMetric(Enum):
    """controller=hqp: the joint-space metric of its level-1 regulariser and its
    singularity-avoidance direction (docs/controllers/hqp.md)."""

    euclidean = "euclidean"  # the paper: 1e-8·I and ∇w/‖∇w‖
    inertia = "inertia"  # 1e-8·M and M⁻¹∇w/‖M⁻¹∇w‖, consistent with N = I − M⁻¹JᵀΛJ


class SE3Formulation(Enum):
    """How ``controller=se3_lie`` evaluates its law (the same law; see its module docstring)."""

    twist = "twist"  # reduced closed form: dexp and ḋexp cancel (fast, default)
    lambda_space = "lambda_space"  # literally through λ̈_ref = −K_V λ̇ − K_P λ + K_F γ


class ActionKind(Enum):
    """What an action of the Gymnasium environment sets (compliant_docking/env/, docs/env.md)."""

    setpoint = "setpoint"  # a pose offset of the controller's setpoint, and gain scales
    torque = "torque"  # residual joint torques added to the controller's command
