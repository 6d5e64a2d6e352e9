"""What was tracked, to look at: a figure of one frame with every marker's path and that
frame's markers on it, beside the tracked shapes in the clamp-edge frame; and a video of
every frame with its points circled, at its own time."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from fractions import Fraction
from pathlib import Path

import numpy as np

from warpcloth.errors import ArgumentError

from .markers import Tracked
from .video import Frames, FrameStream

__all__ = ["FINEST_AVI_S", "FONT_SIZE", "avi_timing", "overlay_figure", "write_overlay", "write_overlay_video"]


FONT_SIZE = 11
"""The overlay's text size (pt) at its 12 × 5.6 in: readable at the page width it is
printed or viewed at (matplotlib's 10 pt labels and 7 pt annotations were not)."""


def overlay_figure(image: np.ndarray, tracked: Tracked, frame: int) -> object:
    """A matplotlib figure: ``image`` (the frame at position ``frame`` of ``tracked``)
    with each marker's pixel path over all frames and its position in this frame, and
    every frame's shape in mm coloured by its time (a colourbar is the key; the shown
    frame in black)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    with plt.rc_context({"font.size": FONT_SIZE, "axes.titlesize": FONT_SIZE, "legend.fontsize": FONT_SIZE - 1}):
        fig, (left, right) = plt.subplots(1, 2, figsize=(12, 5.6), width_ratios=(1.1, 1))
        left.imshow(image, cmap="gray", vmin=0, vmax=255)
        for m in range(len(tracked.s_mm)):
            left.plot(tracked.px[:, m, 0], tracked.px[:, m, 1], "-", color="tab:orange", lw=0.8, alpha=0.8)
        left.scatter(
            tracked.px[frame, :, 0],
            tracked.px[frame, :, 1],
            s=60,
            facecolors="none",
            edgecolors="tab:red",
            linewidths=1.2,
        )
        for m, s in enumerate(tracked.s_mm):
            # left of the marker, boxed: the paths run off to the right, and red on the
            # dark frame alone does not read
            left.annotate(
                f"{s:g}",
                tracked.px[frame, m],
                xytext=(-9, 0),
                textcoords="offset points",
                ha="right",
                va="center",
                color="tab:red",
                bbox={"fc": "white", "alpha": 0.8, "lw": 0, "pad": 1},
            )
        left.set_title(
            f"frame {tracked.frame[frame]}, t = {tracked.t[frame]:.4f} s: markers (red, s in mm)\n"
            "and their paths over the video (orange)"
        )
        left.set_axis_off()
        time = matplotlib.colors.Normalize(float(tracked.t[0]), float(tracked.t[-1]))
        for f in range(len(tracked.t)):
            if f != frame:
                right.plot(
                    tracked.mm[f, :, 0], tracked.mm[f, :, 1], "-", color=plt.cm.viridis(time(tracked.t[f])), lw=0.8
                )
        right.plot(
            tracked.mm[frame, :, 0],
            tracked.mm[frame, :, 1],
            "o-",
            ms=3,
            color="black",
            lw=1.4,
            label=f"frame {tracked.frame[frame]} (left)",
        )
        right.plot([0], [0], "s", color="tab:red", label="clamp's lowest point at rest")
        right.set_aspect("equal", adjustable="datalim")  # the axes keep their width; the data range grows
        right.set_xlabel("x from the clamp edge (mm)")
        right.set_ylabel("y from the clamp edge (mm)")
        right.set_title(
            f"tracked shapes, every frame\n(median uncertainty {np.nanmedian(tracked.u_mm) * 1e3:.2g} µm "
            + ("across the strip)" if tracked.u_along_mm is not None else "per coordinate)")
        )
        right.legend(loc="lower right")
        fig.colorbar(matplotlib.cm.ScalarMappable(time, "viridis"), ax=right, label="t (s)", shrink=0.85)
        fig.tight_layout()
    return fig


def write_overlay(path: str | Path, image: np.ndarray, tracked: Tracked, frame: int) -> None:
    """The :func:`overlay_figure` as a PNG, written atomically."""
    import matplotlib.pyplot as plt

    from warpcloth.io.atomic import write_atomically

    fig = overlay_figure(image, tracked, frame)
    try:
        write_atomically(path, lambda tmp: fig.savefig(tmp, dpi=110))
    finally:
        plt.close(fig)


FINEST_AVI_S = Fraction(1, 1000)
"""The finest video time base FFmpeg's AVI muxer keeps (a finer one it replaces by 1/600 s)."""


def avi_timing(times: Sequence[Fraction]) -> tuple[Fraction, list[int], float]:
    """How AVI holds frames at ``times`` (s, exact): the time base (their common divisor,
    the coarsest that keeps every time, or :data:`FINEST_AVI_S` where that is finer), each
    frame's stamp in it, and by how much the times are rounded (s, 0 when exact). Frames
    closer than that time base cannot be held: an error, before anything is written."""
    import math

    exact = Fraction(math.gcd(*(t.numerator for t in times)), math.lcm(*(t.denominator for t in times)))
    time_base = max(exact, FINEST_AVI_S)
    pts = [round(t / time_base) for t in times]
    if any(b <= a for a, b in zip(pts, pts[1:], strict=False)):
        raise ArgumentError(
            "overlay_video",
            f"frames less than {float(FINEST_AVI_S):g} s apart: an AVI written by "
            "FFmpeg holds at most 1000 frames/s (leave --overlay-video out, or use --overlay)",
        )
    return time_base, pts, max(abs(float(t - p * time_base)) for t, p in zip(times, pts, strict=True))


def write_overlay_video(
    path: str | Path, frames: Frames | FrameStream, tracked: Tracked, times: Sequence[Fraction]
) -> None:
    """The frames ``tracked`` was tracked from (``(index, t, image)`` each, in the same
    order, at the exact ``times`` s) with their points circled and labelled, as grey FFV1 in
    AVI, encoded one at a time and written atomically, each frame at its own time as far as
    AVI holds it (:func:`avi_timing`)."""
    import cv2

    from warpcloth.io.atomic import write_atomically

    from .video import write_video

    time_base, pts, _ = avi_timing(times)

    def drawn() -> Iterator[np.ndarray]:
        for f, (_, _, image) in enumerate(frames):
            image = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) if image.ndim == 3 else image.copy()
            for m, s in enumerate(tracked.s_mm):
                if not np.all(np.isfinite(tracked.px[f, m])):  # hidden in this frame
                    continue
                centre = tuple(int(round(v * 16)) for v in tracked.px[f, m])
                cv2.circle(image, centre, 8 * 16, 255, 1, cv2.LINE_AA, 4)
                cv2.putText(
                    image,
                    f"{s:g}",
                    (int(tracked.px[f, m, 0]) + 10, int(tracked.px[f, m, 1]) + 4),
                    cv2.FONT_HERSHEY_SIMPLEX,
                    0.35,
                    255,
                    1,
                    cv2.LINE_AA,
                )
            cv2.putText(
                image,
                f"frame {tracked.frame[f]}  t = {tracked.t[f]:.4f} s",
                (10, 20),
                cv2.FONT_HERSHEY_SIMPLEX,
                0.5,
                255,
                1,
                cv2.LINE_AA,
            )
            yield image

    write_atomically(path, lambda tmp: write_video(tmp, drawn(), pts, time_base))
