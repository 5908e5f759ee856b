"""A user's interface from CAD: two mesh files → tool and target fragments of convex pieces.

Input convention (docs/interfaces.md): the plug and the socket are closed meshes (STL, OBJ,
PLY: anything trimesh reads) in ONE frame, at the mated pose (as exported from a CAD
assembly), with the docking axis along z, out of the socket's opening, through x = y = 0.
From that the converter derives the frames of the scene's convention:

- the seat (target ``dock`` origin) is the plug's lowest point on the axis, z_tip (the
  plug's tip as it sits in the socket); the target's axes are the CAD axes;
- the tool's ``dock`` origin is the plug's top, z_top (its mounting face), with +z towards
  the tip (CAD −z) and x along CAD x; ``tcp`` is the tip, (0, 0, z_top − z_tip) in it;
  ``sensor_site`` is the ``dock`` origin. So at the mated pose tcp = seat · Rx(180°).

Each part is decomposed into convex pieces (its hull if it is convex, else CoACD), the
pieces are checked against the clearance (:mod:`.clearance`); a part whose pieces lose
clearance is decomposed again at half the CoACD threshold, down to ``min_threshold``,
and the conversion is refused if that is not enough (:class:`ClearanceLost`). With
``collision="sdf"`` each part instead collides as its own mesh through MuJoCo's signed
distance field (``type="sdf"``): exact shape, no decomposition, but far slower contact
(docs/interfaces.md has the measurements). The
fragments (``tool.xml``, ``target.xml``, self-contained: meshes inline) and
``interface.json`` (what was done and measured) are written to the output directory.
A second call with the same input files and options finds ``interface.json`` and does
nothing; decompositions are cached per part in ``<out>/.cache/``.
"""

from __future__ import annotations

import hashlib
import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from compliant_docking.config.geometry import ContactParams
from compliant_docking.config.ranges import Range
from compliant_docking.config.ranges import problems as range_problems
from compliant_docking.sim.geometry.clearance import (
    LIFT,
    SAMPLES,
    ClearanceReport,
    check_clearance,
    yaw_play_deg,
)
from compliant_docking.sim.geometry.collision import (
    PLUG_COLLISION_GROUP,
    PLUG_RGBA,
    SOCKET_RGBA,
    VISUAL_GROUP,
    make_plug_collider,
    make_socket_collider,
)
from compliant_docking.sim.geometry.convex import (
    CoacdSettings,
    Hull,
    coacd_version,
    decompose,
    require_cad_extra,
)
from compliant_docking.sim.geometry.fragment import MATED, Key, declare_key
from compliant_docking.sim.geometry.mesh import Mesh

#: bump when the fragments written for the same inputs change (invalidates the cache)
CONVERTER_VERSION = 1
COLLISIONS = ("convex", "sdf")
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
MANIFEST, TOOL_FILE, TARGET_FILE = "interface.json", "tool.xml", "target.xml"


@dataclass(frozen=True)
class ConvertOptions:
    """How to convert (every field is part of the cache key).

    unit: length unit of the mesh files (m, cm, mm, in). symmetry: the key (n: mates every
    360°/n; 1: one way only; 0: round). plug_mass [kg]: None = density × volume.
    density [kg/m³]. coacd: CoACD settings of the first attempt. min_threshold: the
    lowest CoACD threshold refinement tries. max_pieces: CoACD's cap on pieces per part
    (-1: none). keep, lift, samples: the clearance check (:func:`.clearance.check_clearance`).
    """

    unit: str = "mm"
    symmetry: int = 1
    plug_mass: float | None = None
    density: float = 2700.0
    coacd: CoacdSettings = field(default_factory=CoacdSettings)
    min_threshold: float = 0.01
    max_pieces: int = -1
    keep: float = 0.75
    lift: float = LIFT
    samples: int = SAMPLES
    contact: ContactParams | None = None
    collision: str = "convex"

    def record(self) -> dict:
        out = dict(self.__dict__)
        out["coacd"] = self.coacd.record()
        if self.contact is not None:
            out["contact"] = {
                k: list(v) if isinstance(v, tuple) else v for k, v in self.contact.__dict__.items()
            }
        return out

    def resolved(self) -> ConvertOptions:
        """These options with the default contact parameters filled in."""
        if self.contact is not None:
            return self
        from compliant_docking.config.store import default_interface

        return replace(self, contact=default_interface()[2])

    def problems(self) -> list[tuple[str, str]]:
        """Every option that cannot be used, as (field, one sentence naming it, what is
        allowed and the value given); [] when all can. NaN and inf are never allowed."""
        found: list[tuple[str, str]] = []
        if self.collision not in COLLISIONS:
            found.append(
                ("collision", f"collision must be one of {', '.join(COLLISIONS)}; got {self.collision!r}.")
            )
        if self.unit not in UNITS:
            found.append(("unit", f"unit must be one of {', '.join(sorted(UNITS))}; got {self.unit!r}."))
        threshold = self.coacd.threshold
        values = {
            "symmetry": (self.symmetry, Range(low=0, integer=True)),
            "plug_mass": (self.plug_mass, Range(low=0.0, low_open=True, unit="kg")),  # None: density × volume
            "density": (self.density, Range(low=0.0, low_open=True, unit="kg/m³")),
            "threshold": (threshold, Range(low=0.0, high=1.0, low_open=True)),
            "min_threshold": (
                self.min_threshold,
                Range(low=0.0, high=threshold if math.isfinite(threshold) else 1.0, low_open=True),
            ),
            "max_pieces": (self.max_pieces, Range(low=-1, integer=True)),
            "keep": (self.keep, Range(low=0.0, high=1.0, low_open=True)),
            "lift": (self.lift, Range(low=0.0, unit="m")),
            "samples": (self.samples, Range(low=1, integer=True)),
        }
        for name, (value, allowed) in values.items():
            found += [(name, text) for text in range_problems(name, value, allowed)]
        if self.max_pieces == 0:
            found.append(("max_pieces", "max_pieces must be -1 (no cap) or at least 1; got 0."))
        return found

    def check(self) -> None:
        """Raise ValueError naming every option that cannot be used (:meth:`problems`)."""
        found = self.problems()
        if found:
            raise ValueError(" ".join(text for _, text in found))


