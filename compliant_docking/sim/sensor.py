"""The wrist force/torque sensor and the joint encoders as the controllers see them.

:func:`wrench_reader`: the external wrench on the tool at the TCP, in world axes, one step
old, with the tool's own weight removed: exact (MuJoCo's constraint force), the ideal
sensor. The ``sensor`` config group (:class:`SensorModel`, :func:`sensing`) makes the
controller's reading realistic, per control step k (time step dt):

    u_k = w_k + b + σ ε_k,  ε_k ~ N(0, I)                          bias and white noise
    y_k = y_(k−1) + α (u_k − y_(k−1)),  α = 1 − exp(−2π f_c dt)   first-order low-pass
                                                                   (exact for a held input;
                                                                   y starts at u_0: a sensor
                                                                   on while the arm was held)
    s_k = y_(jP) for jP ≤ k < (j+1)P,  P = 1 / (rate · dt)        sampled every P steps, held
    reading_k = s_(k−D),  D = delay_s / dt                         transport delay

with w the exact reading compensated with the tool the controller believes (a payload
error shows as a force, as on a real sensor), b the bias (fixed plus a per-seed draw),
σ the noise per axis (the filter lowers it to σ·√(α/(2−α))); encoders add white noise
to q and v. Everything is drawn once per
run from the seed (``SeedSequence([seed, 200 + stream])``), so a seed gives one reading
whatever the controller. The run's time series keeps the exact wrench in ``fx … mz``
(the metrics and the gate judge it) and the controller's reading in ``sensed_fx …``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco
import numpy as np
import pinocchio as pin

from compliant_docking.config.robustness import SensorConfig, sample_period
from compliant_docking.sim.misalignment import stream_rng
from compliant_docking.sim.models import ArmModel, RigidTool
from compliant_docking.sim.scene import Scene
from compliant_docking.sim.settings import SimSettings

#: column names of the controller's F/T reading in the time series (non-ideal sensors)
SENSED_COLUMNS = ("sensed_fx", "sensed_fy", "sensed_fz", "sensed_mx", "sensed_my", "sensed_mz")
#: random streams of the sensor's draws (misalignment 0-3, model error 100+, dynamics 300+)
STREAM_NOISE, STREAM_BIAS, STREAM_Q, STREAM_V = 200, 201, 202, 203


def wrench_reader(
    scene: Scene, data: mujoco.MjData, out: np.ndarray, tool: RigidTool | None = None
) -> Callable[..., None]:
    """A function writing into ``out`` the tool's external wrench [f; m] at the TCP, world axes.

    ``tool``: the tool whose weight is compensated (default: the true one, scene.arm.tool);
    the function takes the step's index and ignores it (the interface of the loop's readers).

    MuJoCo's force/torque sensors give what the tool subtree exerts on its parent about
    the sensor site, in the site frame: minus the external wrench (minus the tool's
    weight). A constant 6×6 map moves the moment to the TCP and flips the sign in the
    site frame; one rotation takes both halves to the world. The values come from the
    previous mj_step: a one-step measurement delay, as on a real robot.
    """
    raw = data.sensordata[scene.force_adr : scene.force_adr + 6]  # [force; torque], a view
    site_rot_T = data.site_xmat[scene.sensor_site].reshape(3, 3).T  # a view, tracks the data
    true_tool = scene.arm.tool
    # TCP → sensor offset in the sensor frame; moment about the TCP = m_s + r × f
    r = -(true_tool.sensor.actInv(true_tool.tcp)).translation
    to_tcp = -np.block([[np.eye(3), np.zeros((3, 3))], [pin.skew(r), np.eye(3)]])
    local = np.zeros((2, 3))  # the wrench at the TCP in sensor axes, rows [f; m]
    local_flat = local.reshape(6)
    out_rows = out.reshape(2, 3)  # a view of out
    # The tool's weight, as the sensor sees it, at the TCP: f = m g and
    # moment (c − p_tcp) × m g = −[m g]× R_dock (com − tcp) with constant parts.
    tool = true_tool if tool is None else tool
    weight = tool.mass * scene.gravity
    has_weight = bool(np.any(weight))
    weight_moment = -pin.skew(weight)
    com_from_tcp = tool.com - tool.tcp.translation  # dock frame
    dock_rot = data.xmat[scene.tool_body].reshape(3, 3)

    def read(k: int = 0) -> None:
        # ndarray.dot: a fraction of the call overhead of `@` on arrays this small
        to_tcp.dot(raw, out=local_flat)
        local.dot(site_rot_T, out=out_rows)  # each row rotated to world axes
        if has_weight:  # payload compensation, as on a real F/T sensor
            out[:3] -= weight
            out[3:] -= weight_moment.dot(dock_rot.dot(com_from_tcp))

    return read


@dataclass(frozen=True)
class SensorModel:
    """The realised settings of the ``sensor`` group for a loop of time step ``dt``."""

    period: int = 1  # steps between F/T samples
    alpha: float | None = None  # low-pass coefficient per step; None: no filter
    delay: int = 0  # transport delay [steps]
    noise: np.ndarray = field(default_factory=lambda: np.zeros(6))  # std per axis [N ×3, N·m ×3]
    bias: np.ndarray = field(default_factory=lambda: np.zeros(6))  # realised offset [N ×3, N·m ×3]
    q_noise: float = 0.0  # [rad]
    v_noise: float = 0.0  # [rad/s]
    seed: int = 0

    @property
    def exact_wrench(self) -> bool:
        """Whether the F/T reading is the exact wrench (no filter, rate, delay, noise, bias)."""
        return (
            self.period == 1
            and self.alpha is None
            and self.delay == 0
            and not np.any(self.noise)
            and not np.any(self.bias)
        )

    @property
    def ideal(self) -> bool:
        """The ideal sensors: the exact wrench and exact joint states."""
        return self.exact_wrench and self.q_noise == 0.0 and self.v_noise == 0.0

    @classmethod
    def from_settings(cls, settings: SensorConfig, dt: float) -> SensorModel:
        """The model of ``settings`` (the ``sensor`` group, typed) at time step ``dt`` [s]; the bias
        drawn with the seed. Raises ValueError naming the setting for values the loop
        cannot realise (the config check refuses them first)."""
        rate, cutoff = settings.rate_hz, settings.cutoff_hz
        period = 1 if rate is None else sample_period(float(rate), dt)
        if period is None:
            raise ValueError(
                f"sensor.rate_hz must make the sample period a whole number of steps of {dt:g} s; got {rate}"
            )
        delay = int(round(float(settings.delay_s) / dt))
        alpha = None if cutoff is None else 1.0 - math.exp(-2.0 * math.pi * float(cutoff) * dt)
        noise = np.array([*settings.force_noise_N, *settings.moment_noise_Nm], dtype=float)
        bias = np.array([*settings.force_bias_N, *settings.moment_bias_Nm], dtype=float)
        seed = int(settings.seed)
        spread = np.repeat([float(settings.force_bias_std_N), float(settings.moment_bias_std_Nm)], 3)
        if np.any(spread):
            bias = bias + spread * stream_rng(seed, STREAM_BIAS).standard_normal(6)
        return cls(
            period=period,
            alpha=alpha,
            delay=delay,
            noise=noise,
            bias=bias,
            q_noise=float(settings.joint_position_noise_rad),
            v_noise=float(settings.joint_velocity_noise_rad_s),
            seed=seed,
        )

    def record(self) -> dict:
        """The realised sensor for metrics.json (flat keys)."""
        return {
            "sensor_period_steps": self.period,
            "sensor_filter_alpha": self.alpha,
            "sensor_delay_steps": self.delay,
            "sensor_force_noise_N": float(np.linalg.norm(self.noise[:3])),
            "sensor_force_bias_N": float(np.linalg.norm(self.bias[:3])),
            "sensor_moment_bias_Nm": float(np.linalg.norm(self.bias[3:])),
        }


class SensedWrench:
    """The F/T path of :class:`SensorModel` (the module docstring) for ``n_steps`` steps:
    :meth:`step` turns the exact reading ``source`` of step k into the controller's
    reading ``out`` and records it. Calling it twice for one step changes nothing."""

    def __init__(self, model: SensorModel, n_steps: int, source: np.ndarray, out: np.ndarray):
        self.model, self.source, self.out = model, source, out
        self.noise = stream_rng(model.seed, STREAM_NOISE).standard_normal((max(n_steps, 1), 6)) * model.noise
        self.raw = np.zeros(6)  # u
        self.filtered = np.zeros(6)  # y
        self.sample = np.zeros(6)  # the held sample s
        self.line = np.zeros((model.delay + 1, 6))  # the delay line, indexed by k mod (D + 1)
        self.record = np.zeros((n_steps, 6))
        self.last = -1

    def step(self, k: int) -> None:
        if k == self.last:
            return
        m, u, y = self.model, self.raw, self.filtered
        np.add(self.source, m.bias, out=u)
        u += self.noise[min(k, len(self.noise) - 1)]
        if self.last < 0 or m.alpha is None:  # at the start: settled on u_0 (on while held)
            y[:] = u
        else:
            y += m.alpha * (u - y)
        if k % m.period == 0:
            self.sample[:] = y
        line, slots = self.line, m.delay + 1
        if self.last < 0:
            line[:] = self.sample  # before the first reading reaches the controller: held
        line[k % slots] = self.sample
        self.out[:] = line[(k + 1) % slots] if m.delay else self.sample
        if k < len(self.record):
            self.record[k] = self.out
        self.last = k


class Sensing:
    """What the controller reads when the sensors are not ideal or its tool is not the
    plant's (the payload compensation then uses the believed tool)."""

    def __init__(self, model: SensorModel, n_steps: int, nv: int, believed_tool: RigidTool | None):
        self.model, self.n_steps, self.believed_tool = model, n_steps, believed_tool
        self.q = np.zeros(nv)
        self.v = np.zeros(nv)
        self.q_noise = stream_rng(model.seed, STREAM_Q).standard_normal((n_steps, nv)) * model.q_noise
        self.v_noise = stream_rng(model.seed, STREAM_V).standard_normal((n_steps, nv)) * model.v_noise
        self.count = 0
        self.wrench: SensedWrench | None = None

    def reader(
        self, scene: Scene, data: mujoco.MjData, exact: np.ndarray, out: np.ndarray
    ) -> Callable[[int], None]:
        """The loop's reader: the exact wrench into ``exact`` (logged), the controller's
        reading into ``out``."""
        read_exact = wrench_reader(scene, data, exact)
        if self.believed_tool is None:
            believed, read_believed = exact, None
        else:
            believed = np.zeros(6)
            read_believed = wrench_reader(scene, data, believed, self.believed_tool)
        path = SensedWrench(self.model, self.n_steps, believed, out)
        self.wrench = path

        def read(k: int) -> None:
            read_exact()
            if read_believed is not None:
                read_believed()
            path.step(k)

        return read

    def updater(self, arm: ArmModel) -> Callable[[np.ndarray, np.ndarray], None]:
        """The loop's arm update with the encoders' noise (exact states: ``arm.update``)."""
        if self.model.q_noise == 0.0 and self.model.v_noise == 0.0:
            return arm.update
        q_buf, v_buf, q_noise, v_noise, update = self.q, self.v, self.q_noise, self.v_noise, arm.update

        def noisy(q: np.ndarray, v: np.ndarray) -> None:
            k = min(self.count, len(q_noise) - 1)
            np.add(q, q_noise[k], out=q_buf)
            np.add(v, v_noise[k], out=v_buf)
            self.count += 1
            update(q_buf, v_buf)

        return noisy

    def timeseries(self, count: int) -> dict[str, np.ndarray]:
        """The controller's F/T reading per step (``sensed_fx … sensed_mz``)."""
        if self.wrench is None:
            return {}
        return {name: self.wrench.record[:count, i] for i, name in enumerate(SENSED_COLUMNS)}


def sensing(
    settings: SensorConfig | None, dt: float, n_steps: int, nv: int, believed_tool: RigidTool | None
) -> Sensing | None:
    """The controller's sensors for ``settings`` (the ``sensor`` group, typed; None: ideal);
    None when the reading is exact and the believed tool is the plant's (the ideal loop, bit
    for bit)."""
    model = SensorModel.from_settings(settings, dt) if settings is not None else SensorModel()
    if model.ideal and believed_tool is None:
        return None
    return Sensing(model, n_steps, nv, believed_tool)


def record_for(settings: SimSettings | None, dt: float | None = None) -> dict:
    """The sensor keys of metrics.json for the run's ``settings`` (never raises: null when
    invalid; None: the config's nodes are not the schema's)."""
    if settings is None or settings.sensor is None:
        return dict.fromkeys(SensorModel().record())
    try:
        step = float(settings.physics.timestep) if dt is None else dt
        return SensorModel.from_settings(settings.sensor, step).record()
    except Exception:
        return dict.fromkeys(SensorModel().record())
