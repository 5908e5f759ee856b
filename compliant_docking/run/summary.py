"""The console summary of one run (also saved as ``summary.txt``): the registry's metrics by
section (the contact section for docking runs), then the status, the gate's verdict and
what failed."""

from __future__ import annotations

from pathlib import Path

from omegaconf import DictConfig

from compliant_docking.evaluation import registry
from compliant_docking.evaluation.tracking_gate import summary_rows as tracking_rows

RULE_WIDTH = 64
#: sections always shown; the seat section only for docking runs (or a failed one)
ALWAYS = (registry.CONTACT, registry.INTERNAL, registry.TRACKING)


def format_summary(record: dict, cfg: DictConfig | None = None) -> str:
    """A short aligned summary of a run for the console."""
    r = record.get
    title = ""
    if cfg is not None:
        title = f"{cfg.robot.name} · {cfg.controller.name} · {cfg.trajectory.name} · {cfg.physics.name}"

    def section(name: str, heading: str | None = None) -> list[tuple[str, str | None]]:
        return [(f"[{heading or name}]", None)] + [
            (m.label, m.format(record)) for m in registry.in_section(name)
        ]

    rows: list[tuple[str, str | None]] = []
    if r("status") != "failed":  # a failed run measured nothing: its reason, not a table of n/a
        for name in ALWAYS:
            rows += section(name)
            if name == registry.CONTACT and any(r(key) is not None for key in registry.CONTACT_KEYS):
                rows += section(registry.CONTACT_EVENTS)  # docking runs: what the contact did
        if r("seat_depth_error_m") is not None or (r("gate_failures") and r("tracking_gate") is None):
            rows += section(registry.SEAT, "seat, true socket pose")
        if r("tracking_gate") is not None:  # the free-space tracking gate
            rows += tracking_rows(record)
        rows += section(registry.RUN)
    width = max((len(label) for label, value in rows if value is not None), default=0)
    lines = ["=" * RULE_WIDTH, f"compliant-docking: {title}".rstrip(": "), "=" * RULE_WIDTH]
    for label, value in rows:
        lines.append(label if value is None else f"  {label:<{width}} : {value}")
    status = r("status")
    verdict = "docked" if r("success") else ("FAILED" if status == "failed" else "not docked")
    if status == "ok" and r("gate_verdict") and not r("success"):
        verdict = str(r("gate_verdict"))  # says what failed, e.g. "seated; peak force … over the budget"
    if status == "interrupted":
        verdict = "INTERRUPTED: the metrics cover the part that ran"
    elif status != "failed" and r("tracking_gate") is not None:
        verdict = f"tracking gate {r('tracking_gate')}"
    elif status != "failed" and r("success") is None:
        verdict = "no gate"
    success = "null" if r("success") is None else str(bool(r("success"))).lower()
    if rows:
        lines.append("-" * RULE_WIDTH)
    # "finished" (the run ran) is not "docked" (it passed its gate): both are said
    ran = {"ok": "run finished", "incomplete": "run stopped short", "interrupted": "run interrupted"}
    lines.append(
        f"  {ran.get(str(status), 'run FAILED')}"
        + ("" if status == "failed" else f" · {verdict}")
        + f" (status {status} · success {success})"
    )
    if r("error"):
        lines.append(f"  error: {r('error')}")
    if r("gate_failures") and verdict != r("gate_verdict"):  # the verdict already lists them
        lines.append(f"  gate: {r('gate_failures')}")
    if r("mujoco_warnings"):
        lines.append(f"  MuJoCo warnings: {r('mujoco_warnings')} (mujoco.log in the run directory)")
    return "\n".join(lines)


def display_path(path: Path) -> str:
    """The path relative to the working directory when it lies below it."""
    try:
        return str(Path(path).resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)
