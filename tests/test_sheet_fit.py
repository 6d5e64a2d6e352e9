"""Fitting a woven sheet to its tracked markers (stage 3; docs/calibration.md, "Sheets").

The reference is the bundled ``shear_swing_markers``: the bundled shear swing run by
scenes/data/make_motion_examples.py at a 1.25 mm spacing (8× finer than the fit's 10 mm)
with a known shear rigidity G = 1.2 gf/(cm·°) (its material file says 0.8), seen as a
camera facing the sheet sees it, with seeded noise of 0.02 mm. The fit, extrapolated to
h → 0, must find G within 2 σ_total, and call itself converged.
"""

import json
import math
import tomllib

import pytest
from conftest import run_cli

from warpcloth.io.measured import read_sheet_markers
from warpcloth.scene.sheet_build import load_sheet_scene

TRUTH = 1.2  # gf/(cm·°), scenes/data/make_motion_examples.py SHEET_TRUTH
RESOLUTION = ("--set", "sheet.spacing_warp_mm=10", "--set", "sheet.spacing_weft_mm=10", "--set", "run.duration_s=0.3")


@pytest.mark.slow
def test_a_sheets_shear_rigidity_is_fitted_from_its_tracked_markers(tmp_path):
    out = tmp_path / "fit"
    done = run_cli(
        "fit",
        "shear_swing",
        "--measured",
        "shear_swing_markers",
        "--free",
        "G",
        *RESOLUTION,
        "--space-filling",
        "4",
        "--out",
        out,
        "--no-progress",
    )
    assert done.returncode == 0, done.stderr
    fit = json.loads((out / "fit.json").read_text())
    assert fit["status"] == "converged"
    g = fit["parameters"]["shear.rigidity_gf_per_cm_deg"]
    value, sigma = g["value"], g["sigma"]
    assert not g["at_bound"]
    print(f"G = {value:.4f} ± {sigma:.4f} gf/(cm·°) (at 10 mm {g['at_spacing']:.4f}) against {TRUTH}")
    assert abs(value - TRUTH) <= 2 * sigma
    assert sigma == pytest.approx(math.hypot(g["sigma_noise"], g["sigma_mesh"]))
    assert fit["continuum"]["status"] == "extrapolated"
    assert fit["noise_source"] == "estimated from the 4th differences of the fit's residuals"
    assert 0.015e-3 < fit["noise_mm"] * 1e-3 < 0.03e-3  # the data's σ is 0.02 mm; measured 0.025
    assert sigma < 0.05
    residuals = (out / "residuals.csv").read_text().splitlines()
    assert residuals[0] == "t_s,marker,residual_y_mm,residual_z_mm"
    assert len(residuals) - 1 == len(read_sheet_markers("shear_swing_markers").t)
    best = tomllib.loads((out / "best.toml").read_text())
    assert best["shear"]["rigidity_gf_per_cm_deg"] == pytest.approx(value)
    assert load_sheet_scene(out / "best.toml").shear.rigidity_gf_per_cm_deg == pytest.approx(value)  # it reruns
    assert (out / "overlay.png").stat().st_size > 10_000


@pytest.mark.parametrize(
    ("arguments", "expected"),
    [
        (("--free", "G", "--measured", "impulsive_rotation_shapes"), "must name t, marker and at least one of x, y, z"),
        (("--free", "stiffness"), "'stiffness' is neither a field of this sheet scene nor one of gamma, G"),
        (("--free", "sheet.spacing_warp_mm"), "is shared by the sheets of one batch"),
        (("--free", "G", "--bounds", "G=-1:2"), "G = -1 is not a valid sheet scene"),
    ],
    ids=["strip-shapes", "unknown-field", "shared-field", "bad-bound"],
)
def test_a_bad_sheet_fit_is_one_line_naming_what(tmp_path, arguments, expected):
    if "--measured" not in arguments:
        arguments = (*arguments, "--measured", "shear_swing_markers")
    done = run_cli("fit", "shear_swing", *RESOLUTION, *arguments, "--out", tmp_path / "fit", "--no-progress")
    assert done.returncode == 2, done.stderr
    message = done.stderr.strip().splitlines()
    assert len(message) == 1 and "Traceback" not in done.stderr
    assert expected in message[0], message[0]
    assert not (tmp_path / "fit").exists()


def test_markers_in_the_wrong_unit_are_refused(tmp_path):
    measured = tmp_path / "metres.csv"  # headed metres, written in millimetres
    measured.write_text("t_s,marker,z_m,y_m\n0.0,0,-50,-100\n0.01,0,-49.9,-100\n0.02,0,-49.8,-100\n")
    done = run_cli("fit", "shear_swing", *RESOLUTION, "--free", "G", "--measured", measured, "--out", tmp_path / "fit")
    assert done.returncode == 2
    assert "a marker 100 m from the middle of the clamp edge is no marker on a sheet" in done.stderr


def test_a_marker_the_scene_does_not_track_is_refused(tmp_path):
    measured = tmp_path / "markers.csv"
    measured.write_text("t_s,marker,z_mm\n0.0,0,-50\n0.01,4,-49.9\n0.02,0,-49.8\n")
    done = run_cli("fit", "shear_swing", *RESOLUTION, "--free", "G", "--measured", measured, "--out", tmp_path / "fit")
    assert done.returncode == 2
    assert "marker 4 is measured, but the scene tracks 4" in done.stderr
