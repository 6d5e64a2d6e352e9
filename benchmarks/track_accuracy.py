"""How well `warpcloth track` recovers the truth of video it did not render itself.

    python benchmarks/track_accuracy.py            # the independent rig (scenes/data/rig/)
    python benchmarks/track_accuracy.py --own      # warpcloth's own renderer (scenes/data/track/)
    python benchmarks/track_accuracy.py --lossless # and the rig's dyed edge with every pixel's colour (+1 min)

The rig's video (``python -m warpcloth.track.rig``) is warpcloth's simulation of the
impulsive rotation filmed by a renderer that shares nothing with the tracker: its own lens
(not OpenCV's model), a strip of real width and thickness ray-cast in 3-D and seen 19° from
square, dots overhanging its near edge, a dark clamp with steel screws turning in view, a
textured backdrop, 4 ms of motion blur, H.264 in MP4 and JPEG boards. For the markers and
for the dyed edge (its silhouette, and the midline with the fabric's thickness) it prints
the bias and RMS per coordinate against the truth, how often the stated uncertainty covers
the error (within 1σ and 2σ per coordinate), the worst error, and the fit of the tracked
markers. With ``--lossless`` the dyed edge's frames are rendered again and written with
every pixel's colour (FFV1 RGB; H.264 4:2:0 keeps one colour sample per 2 × 2 pixels) and
tracked and fitted the same way. Results in benchmarks/RESULTS.md.
"""

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from warpcloth.io.measured import read_measurement, read_tracked_shapes

ROOT = Path(__file__).resolve().parents[1]


def cli(*args: str) -> subprocess.CompletedProcess:
    done = subprocess.run([sys.executable, "-m", "warpcloth", *args], capture_output=True, text=True)
    if done.returncode not in (0, 6, 9):
        raise SystemExit(f"warpcloth {' '.join(args)} failed:\n{done.stderr}")
    return done


