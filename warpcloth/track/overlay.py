"""The figure of what was tracked: one frame with every marker's path and that frame's
markers on it, beside the tracked shapes in the clamp-edge frame."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .markers import Tracked

__all__ = ["overlay_figure", "write_overlay"]


def overlay_figure(image: np.ndarray, tracked: Tracked, frame: int) -> object:
    """A matplotlib figure: ``image`` (the frame at position ``frame`` of ``tracked``)
    with each marker's pixel path over all frames and its position in this frame, and
    every frame's shape in mm (the shown one in black)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 5.6), width_ratios=(1.1, 1))
    left.imshow(image, cmap="gray", vmin=0, vmax=255)
    for m in range(len(tracked.s_mm)):
        left.plot(tracked.px[:, m, 0], tracked.px[:, m, 1], "-", color="tab:orange", lw=0.7, alpha=0.8)
    left.scatter(tracked.px[frame, :, 0], tracked.px[frame, :, 1], s=60, facecolors="none", edgecolors="tab:red",
                 linewidths=1.0)
    for m, s in enumerate(tracked.s_mm):
        left.annotate(f"{s:g}", tracked.px[frame, m], xytext=(6, -6), textcoords="offset points", color="tab:red",
                      fontsize=7)
    left.set_title(f"frame {tracked.frame[frame]} at t = {tracked.t[frame]:.4f} s: markers (s in mm) and their paths")
    left.set_axis_off()
    for f in range(len(tracked.t)):
        shown = f == frame
        right.plot(tracked.mm[f, :, 0], tracked.mm[f, :, 1], "o-" if shown else "-", ms=3,
                   color="black" if shown else plt.cm.viridis(f / max(len(tracked.t) - 1, 1)), lw=1.4 if shown else 0.8)
    right.plot([0], [0], "s", color="tab:red", label="clamp's lowest point at rest")
    right.set_aspect("equal")
    right.set_xlabel("x (mm)")
    right.set_ylabel("y (mm)")
    right.set_title(f"tracked shapes, every frame (median uncertainty {np.median(tracked.u_mm) * 1e3:.2g} µm)")
    right.legend(loc="lower left", fontsize=8)
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
