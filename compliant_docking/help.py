"""``python -m compliant_docking --help``: the config groups, their options, the defaults.

Hydra's own help would also list the typed schemas (``schema/*``), which are not
choices; this lists only the groups a user composes from.
"""

from __future__ import annotations

from hydra import compose, initialize_config_dir
from hydra.core.global_hydra import GlobalHydra
from omegaconf import OmegaConf

from compliant_docking import CONF_DIR

GROUPS = {
    "robot": "the arm",
    "tool": "the plug on the flange",
    "target": "the socket; none: free space",
    "physics": "MuJoCo options and gravity",
    "controller": "the control law",
    "trajectory": "the planner",
    "task": "start pose, run length, success criteria",
    "render": "video of the run: render=video writes docking.mp4",
    "experiment": "presets, added with +experiment=NAME",
    "robot_controller": "per-robot gains, applied automatically as ${robot}_${controller}",
}
#: groups that are not for composing by hand
HIDDEN = ("hydra", "schema")

USAGE = """\
compliant-docking: simulate a robot arm docking a plug into a socket under compliant control.

Usage:
  python -m compliant_docking [group=option ...] [key=value ...]      one run into runs/
  python -m compliant_docking -m group=a,b [key=v1,v2 ...]            a sweep into runs/multirun/

Examples:
  python -m compliant_docking controller=hqp robot=fr3
  python -m compliant_docking physics=earth controller.k=100
  python -m compliant_docking -m controller=impedance,hqp,se3_lie robot=iiwa14,fr3
  python -m compliant_docking -m +experiment=controller_comparison    (presets: conf/experiment)
  python -m compliant_docking -m <same overrides> resume=last          (finish an interrupted sweep)
  python -m compliant_docking -m <overrides> hydra/launcher=submitit_slurm hydra.launcher.partition=P
  python -m compliant_docking.report runs/multirun/<date>/<time>      (tables and figures again)

Exit status: 0 success, 1 the run failed (error, divergence), 3 the run's gate did not pass.
Hydra's own options: --hydra-help, --cfg job (print the composed config), --info.
"""


def print_help(overrides: list[str]) -> None:
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        loader = GlobalHydra.instance().config_loader()
        print(USAGE)
        print("Configuration groups (group=option; default first):")
        cfg = compose(config_name="config",
                      overrides=[o for o in overrides if "=" in o and not o.startswith("-")])
        groups = [g for g in loader.list_groups("") if not g.startswith(HIDDEN)]
        for group in sorted(groups, key=lambda g: (list(GROUPS).index(g) if g in GROUPS else 99, g)):
            options = sorted(loader.get_group_options(group))
            node = cfg.get(group)
            default = node.get("name") if hasattr(node, "get") else None
            ordered = [default] + [o for o in options if o != default] if default in options else options
            what = f"  — {GROUPS[group]}" if group in GROUPS else ""
            print(f"  {group:<17} {', '.join(ordered)}{what}")
        print("\nThe composed configuration (override any key as key=value):\n")
        print(OmegaConf.to_yaml(cfg))
