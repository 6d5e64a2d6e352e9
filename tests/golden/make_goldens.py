"""Write the golden outputs that guard refactors: ``python tests/golden/make_goldens.py``.

Probes and frames of both bundled scenes (float64, as bundled) and the summaries of a
small sweep. tests/test_golden.py requires today's code to reproduce them bitwise; they
are regenerated only when a change is *meant* to change results, and the commit says why.
"""

from pathlib import Path

import numpy as np

import warpcloth as wc

HERE = Path(__file__).parent
SCENES = ("damped_swing", "impulsive_rotation")
SWEEP_OVERRIDES = ["sweep.random.samples=6", "run.duration_s=0.4"]


def scene_outputs(name: str) -> dict[str, np.ndarray]:
    """Probes, times and frames of a bundled scene run as bundled."""
    result = wc.simulate(wc.load_scene(name))
    return {"t": result.t, "probes": result.probes, "frame_times": result.frame_times, "frames": result.frames}


def sweep_summary(out: Path) -> "object":
    """Summary table of a small in-process sweep of the bundled calibration sweep."""
    return wc.run_sweep(wc.load_sweep("damped_swing_sweep", SWEEP_OVERRIDES), out, workers=0)


if __name__ == "__main__":
    import tempfile

    for name in SCENES:
        np.savez_compressed(HERE / f"{name}.npz", **scene_outputs(name))
    with tempfile.TemporaryDirectory() as tmp:
        sweep_summary(Path(tmp) / "sweep").to_parquet(HERE / "sweep_summary.parquet", index=False)
    print("wrote", *sorted(p.name for p in HERE.iterdir() if p.suffix in (".npz", ".parquet")))
