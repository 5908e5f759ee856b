"""The look of every figure (a run's, the comparison across runs, a tuning study's) and how
it is saved: a compact journal style (:data:`STYLE`), PNG unless other formats are asked for.

matplotlib is imported lazily with the non-interactive Agg backend (:func:`apply_style`), so
runs on machines without a display work, and a job that draws nothing never imports it.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

PNG_DPI = 200
#: formats of a figure unless asked otherwise (file suffixes without the dot)
FORMATS = ("png",)
#: formats matplotlib's Agg-based backends write here
KNOWN_FORMATS = ("png", "pdf", "svg")

#: line colours, in order: blue, green, orange, red, violet, two greys
COLORS = ["#0C5DA5", "#00B945", "#FF9500", "#FF2C00", "#845B97", "#474747", "#9e9e9e"]
#: The base style of every figure: small serif text, thin lines, ticks inside on all four
#: sides, no legend frame (the look of SciencePlots' "science" + "no-latex" styles, set here
#: so plotting needs only matplotlib; apply_style then tunes it for speed)
STYLE = {
    "figure.figsize": (3.5, 2.625),
    "xtick.direction": "in",
    "xtick.major.size": 3,
    "xtick.major.width": 0.5,
    "xtick.minor.size": 1.5,
    "xtick.minor.width": 0.5,
    "xtick.top": True,
    "ytick.direction": "in",
    "ytick.major.size": 3,
    "ytick.major.width": 0.5,
    "ytick.minor.size": 1.5,
    "ytick.minor.width": 0.5,
    "ytick.right": True,
    "axes.linewidth": 0.5,
    "grid.linewidth": 0.5,
    "lines.linewidth": 1.0,
    "savefig.pad_inches": 0.05,
    "text.usetex": False,
    "font.family": "serif",
    "font.serif": ["STIXGeneral"],
    "mathtext.fontset": "cm",
}


def apply_style():
    """The figures' style (:data:`STYLE`), tuned for speed; returns pyplot."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update(STYLE)
    plt.rcParams["axes.prop_cycle"] = matplotlib.cycler(color=COLORS)
    plt.rcParams.update(
        {
            "figure.dpi": 100,
            "savefig.dpi": PNG_DPI,
            "savefig.bbox": None,  # a tight box lays every figure out twice; margins are fixed
            "axes.formatter.use_mathtext": False,  # mathtext tick labels: ~0.25 s per run
            "axes.formatter.useoffset": False,  # no "×1e-5 + 5.4999e-1": values as they are
            "axes.grid": True,
            "grid.alpha": 0.3,
            "legend.frameon": False,
            # no minor ticks: laying them out was most of the plotting time
            "xtick.minor.visible": False,
            "ytick.minor.visible": False,
        }
    )
    return plt


def check_formats(formats: Sequence[str]) -> tuple[str, ...]:
    """The formats, lower case without dots; ValueError naming the allowed ones."""
    out = tuple(str(f).lower().lstrip(".") for f in formats)
    unknown = [f for f in out if f not in KNOWN_FORMATS]
    if unknown or not out:
        raise ValueError(
            f"figure formats must be some of {', '.join(KNOWN_FORMATS)}, got {', '.join(map(str, formats)) or 'none'}"
        )
    return out


def save(fig, out_dir: Path, stem: str, formats: Sequence[str] = FORMATS) -> list[Path]:
    """``fig`` as ``out_dir/stem.<format>`` for each format; returns the files."""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for fmt in check_formats(formats):
        path = out_dir / f"{stem}.{fmt}"
        fig.savefig(path)
        paths.append(path)
        fig.set_layout_engine("none")  # laid out once, by the first save (text layout is slow)
    return paths
