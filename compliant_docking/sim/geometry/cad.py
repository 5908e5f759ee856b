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

Each part is decomposed into convex pieces (its hull if it is convex, else CoACD), and
the pieces are rebuilt to collide like the solid (:mod:`.conform`: split exactly by the
part's own faces, merged, grown into each other at their cuts and bevelled at their
seams). They are checked against the clearance (:mod:`.clearance`) and for holes; a part
that fails is decomposed again at half the CoACD threshold, down to ``min_threshold``,
and the conversion is refused if that is not enough (:class:`ClearanceLost`). The
fragments' contacts are then audited (:mod:`.conversion_audit`: the plug swept over the
mouth, funnel and bore, every contact normal against the socket's surface) and the
conversion is refused if one is unsound (:class:`ContactsUnsound`). With
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
from compliant_docking.sim.geometry.cad_fragments import target_fragment, tool_fragment
from compliant_docking.sim.geometry.clearance import (
    LIFT,
    SAMPLES,
    ClearanceReport,
    check_clearance,
    yaw_play_deg,
)
from compliant_docking.sim.geometry.conform import ConformReport, ConformSettings, conform
from compliant_docking.sim.geometry.conversion_audit import (
    TOLERANCE_DEG,
    ContactAudit,
    audit_fragments,
    sweep_for,
)
from compliant_docking.sim.geometry.convex import (
    CoacdSettings,
    Hull,
    coacd_version,
    decompose,
    require_cad_extra,
)
from compliant_docking.sim.geometry.fragment import Key
from compliant_docking.sim.geometry.mesh import Mesh

