"""What a run's figures cost, option by option (the measurement behind run/figures.py).

    python benchmarks/figure_cost.py [--repeats 5]

Runs the default docking run once (no figures) for its time series, then draws its four
figures (:func:`compliant_docking.run.figures.plot_run`) in a fresh process per try,
once with the chosen settings and once with each option that was dropped put back, and
prints the CPU time of the drawing (best of ``--repeats``; CPU time, not wall time, so
other work on this shared machine matters less) and of importing matplotlib.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent

#: name → (formats, rcParams put back on top of the chosen style)
VARIANTS = {
    "chosen: PNG, fixed margins, plain tick labels": (["png"], {}),
    "+ PDF of each figure": (["png", "pdf"], {}),
    "+ mathtext tick labels": (["png"], {"axes.formatter.use_mathtext": True}),
    "+ constrained layout engine": (["png"], {"figure.constrained_layout.use": True}),
    "+ tight bounding box": (["png"], {"savefig.bbox": "tight"}),
    "all of them (the earlier figures)": (
        ["png", "pdf"],
        {
            "axes.formatter.use_mathtext": True,
            "figure.constrained_layout.use": True,
            "savefig.bbox": "tight",
        },
    ),
}

DRAW = """
import json, sys, time
formats, rc, ts_path, out = json.loads(sys.argv[1])
import numpy as np, pandas as pd
ts = pd.read_parquet(ts_path)
start = time.process_time()
from compliant_docking.run import figures
plt = figures.apply_style()
imported = time.process_time()
style = figures.apply_style
def apply_style():
    style().rcParams.update(rc)
    return plt
figures.apply_style = apply_style
from pathlib import Path
figures.plot_run(ts, Path(out), axis=np.array([0.0, 0.0, -1.0]), torque_limits=np.full(7, 100.0),
                  title="iiwa14 · impedance · quintic", formats=formats)
print(json.dumps([imported - start, time.process_time() - imported]))
"""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    from compliant_docking.config import load_config
    from compliant_docking.run.runner import execute

    with tempfile.TemporaryDirectory(prefix="figure_cost_") as name:
        tmp = Path(name)
        execute(load_config("task.progress=false"), tmp / "run", figures=False, echo=False)
        ts_path = str(tmp / "run" / "timeseries.parquet")
        print(f"{'variant':48} {'draw + save [s CPU]':>20} {'import [s CPU]':>15}")
        for label, (formats, rc) in VARIANTS.items():
            times = []
            for i in range(args.repeats):
                arg = json.dumps([formats, rc, ts_path, str(tmp / f"out{i}")])
                result = subprocess.run(
                    [sys.executable, "-c", DRAW, arg], cwd=REPO, capture_output=True, text=True, check=True
                )
                times.append(json.loads(result.stdout.strip().splitlines()[-1]))
            draw = min(t[1] for t in times)
            imported = min(t[0] for t in times)
            print(f"{label:48} {draw:20.2f} {imported:15.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