class ClearanceLost(ValueError):
    """The pieces lose the clearance even at the lowest CoACD threshold; ``report`` says how."""

    def __init__(self, report: ClearanceReport, thresholds: dict[str, float]):
        self.report = report
        super().__init__(
            f"the convex pieces do not keep the clearance ({report.summary()}) even at CoACD "
            f"threshold {thresholds} (min_threshold): refusing to write fragments. Lower "
            "--min-threshold, allow more pieces (--max-pieces), or use MuJoCo's SDF collision "
            "for this shape (docs/interfaces.md)"
        )


@dataclass
class Conversion:
    """The result: where the fragments are, whether they came from the cache, the manifest."""

    out_dir: Path
    cached: bool
    manifest: dict


def input_hash(plug: bytes, socket: bytes, options: ConvertOptions) -> str:
    digest = hashlib.sha256()
    for chunk in (plug, socket):
        digest.update(hashlib.sha256(chunk).digest())
    extra = {"options": options.record(), "converter": CONVERTER_VERSION, "coacd": coacd_version()}
    digest.update(json.dumps(extra, sort_keys=True).encode())
    return digest.hexdigest()


def load_mesh(path: Path, data: bytes, scale: float, what: str) -> Mesh:
    """A closed mesh from a file's bytes (its suffix names the format), scaled to metres."""
    import io

    import trimesh

    mesh: Any = trimesh.load(io.BytesIO(data), file_type=path.suffix.lstrip(".").lower(), force="mesh")
    if not mesh.is_watertight or not mesh.is_winding_consistent:
        raise ValueError(f"{what} {path}: the mesh must be a closed solid (watertight, consistently wound)")
    if mesh.volume < 0.0:
        mesh.invert()
    return np.asarray(mesh.vertices, dtype=np.float64) * scale, np.asarray(mesh.faces, dtype=np.int64)


def _pieces(mesh: Mesh, settings: CoacdSettings, max_pieces: int, cache: Path, log) -> list[Hull]:
    """The part's convex pieces, from ``cache`` when this mesh was decomposed so before."""
    vertices, faces = mesh
    key = hashlib.sha256(
        vertices.tobytes()
        + faces.tobytes()
        + json.dumps([settings.record(), max_pieces, coacd_version()], sort_keys=True).encode()
    ).hexdigest()[:24]
    path = cache / f"{key}.npz"
    if path.is_file():
        with np.load(path) as stored:  # arr_0, arr_1, …
            return [Hull.of(stored[f"arr_{i}"]) for i in range(len(stored.files))]
    started = time.perf_counter()
    hulls = decompose(vertices, faces, settings, max_pieces=max_pieces)
    log(
        f"  CoACD threshold {settings.threshold:g}: {len(hulls)} pieces in {time.perf_counter() - started:.1f} s"
    )
    cache.mkdir(parents=True, exist_ok=True)
    np.savez(path, *[h.vertices for h in hulls])
    return hulls