def compare(name: str, tracked: Path, truth_xy_mm: np.ndarray, truth_keys: np.ndarray) -> None:
    shapes = read_measurement(tracked)
    keys = shapes.frame * 100_000 + np.rint(shapes.s * 1e6).astype(int)
    where = {k: i for i, k in enumerate(truth_keys)}
    rows = np.array([where[k] for k in keys])
    error = np.column_stack([shapes.x, shapes.y]) * 1e3 - truth_xy_mm[rows]
    u = shapes.u[:, None] * 1e3
    bias, rms = error.mean(axis=0), np.sqrt(np.mean(error**2, axis=0))
    print(
        f"{name}: bias x {bias[0]:+.4f}, y {bias[1]:+.4f} mm; RMS x {rms[0]:.4f}, y {rms[1]:.4f} mm; largest "
        f"|error| {np.max(np.linalg.norm(error, axis=1)):.4f} mm ({len(error)} points in "
        f"{len(np.unique(shapes.frame))} frames)"
    )
    if shapes.u_along is None:
        print(
            f"  stated u median {np.median(u):.4f} mm, covers {np.mean(np.abs(error) <= u):.0%} within 1σ and "
            f"{np.mean(np.abs(error) <= 2 * u):.0%} within 2σ per coordinate"
        )
        return
    # a curve's points: across the strip (u_mm) and along it (u_along_mm), by the truth's tangent
    frame = truth_keys // 100_000
    tangent = np.zeros_like(truth_xy_mm)
    for f in np.unique(frame):
        at = frame == f
        tangent[at] = np.gradient(truth_xy_mm[at], axis=0)
    tangent = tangent[rows] / np.linalg.norm(tangent[rows], axis=1)[:, None]
    parts = {
        "across": (error[:, 0] * -tangent[:, 1] + error[:, 1] * tangent[:, 0], shapes.u * 1e3),
        "along": ((error * tangent).sum(axis=1), shapes.u_along * 1e3),
    }
    for part, (e, stated) in parts.items():
        print(
            f"  {part}: bias {e.mean():+.4f}, RMS {np.sqrt(np.mean(e**2)):.4f} mm; stated u median "
            f"{np.median(stated):.4f} mm, covers {np.mean(np.abs(e) <= stated):.0%} within 1σ and "
            f"{np.mean(np.abs(e) <= 2 * stated):.0%} within 2σ"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--own", action="store_true", help="warpcloth's own renderer's example instead of the rig")
    parser.add_argument("--lossless", action="store_true", help="also the rig's dyed edge recorded losslessly")
    args = parser.parse_args()
    data = ROOT / "scenes" / "data" / ("track" if args.own else "rig")
    described = json.loads((data / "truth.json").read_text())
    boards = sorted(str(p) for p in data.glob("board_*.*"))
    with tempfile.TemporaryDirectory() as scratch:
        out = Path(scratch)
        done = cli("track", "calibrate", *boards, "--board", "11x10", "--square-mm", "10", "--origin-corner", "1,1",
                   "-o", str(out / "plane.json"))  # fmt: skip
        print(done.stdout.strip().splitlines()[0])
        video = data / ("rotation.avi" if args.own else "rotation.mp4")
        rig = [] if args.own else ["--marker-height-mm", str(described["markers"]["z_mm"])]
        cli("track", str(video), "--plane", str(out / "plane.json"), "--background", str(data / "background.png"),
            "--marker-s", "5:95:10", "--marker-diameter-mm", "2.4", "--no-progress", "-o", str(out / "markers.csv"),
            *rig)  # fmt: skip
        truth = read_tracked_shapes(data / "truth.csv")
        keys = truth.frame * 100_000 + np.rint(truth.s * 1e6).astype(int)
        compare("markers", out / "markers.csv", np.column_stack([truth.x, truth.y]) * 1e3, keys)
        cli("fit", "impulsive_rotation", "--measured", str(out / "markers.csv"), "--free",
                  "gamma,rotation_centre_dy_mm", "--bounds", "rotation_centre_dy_mm=0:8", "--no-progress", "--out",
                  str(out / "fit"))  # fmt: skip
        result = json.loads((out / "fit" / "fit.json").read_text())
        dy, gamma = result["parameters"]["clamp.rotation_centre_dy_mm"], result["parameters"]["damping.gamma_per_s"]
        truths = described["truth"] if "truth" in described else described["example"]["truth"]
        true_dy, true_gamma = truths["clamp.rotation_centre_dy_mm"], truths["damping.gamma_per_s"]
        print(
            f"fit of the markers: {result['status']}, dy = {dy['value']:.4f} ± {dy['sigma']:.4f} mm (truth "
            f"{true_dy}: {(dy['value'] - true_dy) / dy['sigma']:+.1f}σ), γ = {gamma['value']:.4f} ± "
            f"{gamma['sigma']:.4f} /s (truth {true_gamma}: {(gamma['value'] - true_gamma) / gamma['sigma']:+.1f}σ), "
            "RMS "
            f"{result['rms_mm']:.4f} mm against the noise {result['noise_mm']:.4f} mm and the mesh's share "
            f"{result['rms_mesh_mm']:.4f} mm"
        )
        if args.own:
            return
        edge_truth = np.loadtxt(data / "edge_truth.csv", delimiter=",", comments=("#", "frame"))
        common = ["--edge-s", "5:95:10", "--free-length-mm", "100", "--edge-colour", "auto", "--no-progress",
                  "--background", str(data / "background.png")]  # fmt: skip
        cli("track", str(data / "edge.mp4"), "--plane", str(out / "plane.json"), *common, "-o", str(out / "edge.csv"))
        keys = edge_truth[:, 0].astype(int) * 100_000 + np.rint(edge_truth[:, 2] * 1e3).astype(int)
        compare("dyed edge, silhouette", out / "edge.csv", edge_truth[:, 5:7], keys)
        videos = {"H.264 4:2:0": data / "edge.mp4"}
        if args.lossless:
            from warpcloth.track.rig import write_lossless_edge

            shown = write_lossless_edge(out / "edge.avi", range(len(np.unique(edge_truth[:, 0]))))
            if np.abs(shown - edge_truth[:, [0, 2, 3, 4]]).max() > 1e-3:  # mm: measured 2e-5
                raise SystemExit("the rig's motion simulated again is not edge_truth.csv's: regenerate the rig")
            videos["lossless RGB"] = out / "edge.avi"
        for k, (label, video) in enumerate(videos.items()):
            midline = out / f"midline-{k}.csv"
            cli("track", str(video), "--plane", str(out / "plane.json"), *common, "--thickness-mm",
                str(described["strip"]["thickness_mm"]), "-o", str(midline))  # fmt: skip
            compare(f"dyed edge, midline (--thickness-mm), {label}", midline, edge_truth[:, 3:5], keys)
            cli("fit", "impulsive_rotation", "--measured", str(midline), "--free",
                      "gamma,rotation_centre_dy_mm", "--bounds", "rotation_centre_dy_mm=0:8", "--no-progress", "--out",
                      str(out / f"fit-{k}"))  # fmt: skip
            result = json.loads((out / f"fit-{k}" / "fit.json").read_text())
            for name, true in (("clamp.rotation_centre_dy_mm", true_dy), ("damping.gamma_per_s", true_gamma)):
                value = result["parameters"][name]
                print(
                    f"fit of the edge's midline, {label}: {result['status']}, {name} = {value['value']:.4f} ± "
                    f"{value['sigma']:.4f} (truth {true}: {(value['value'] - true) / value['sigma']:+.1f}σ)"
                )


if __name__ == "__main__":
    main()
