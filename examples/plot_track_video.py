"""
Tracking markers in video, checked against the simulation that made it
========================================================================

``warpcloth track`` turns lab video into the tracked shapes ``warpcloth fit`` reads. The
bundled video is warpcloth's own impulsive rotation (rotation centre 4.0 mm above the
clamp's lowest point, γ = 0.8 /s) filmed by a synthetic camera tilted away from square,
with lens distortion, uneven lighting, motion blur and sensor noise
(``python -m warpcloth.track.render``), so the tracked markers can be compared with the
simulated ones. This is ``warpcloth track calibrate`` and ``warpcloth track`` step by step.

What to read off: the **calibration's reprojection error**, the overlay (every marker
found, in its order along the strip), and the **error against the truth** in mm, frame by
frame, beside the uncertainty the tracker reports.
"""

# %%
# Calibrate the camera and the strip's plane
# ------------------------------------------
# Six chessboard images (11 × 10 inner corners, 10 mm squares); the first is held in the
# strip's plane with inner corner (1, 1) at the clamp's lowest point.
import importlib.resources
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from warpcloth.io.measured import read_tracked_shapes
from warpcloth.track.calibration import calibrate_plane, read_image
from warpcloth.track.centreline import track_centreline
from warpcloth.track.markers import track_markers
from warpcloth.track.overlay import overlay_figure
from warpcloth.track.video import read_frames

data = Path(str(importlib.resources.files("warpcloth.scenes") / "data" / "track"))
mapping, record = calibrate_plane([data / f"board_{i}.png" for i in range(6)], (11, 10), 10.0, origin_corner=(1, 1))
print(
    f"reprojection RMS {record['reprojection_rms_px']:.3f} px; plane view {record['plane_view']['rms_mm']:.4f} mm, "
    f"{record['plane_view']['mm_per_px'][0]:.3f} to {record['plane_view']['mm_per_px'][1]:.3f} mm/px"
)

# %%
# Track the markers
# -----------------
# Ten dark dots of 2.4 mm, every 10 mm from s = 5 mm; the background is a frame without
# the strip. Each frame's time is the container's timestamp.
frames = read_frames(data / "rotation.avi")
s_mm = np.arange(5.0, 96.0, 10.0)
tracked = track_markers(
    frames, read_image(data / "background.png", "--background"), mapping, s_mm, 2.4, data / "rotation.avi"
)
print(
    f"{len(frames.t)} frames, {len(frames.dropped)} gaps, {len(frames.duplicated)} duplicates; "
    f"median uncertainty {np.median(tracked.u_mm) * 1e3:.2f} µm"
)
middle = len(frames.t) // 2
overlay_figure(frames.images[middle], tracked, middle)
plt.show()

# %%
# Against the truth
# -----------------
# The simulated markers at each frame's time (``truth.csv``). The error is centroiding and
# calibration together; the tracker's reported uncertainty is the sensor noise's share.
truth = read_tracked_shapes(data / "truth.csv")
true_mm = np.column_stack([truth.x, truth.y]).reshape(tracked.mm.shape) * 1e3
error = tracked.mm - true_mm
bias, rms = error.reshape(-1, 2).mean(axis=0), np.sqrt(np.mean(error.reshape(-1, 2) ** 2, axis=0))
print(f"bias x {bias[0]:+.4f} mm, y {bias[1]:+.4f} mm; RMS x {rms[0]:.4f} mm, y {rms[1]:.4f} mm")
fig, ax = plt.subplots(figsize=(7, 3.5))
ax.plot(tracked.t, np.linalg.norm(error, axis=2) * 1e3, ".", color="tab:blue", alpha=0.6)
ax.plot(
    tracked.t,
    np.median(tracked.u_mm, axis=1) * 1e3 * np.sqrt(2),
    "-",
    color="tab:red",
    label="reported uncertainty (both coordinates)",
)
ax.set_xlabel("t (s)")
ax.set_ylabel("|tracked − simulated| (µm)")
ax.set_title("every marker in every frame")
ax.legend()
fig.tight_layout()
plt.show()

# %%
# Without markers
# ---------------
# The strip's centreline at the same arc lengths (``--centreline-s``), measured along the
# line from the free end (``--free-length-mm 100``): the same truth applies. The strip is
# seen edge-on, its thickness (1.6 mm, ``--thickness-mm``) wide: a strip seen wider shows a
# face, whose centre is not the midline, and is refused.
line = track_centreline(
    frames,
    read_image(data / "background.png", "--background"),
    mapping,
    s_mm,
    100.0,
    data / "rotation.avi",
    thickness_mm=1.6,
)
line_error = (line.mm - true_mm).reshape(-1, 2)
print(
    f"centreline: bias x {line_error[:, 0].mean():+.4f} mm, y {line_error[:, 1].mean():+.4f} mm; RMS "
    f"{np.sqrt(np.mean(line_error[:, 0] ** 2)):.4f}, {np.sqrt(np.mean(line_error[:, 1] ** 2)):.4f} mm"
)