def convert(
    plug_path: str | Path,
    socket_path: str | Path,
    out_dir: str | Path,
    options: ConvertOptions = ConvertOptions(),
    *,
    log: Callable[[str], None] = print,
) -> Conversion:
    """Convert a CAD pair into fragments in ``out_dir`` (module doc); raises ValueError
    for unusable inputs and :class:`ClearanceLost` when the pieces cannot keep the
    clearance."""
    options.check()
    options = options.resolved()
    plug_path, socket_path, out_dir = Path(plug_path), Path(socket_path), Path(out_dir)
    data = {}
    for what, path in (("plug", plug_path), ("socket", socket_path)):
        if not path.is_file():
            raise ValueError(f"{what}: no such file {path}")
        data[what] = path.read_bytes()
    digest = input_hash(data["plug"], data["socket"], options)
    manifest_path = out_dir / MANIFEST
    if manifest_path.is_file() and (out_dir / TOOL_FILE).is_file() and (out_dir / TARGET_FILE).is_file():
        manifest = json.loads(manifest_path.read_text())
        if manifest.get("input_hash") == digest:
            log(f"{out_dir}: up to date (input hash {digest[:12]}), nothing to do")
            return Conversion(out_dir, True, manifest)
    require_cad_extra()
    started = time.perf_counter()
    scale = UNITS[options.unit]
    plug = load_mesh(plug_path, data["plug"], scale, "plug")
    socket = load_mesh(socket_path, data["socket"], scale, "socket")
    z_tip, z_top = float(plug[0][:, 2].min()), float(plug[0][:, 2].max())
    if not socket[0][:, 2].min() <= z_tip <= socket[0][:, 2].max():
        raise ValueError(
            f"the plug's tip (z = {z_tip:.6g} m) is not within the socket's height: the two files "
            "must hold the parts mated, in one frame, docking axis along z (docs/interfaces.md)"
        )

    cache = out_dir / ".cache"
    settings = {"plug": options.coacd, "socket": options.coacd}
    report: ClearanceReport | None = None
    while options.collision == "convex":
        hulls = {
            part: _pieces(m, settings[part], options.max_pieces, cache, log)
            for part, m in (("plug", plug), ("socket", socket))
        }
        report = check_clearance(
            plug,
            hulls["plug"],
            socket,
            hulls["socket"],
            keep=options.keep,
            lift=options.lift,
            samples=options.samples,
        )
        log(f"  {len(hulls['plug'])} plug + {len(hulls['socket'])} socket pieces: {report.summary()}")
        if report.passed:
            break
        finer = {part: settings[part].threshold / 2.0 for part in report.refine()}
        if not finer or all(settings[p].threshold <= options.min_threshold for p in finer):
            raise ClearanceLost(report, {p: settings[p].threshold for p in report.refine()})
        for part, threshold in finer.items():
            settings[part] = replace(settings[part], threshold=max(threshold, options.min_threshold))
        log(
            f"  refining {', '.join(finer)}: CoACD threshold {', '.join(f'{settings[p].threshold:g}' for p in finer)}"
        )

    if options.collision == "sdf":  # the meshes themselves; no pieces, no check, no measured play
        hulls, report = {"plug": [], "socket": []}, None
        key = Key(options.symmetry, None)
    else:
        play = (
            yaw_play_deg(plug, hulls["socket"], options.symmetry, lift=options.lift)
            if options.symmetry
            else None
        )
        key = Key(options.symmetry if play is not None else 0, play)
        if options.symmetry and play is None:
            log("  the plug turns freely in the socket's pieces: the interface is not keyed (key_symmetry 0)")
    tool, mass = tool_fragment(plug, hulls["plug"], z_tip, z_top, options, key)
    target = target_fragment(socket, hulls["socket"], z_tip, options, key)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / TOOL_FILE).write_text(tool.to_xml())
    (out_dir / TARGET_FILE).write_text(target.to_xml())
    manifest = {
        "input_hash": digest,
        "plug_file": str(plug_path),
        "socket_file": str(socket_path),
        "options": options.record(),
        "thresholds": {part: s.threshold for part, s in settings.items()},
        "collision": options.collision,
        "pieces": {part: len(h) for part, h in hulls.items()},
        "clearance": None if report is None else report.record(),
        "key_symmetry": key.symmetry,
        "key_yaw_play_deg": key.yaw_play_deg,
        "tcp_in_tool_dock_m": [0.0, 0.0, z_top - z_tip],
        "seat_in_cad_m": [0.0, 0.0, z_tip],
        **mass,
        "converter_version": CONVERTER_VERSION,
        "coacd_version": coacd_version(),
        "mujoco_version": mujoco.__version__,
        "wall_time_s": time.perf_counter() - started,
    }
    manifest_path.write_text(json.dumps(manifest, indent=2) + "\n")
    return Conversion(out_dir, False, manifest)