#: bump when the fragments written for the same inputs change (invalidates the cache)
CONVERTER_VERSION = 2
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
    (-1: none). conform: how the pieces are rebuilt (:class:`.conform.ConformSettings`).
    keep, lift, samples: the clearance check (:func:`.clearance.check_clearance`).
    audit_tolerance_deg: the contact audit's tolerance (:mod:`.conversion_audit`).
    """

    unit: str = "mm"
    symmetry: int = 1
    plug_mass: float | None = None
    density: float = 2700.0
    coacd: CoacdSettings = field(default_factory=CoacdSettings)
    min_threshold: float = 0.01
    max_pieces: int = -1
    conform: ConformSettings = field(default_factory=ConformSettings)
    keep: float = 0.75
    lift: float = LIFT
    samples: int = SAMPLES
    contact: ContactParams | None = None
    collision: str = "convex"
    audit_tolerance_deg: float = TOLERANCE_DEG

    def record(self) -> dict:
        out = dict(self.__dict__)
        out["coacd"] = self.coacd.record()
        out["conform"] = self.conform.record()
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

    def check(self) -> None:
        if self.collision not in COLLISIONS:
            raise ValueError(f"collision must be one of {COLLISIONS}; got {self.collision!r}")
        if self.unit not in UNITS:
            raise ValueError(f"unit must be one of {sorted(UNITS)}; got {self.unit!r}")
        if not (isinstance(self.symmetry, int) and self.symmetry >= 0):
            raise ValueError(f"symmetry must be an integer >= 0 (0: round); got {self.symmetry!r}")
        if not 0.0 < self.keep <= 1.0:
            raise ValueError(f"keep must be in (0, 1] (share of the clearance to keep); got {self.keep}")
        self.conform.check()
        if not (math.isfinite(self.audit_tolerance_deg) and 0.0 < self.audit_tolerance_deg < 90.0):
            raise ValueError(
                f"audit_tolerance_deg must be in (0, 90) [deg]; got {self.audit_tolerance_deg!r}"
            )
        if not 0.0 < self.min_threshold <= self.coacd.threshold:
            raise ValueError(
                f"min_threshold must be in (0, threshold = {self.coacd.threshold}]; got {self.min_threshold}"
            )


class Refused(ValueError):
    """The conversion is refused: the pieces are not a faithful model of the parts."""


class ClearanceLost(Refused):
    """The pieces lose the clearance, or leave holes in a part's surface, even at the
    lowest CoACD threshold; ``report`` says how."""

    def __init__(
        self, report: ClearanceReport, thresholds: dict[str, float], holes: dict[str, float] | None = None
    ):
        self.report = report
        self.holes = holes or {}
        failed = [] if report.passed else [f"do not keep the clearance ({report.summary()})"]
        failed += [
            f"leave holes ({100 * share:.3f} % of the {part}'s surface, probed 1 µm under it, is in no piece)"
            for part, share in self.holes.items()
        ]
        super().__init__(
            f"the convex pieces {' and '.join(failed)} even at CoACD "
            f"threshold {thresholds} (min_threshold): refusing to write fragments. Lower "
            "--min-threshold, allow more pieces (--max-pieces), or use MuJoCo's SDF collision "
            "for this shape (docs/interfaces.md)"
        )


class ContactsUnsound(Refused):
    """The fragments' contacts fail the contact audit; ``audit`` says where."""

    def __init__(self, audit: ContactAudit):
        self.audit = audit
        super().__init__(
            f"the convex pieces' contacts are not those of the solid parts ({audit.summary()}): "
            f"{audit.describe()}. Refusing to write fragments. A larger --margin-mm or a smaller "
            "--bevel-deg buries the pieces' cuts deeper; --collision sdf avoids pieces "
            "(docs/interfaces.md, 'How to check a new interface')"
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


def _cached(cache: Path, key: bytes, make: Callable[[], tuple[list[Hull], dict]]) -> tuple[list[Hull], dict]:
    """Pieces and their record from ``cache`` under ``key``'s digest, else made and stored."""
    path = cache / f"{hashlib.sha256(key).hexdigest()[:24]}.npz"
    if path.is_file():
        with np.load(path) as stored:  # arr_0, arr_1, … and the record
            arrays = sorted((f for f in stored.files if f.startswith("arr_")), key=lambda f: int(f[4:]))
            record = json.loads(str(stored["record"])) if "record" in stored.files else {}
            return [Hull.of(stored[f]) for f in arrays], record
    hulls, record = make()
    cache.mkdir(parents=True, exist_ok=True)
    np.savez(path, *[h.vertices for h in hulls], record=json.dumps(record))
    return hulls, record


def _pieces(mesh: Mesh, settings: CoacdSettings, max_pieces: int, cache: Path, log) -> list[Hull]:
    """The part's convex pieces by CoACD, from ``cache`` when this mesh was decomposed so before."""
    vertices, faces = mesh

    def make() -> tuple[list[Hull], dict]:
        started = time.perf_counter()
        hulls = decompose(vertices, faces, settings, max_pieces=max_pieces)
        seconds = time.perf_counter() - started
        log(f"  CoACD threshold {settings.threshold:g}: {len(hulls)} pieces in {seconds:.1f} s")
        return hulls, {"seconds": seconds}

    key = vertices.tobytes() + faces.tobytes()
    key += json.dumps([settings.record(), max_pieces, coacd_version()], sort_keys=True).encode()
    return _cached(cache, key, make)[0]


def _conformed(
    mesh: Mesh, hulls: list[Hull], settings: ConformSettings, cache: Path, what: str, log
) -> tuple[list[Hull], ConformReport]:
    """The pieces rebuilt by :func:`.conform.conform`, from ``cache`` when done so before."""

    def make() -> tuple[list[Hull], dict]:
        pieces, report = conform(hulls, mesh, settings)
        log(f"  {what}: {report.summary()} in {report.seconds:.1f} s")
        return pieces, report.record()

    key = b"conform" + mesh[0].tobytes() + mesh[1].tobytes() + b"".join(h.vertices.tobytes() for h in hulls)
    key += json.dumps([settings.record(), CONVERTER_VERSION], sort_keys=True).encode()
    pieces, record = _cached(cache, key, make)
    return pieces, ConformReport(**record)


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
    conformed: dict[str, ConformReport] = {}
    while options.collision == "convex":
        hulls = {}
        for part, m in (("plug", plug), ("socket", socket)):
            raw = _pieces(m, settings[part], options.max_pieces, cache, log)
            hulls[part], conformed[part] = _conformed(m, raw, options.conform, cache, part, log)
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
        holes = {part: r.uncovered for part, r in conformed.items() if not r.covered}
        if report.passed and not holes:
            break
        refine = sorted(set(report.refine()) | set(holes))
        finer = {part: settings[part].threshold / 2.0 for part in refine}
        if not finer or all(settings[p].threshold <= options.min_threshold for p in finer):
            raise ClearanceLost(report, {p: settings[p].threshold for p in refine}, holes)
        for part, threshold in finer.items():
            settings[part] = replace(settings[part], threshold=max(threshold, options.min_threshold))
        log(
            f"  refining {', '.join(finer)}: CoACD threshold {', '.join(f'{settings[p].threshold:g}' for p in finer)}"
        )

    audit: ContactAudit | None = None
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
    texts = {
        TOOL_FILE: tool.to_xml(),
        TARGET_FILE: target_fragment(socket, hulls["socket"], z_tip, options, key).to_xml(),
    }
    if report is not None:  # audit what is written (MuJoCo's XML keeps 6 significant digits)
        sweep = sweep_for(plug, socket, z_tip, key.symmetry, report.nominal_m)
        written = {name: mujoco.MjSpec.from_string(text) for name, text in texts.items()}
        audit = audit_fragments(
            written[TOOL_FILE], written[TARGET_FILE], plug, socket, z_tip, sweep, options.audit_tolerance_deg
        )
        log(f"  {audit.summary()}")
        if not audit.passed:
            raise ContactsUnsound(audit)
    out_dir.mkdir(parents=True, exist_ok=True)
    for name, text in texts.items():
        (out_dir / name).write_text(text)
    manifest = {
        "input_hash": digest,
        "plug_file": str(plug_path),
        "socket_file": str(socket_path),
        "options": options.record(),
        "thresholds": {part: s.threshold for part, s in settings.items()},
        "collision": options.collision,
        "pieces": {part: len(h) for part, h in hulls.items()},
        "clearance": None if report is None else report.record(),
        "conform": {part: r.record() for part, r in conformed.items()},
        "contact_audit": None if audit is None else audit.record(),
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
