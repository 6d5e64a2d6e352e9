"""How well `warpcloth track` recovers the bundled example's simulated markers.

    python benchmarks/track_accuracy.py

Calibrates on scenes/data/track/board_*.png, tracks rotation.avi and compares with
truth.csv (the simulation's markers at each frame's time): the error in the clamp-edge
frame (mm: centroiding and calibration together) and in the image (px: the tracked
centroid against the true marker centre projected by the renderer's own camera, so
centroiding alone); and the centreline without markers at the markers' arc lengths.
Results in benchmarks/RESULTS.md.
"""

import json
from pathlib import Path

import numpy as np

from warpcloth.io.measured import read_tracked_shapes
from warpcloth.track.calibration import calibrate_plane, read_image
from warpcloth.track.camera import Camera, PlanePose
from warpcloth.track.centreline import track_centreline
from warpcloth.track.markers import track_markers
from warpcloth.track.video import read_frames

DATA = Path(__file__).resolve().parents[1] / "scenes" / "data" / "track"


def main():
    described = json.loads((DATA / "truth.json").read_text())
    mapping, record = calibrate_plane([DATA / f"board_{i}.png" for i in range(6)], (11, 10), 10.0, origin_corner=(1, 1))
    frames = read_frames(DATA / "rotation.avi")
    s = np.array(described["example"]["marker_s_mm"])
    tracked = track_markers(
        frames, read_image(DATA / "background.png", "--background"), mapping, s, 2.4, DATA / "rotation.avi"
    )
    truth = read_tracked_shapes(DATA / "truth.csv")
    true_mm = np.column_stack([truth.x, truth.y]).reshape(len(frames.t), len(s), 2) * 1e3
    error_mm = tracked.mm - true_mm
    cam = described["camera"]
    k = np.array(cam["matrix"])
    camera = Camera(k[0, 0], k[1, 1], k[0, 2], k[1, 2], tuple(cam["distortion"]), *cam["image_size_px"])
    plane = PlanePose(
        np.array(described["strip_plane"]["rotation"]), np.array(described["strip_plane"]["translation_mm"])
    )
    true_px = camera.project(plane.to_camera(true_mm * [1, -1]))  # plane coordinates (x, −y)
    error_px = tracked.px - true_px
    print(
        f"calibration: reprojection RMS {record['reprojection_rms_px']:.4f} px, plane view "
        f"{record['plane_view']['rms_mm']:.4f} mm"
    )
    for name, error, unit in (("plane (centroid + calibration)", error_mm, "mm"), ("image (centroid)", error_px, "px")):
        flat = error.reshape(-1, 2)
        bias, rms = flat.mean(axis=0), np.sqrt(np.mean(flat**2, axis=0))
        print(
            f"{name}: bias x {bias[0]:+.4f}, y {bias[1]:+.4f} {unit}; RMS x {rms[0]:.4f}, y {rms[1]:.4f} {unit}; "
            f"largest |error| {np.max(np.linalg.norm(flat, axis=1)):.4f} {unit}"
        )
    print(f"reported uncertainty u: median {np.median(tracked.u_mm):.4f} mm, {np.median(tracked.u_px):.4f} px")
    line = track_centreline(
        frames, read_image(DATA / "background.png", "--background"), mapping, s, 100.0, DATA / "rotation.avi"
    )
    flat = (line.mm - true_mm).reshape(-1, 2)
    bias, rms = flat.mean(axis=0), np.sqrt(np.mean(flat**2, axis=0))
    print(
        f"centreline (no markers; s from the free end): bias x {bias[0]:+.4f}, y {bias[1]:+.4f} mm; RMS x "
        f"{rms[0]:.4f}, y {rms[1]:.4f} mm; largest |error| {np.max(np.linalg.norm(flat, axis=1)):.4f} mm"
    )


if __name__ == "__main__":
    main()