def _mass_properties(plug: Mesh, options: ConvertOptions) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass [kg], centre of mass and inertia about it (CAD axes) of the uniform plug."""
    import trimesh

    mesh = trimesh.Trimesh(*plug, process=False)
    volume = float(mesh.volume)
    density = options.density if options.plug_mass is None else options.plug_mass / volume
    mesh.density = density
    return float(mesh.mass), np.asarray(mesh.center_mass), np.asarray(mesh.moment_inertia)


def tool_fragment(
    plug: Mesh, hulls: list[Hull], z_tip: float, z_top: float, options: ConvertOptions, key: Key
) -> tuple[mujoco.MjSpec, dict]:
    """The tool fragment of a plug (CAD frame, mated) and its pieces, and the mass record."""
    top = np.array([0.0, 0.0, z_top])

    def to_dock(points: np.ndarray) -> np.ndarray:  # CAD → dock frame: MATED · (p − top)
        return (np.asarray(points) - top) @ MATED.T

    mass, com, inertia = _mass_properties(plug, options)
    com_dock, inertia_dock = to_dock(com[None])[0], MATED @ inertia @ MATED.T
    spec = mujoco.MjSpec()
    spec.modelname = "cad_plug"
    body = spec.worldbody.add_body(name="dock")
    body.explicitinertial = True
    body.mass = mass
    body.ipos = com_dock.tolist()
    i = inertia_dock
    body.fullinertia = [i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2]]
    for k, hull in enumerate(hulls):
        spec.add_mesh(name=f"plug_piece_{k}", uservert=to_dock(hull.vertices).ravel().tolist())
        g = body.add_geom(
            name=f"plug_piece_{k}",
            type=mujoco.mjtGeom.mjGEOM_MESH,
            meshname=f"plug_piece_{k}",
            group=PLUG_COLLISION_GROUP,
            rgba=list(PLUG_RGBA),
        )
        make_plug_collider(g, options.contact)
    visual = _add_visual(spec, body, "plug_visual", to_dock(plug[0]), plug[1], VISUAL_GROUP, PLUG_RGBA)
    if options.collision == "sdf":
        visual.type = mujoco.mjtGeom.mjGEOM_SDF
        make_plug_collider(visual, options.contact)
    body.add_site(name="sensor_site", pos=[0.0, 0.0, 0.0], quat=[1.0, 0.0, 0.0, 0.0])
    body.add_site(name="tcp", pos=[0.0, 0.0, z_top - z_tip])
    declare_key(spec, key)
    record = {
        "mass_kg": mass,
        "com_in_tool_dock_m": com_dock.tolist(),
        "inertia_in_tool_dock_kg_m2": i.tolist(),
    }
    return spec, record


def target_fragment(
    socket: Mesh, hulls: list[Hull], z_tip: float, options: ConvertOptions, key: Key
) -> mujoco.MjSpec:
    """The target fragment of a socket (CAD frame, mated; the seat at z_tip) and its pieces."""
    seat = np.array([0.0, 0.0, z_tip])
    spec = mujoco.MjSpec()
    spec.modelname = "cad_socket"
    body = spec.worldbody.add_body(name="dock")
    for k, hull in enumerate(hulls):
        spec.add_mesh(name=f"socket_piece_{k}", uservert=(hull.vertices - seat).ravel().tolist())
        g = body.add_geom(
            name=f"socket_piece_{k}",
            type=mujoco.mjtGeom.mjGEOM_MESH,
            meshname=f"socket_piece_{k}",
            group=PLUG_COLLISION_GROUP,
            rgba=list(SOCKET_RGBA),
        )
        make_socket_collider(g, options.contact)
    visual = _add_visual(spec, body, "socket_visual", socket[0] - seat, socket[1], 0, SOCKET_RGBA)
    if options.collision == "sdf":
        visual.type = mujoco.mjtGeom.mjGEOM_SDF
        make_socket_collider(visual, options.contact)
    body.add_site(name="seat", pos=[0.0, 0.0, 0.0])
    body.add_site(name="mouth", pos=[0.0, 0.0, float(socket[0][:, 2].max()) - z_tip])
    declare_key(spec, key)
    return spec


def _add_visual(
    spec, body, name: str, vertices: np.ndarray, faces: np.ndarray, group: int, rgba
) -> mujoco.MjsGeom:
    """The part's own mesh, drawn, colliding with nothing (the SDF route makes it collide)."""
    spec.add_mesh(name=name, uservert=np.ravel(vertices).tolist(), userface=np.ravel(faces).tolist())
    return body.add_geom(
        name=name,
        type=mujoco.mjtGeom.mjGEOM_MESH,
        meshname=name,
        contype=0,
        conaffinity=0,
        density=0.0,
        group=group,
        rgba=list(rgba),
    )
