"""The pieces of a video frame beyond the rendered views: the labels, the force-over-time
strip and the H.264 encoder (PyAV). Used by :mod:`compliant_docking.viz.render`; Pillow
and PyAV are imported only when a video is made."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

#: colours (RGB) of the overlay
STRIP_BG, TEXT, MUTED = (28, 30, 36), (235, 235, 240), (150, 152, 160)
PAST, FUTURE, CURSOR, BUDGET = (90, 170, 255), (85, 88, 98), (255, 210, 80), (230, 90, 80)


def overlay_font(size: int):
    from PIL import ImageFont

    try:
        return ImageFont.load_default(size=size)  # Pillow ≥ 10.1 with FreeType
    except TypeError:
        return ImageFont.load_default()


class Labels:
    """The run's title and each view's name, drawn once and blended into every frame."""

    def __init__(self, width: int, height: int, title: str, labels: list[str]):
        from PIL import Image, ImageDraw

        size = max(10, height // 32)
        font = overlay_font(size)
        layer = Image.new("RGBA", (width, min(height, int(3.2 * size) + 8)), (0, 0, 0, 0))
        draw = ImageDraw.Draw(layer)
        if title:
            draw.text((8, 6), title, fill=TEXT, font=font, stroke_width=2, stroke_fill=(0, 0, 0))
        view_w = width // len(labels)
        for i, label in enumerate(labels):
            draw.text(
                (i * view_w + 8, 6 + 1.5 * size if i == 0 and title else 6),
                label,
                fill=MUTED,
                font=font,
                stroke_width=2,
                stroke_fill=(0, 0, 0),
            )
        rgba = np.asarray(layer).astype(np.float32)
        self.alpha = rgba[..., 3:] / 255.0
        self.premultiplied = rgba[..., :3] * self.alpha

    def paint(self, image: np.ndarray) -> None:
        """Blend the labels into the top rows of ``image`` (in place)."""
        top = image[: self.alpha.shape[0]]
        top[:] = (top * (1.0 - self.alpha) + self.premultiplied).astype(np.uint8)


class ForceStrip:
    """The overlay below the views: text on the left, the axial force over time on the right."""

    def __init__(self, width: int, height: int, t: np.ndarray, axial: np.ndarray, budget: float | None):
        from PIL import Image, ImageDraw

        self.width, self.height = width, height
        self.size = max(10, height // 5)
        self.font, self.big = overlay_font(self.size), overlay_font(int(self.size * 1.35))
        self.text_w = min(width // 2, int(self.size * 11.5))
        x0, x1 = self.text_w + 6, width - 8
        y0, y1 = 6, height - self.size - 8
        self.x0, self.x1 = x0, x1
        self.t0, self.t1 = float(t[0]), float(t[-1]) if len(t) > 1 else float(t[0]) + 1.0
        finite = np.where(np.isfinite(axial), axial, 0.0)
        # the scale follows the data; the gate's budget is drawn when it is within 1.5× of it
        top = max(float(finite.max(initial=0.0)), 1.0)
        show_budget = budget is not None and 0.0 < budget <= 1.5 * top
        if budget is not None and show_budget:
            top = max(top, budget)
        top *= 1.1
        bottom = min(float(finite.min(initial=0.0)), 0.0) * 1.1
        span = top - bottom

        def y_of(value):
            return y1 - (np.asarray(value) - bottom) / span * (y1 - y0)

        base = Image.new("RGB", (width, height), STRIP_BG)
        draw = ImageDraw.Draw(base)
        draw.line([(x0, y_of(0.0)), (x1, y_of(0.0))], fill=(70, 72, 80))
        if show_budget:
            yb = float(y_of(budget))
            for xa in range(x0, x1, 10):
                draw.line([(xa, yb), (min(xa + 5, x1), yb)], fill=BUDGET)
            draw.text((x1 - 4, yb + 3), f"gate budget {budget:g} N", fill=BUDGET, font=self.font, anchor="rt")
        draw.text((x0, height - 4), f"{self.t0:g} s", fill=MUTED, font=self.font, anchor="ld")
        draw.text((x1, height - 4), f"{self.t1:.3g} s", fill=MUTED, font=self.font, anchor="rd")
        draw.text(
            ((x0 + x1) / 2, height - 4),
            "axial contact force [N] over time",
            fill=MUTED,
            font=self.font,
            anchor="md",
        )
        scale = f"{top / 1.1:.3g} N"
        draw.text((x0 + 2, y0), scale, fill=MUTED, font=self.font, anchor="lt")
        if budget is not None and not show_budget:  # on the left: the curve rises at the end
            left = x0 + 2 + draw.textlength(scale + "   ", font=self.font)
            draw.text(
                (left, y0),
                f"gate budget {budget:g} N: off the scale",
                fill=BUDGET,
                font=self.font,
                anchor="lt",
            )
        past, future = base.copy(), base.copy()
        # one column per pixel: the range of the force over that column's time span
        columns = np.arange(x0, x1 + 1)
        edges = self.t0 + (columns - x0 + np.array([[-0.5], [0.5]])) / max(x1 - x0, 1) * (self.t1 - self.t0)
        idx = np.clip(np.searchsorted(t, edges), 0, len(t) - 1)
        for img, colour in ((past, PAST), (future, FUTURE)):
            d = ImageDraw.Draw(img)
            for c, lo, hi in zip(columns, idx[0], np.maximum(idx[1], idx[0] + 1)):
                seg = finite[lo:hi]
                d.line(
                    [(float(c), float(y_of(seg.min()))), (float(c), float(y_of(seg.max())))],
                    fill=colour,
                    width=2,
                )
        self.past, self.future = np.asarray(past), np.asarray(future)

    def x_of(self, t: float) -> int:
        frac = (t - self.t0) / max(self.t1 - self.t0, 1e-12)
        return int(round(self.x0 + min(max(frac, 0.0), 1.0) * (self.x1 - self.x0)))

    def draw(self, t: float, axial: float, norm: float, contacts: int) -> np.ndarray:
        """The strip at time ``t`` [s] with the current axial force and ‖f‖ [N]."""
        from PIL import Image, ImageDraw

        xc = self.x_of(t)
        out = self.future.copy()
        out[:, :xc] = self.past[:, :xc]
        out[: self.height - self.size - 6, max(xc - 1, 0) : xc + 1] = CURSOR
        img = Image.fromarray(out[:, : self.text_w])
        draw = ImageDraw.Draw(img)
        s = self.size
        draw.text((8, 4), f"t = {t:6.2f} s", fill=TEXT, font=self.big)
        axial_text = "n/a" if not math.isfinite(axial) else f"{axial:7.2f} N"
        norm_text = "n/a" if not math.isfinite(norm) else f"{norm:.2f} N"
        draw.text((8, 4 + 1.6 * s), f"axial force {axial_text}", fill=PAST, font=self.font)
        draw.text((8, 4 + 2.8 * s), f"|f| {norm_text} · contacts {contacts}", fill=MUTED, font=self.font)
        out[:, : self.text_w] = np.asarray(img)
        return out


class Encoder:
    """H.264 (libx264, else MPEG-4 part 2) into an MP4 container, through PyAV."""

    def __init__(self, path: Path, width: int, height: int, fps: int, crf: int):
        import av

        self._av = av
        self.container = av.open(str(path), mode="w", format="mp4")
        if "libx264" in av.codecs_available:
            self.stream = self.container.add_stream(
                "libx264", rate=fps, options={"crf": str(int(crf)), "preset": "veryfast"}
            )
        else:  # a PyAV build without x264
            self.stream = self.container.add_stream("mpeg4", rate=fps)
            self.stream.bit_rate = 4_000_000
        self.stream.width, self.stream.height = width, height
        self.stream.pix_fmt = "yuv420p"

    def add(self, rgb: np.ndarray) -> None:
        frame = self._av.VideoFrame.from_ndarray(np.ascontiguousarray(rgb), format="rgb24")
        for packet in self.stream.encode(frame):
            self.container.mux(packet)

    def __enter__(self) -> Encoder:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        try:
            if exc_type is None:
                for packet in self.stream.encode():  # flush
                    self.container.mux(packet)
        finally:
            self.container.close()
