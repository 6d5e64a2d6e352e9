"""USD export read back with pxr: stage metadata, prims, time samples equal to the frames,
value clips, per-variant primvars, and no half-written stage after a kill."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from conftest import overrides
from pxr import Usd, UsdGeom

import warpcloth as wc
from warpcloth.io.load import load_recording
from warpcloth.viz import usd
from warpcloth.viz.usd import export_usd

ROTATION = overrides(run__duration_s=0.2, strip__spacing_mm=5.0, integrator__dt_s=1e-5)
SWING = overrides(run__duration_s=0.3, release__settle_time_s=0.1)


@pytest.fixture(scope="module")
def rotation_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("rotation")
    wc.simulate(wc.load_scene("impulsive_rotation", ROTATION), out=out)
    return out


@pytest.fixture(scope="module")
def swing_batch(tmp_path_factory):
    out = tmp_path_factory.mktemp("batch")
    scenes = [wc.load_scene("damped_swing", [*SWING, f"damping.gamma_per_s={g}"]) for g in (0.1, 0.5, 2.0)]
    wc.simulate(scenes, out=out)
    return out


def curve_points(stage, path, frame):
    return np.array(UsdGeom.BasisCurves(stage.GetPrimAtPath(path)).GetPointsAttr().Get(frame))


def test_stage_metadata_prims_and_samples_round_trip(rotation_run, tmp_path):
    recording = load_recording(rotation_run)
    n_frames, _, n_nodes, _ = recording.frames.shape
    path = export_usd(recording, tmp_path / "rotation.usda")
    stage = Usd.Stage.Open(str(path))
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert "metersPerUnit = 1" in path.read_text()  # written, not defaulted (a default reads as 0.01)
    assert stage.GetTimeCodesPerSecond() == stage.GetFramesPerSecond() == 60.0
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (0, n_frames - 1)
    assert stage.GetDefaultPrim().GetPath() == "/World"
    curves = UsdGeom.BasisCurves(stage.GetPrimAtPath("/World/Strips/variant_0000"))
    assert curves.GetTypeAttr().Get() == UsdGeom.Tokens.linear
    assert curves.GetWrapAttr().Get() == UsdGeom.Tokens.nonperiodic
    assert list(curves.GetCurveVertexCountsAttr().Get()) == [n_nodes]
    assert curves.GetCurveVertexCountsAttr().GetNumTimeSamples() == 0  # topology is static
    assert curves.GetPointsAttr().GetNumTimeSamples() == n_frames
    assert curves.GetExtentAttr().GetNumTimeSamples() == n_frames
    assert len(curves.GetWidthsAttr().Get()) == 1
    for f in (0, n_frames // 2, n_frames - 1):
        points = curve_points(stage, "/World/Strips/variant_0000", f)
        np.testing.assert_allclose(points[:, :2], recording.frames[f, 0], atol=1e-7)  # float32 of ~0.1 m
        assert np.all(points[:, 2] == 0)
        lo, hi = np.array(curves.GetExtentAttr().Get(f))
        assert np.all(points >= lo) and np.all(points <= hi)
    # The clamp prim carries the recorded rigid motion: its box's lower edge follows
    # the clamp-edge node of the frames (the rotation turns it by 1.3 rad here).
    clamp = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Clamps/variant_0000"))
    box = np.array(clamp.GetPointsAttr().Get())
    lower_edge = box[box[:, 1] == box[:, 1].min()].mean(axis=0)
    edge_node = recording.n_clamped - 1
    turned = False
    for f in range(0, n_frames, 3):
        matrix = np.array(clamp.ComputeLocalToWorldTransform(f))
        placed = np.append(lower_edge, 1.0) @ matrix
        np.testing.assert_allclose(placed[:2], recording.frames[f, 0, edge_node], atol=1e-9)
        turned |= abs(matrix[0, 1]) > 0.5
    assert turned


def test_batch_gets_a_prim_per_variant_with_its_parameters(swing_batch, tmp_path):
    recording = load_recording(swing_batch)
    stage = Usd.Stage.Open(str(export_usd(recording, tmp_path / "batch.usdc", ribbon=True)))
    strips = stage.GetPrimAtPath("/World/Strips").GetChildren()
    assert [p.GetName() for p in strips] == ["variant_0000", "variant_0001", "variant_0002"]
    colours = []
    for j, prim in enumerate(strips):
        api = UsdGeom.PrimvarsAPI(prim)
        gamma = api.GetPrimvar("warpcloth:damping:gamma_per_s")
        assert gamma.GetInterpolation() == UsdGeom.Tokens.constant
        assert list(gamma.Get()) == [recording.scenes[j].damping.gamma_per_s]
        colours.append(tuple(UsdGeom.Gprim(prim).GetDisplayColorAttr().Get()[0]))
        np.testing.assert_allclose(curve_points(stage, prim.GetPath(), 9)[:, :2], recording.frames[9, j], atol=1e-7)
    assert len(set(colours)) == 3
    ribbon = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Ribbons/variant_0001"))
    vertices = np.array(ribbon.GetPointsAttr().Get(9))
    width = recording.scenes[1].strip.width_mm * 1e-3
    np.testing.assert_allclose(vertices[0::2, :2], recording.frames[9, 1], atol=1e-7)
    np.testing.assert_allclose(vertices[1::2, 2] - vertices[0::2, 2], width, rtol=1e-6)


def test_many_variants_share_one_curves_prim(swing_batch, tmp_path, monkeypatch):
    monkeypatch.setattr(usd, "PRIM_PER_STRIP_LIMIT", 2)
    recording = load_recording(swing_batch)
    stage = Usd.Stage.Open(str(export_usd(recording, tmp_path / "many.usd")))
    curves = UsdGeom.BasisCurves(stage.GetPrimAtPath("/World/Strips/curves"))
    n_nodes = recording.frames.shape[2]
    assert list(curves.GetCurveVertexCountsAttr().Get()) == [n_nodes] * 3
    gamma = UsdGeom.PrimvarsAPI(curves).GetPrimvar("warpcloth:damping:gamma_per_s")
    assert gamma.GetInterpolation() == UsdGeom.Tokens.uniform and list(gamma.Get()) == [0.1, 0.5, 2.0]
    points = curve_points(stage, "/World/Strips/curves", 12).reshape(3, n_nodes, 3)
    np.testing.assert_allclose(points[..., :2], recording.frames[12], atol=1e-7)
    with pytest.raises(wc.ArgumentError, match="^ribbon: "):
        export_usd(recording, tmp_path / "many_ribbons.usd", ribbon=True)


def test_value_clips_give_the_same_samples_and_move_with_the_file(rotation_run, tmp_path):
    recording = load_recording(rotation_run)
    n_frames = len(recording.frame_times)
    export_usd(recording, tmp_path / "a" / "clipped.usdc", frames_per_clip=4)
    (clips_dir,) = (tmp_path / "a").glob("clipped_clips_*")
    assert len(list(clips_dir.glob("frames-*.usdc"))) == -(-n_frames // 4)
    export_usd(recording, tmp_path / "a" / "clipped.usdc", frames_per_clip=5)  # replaces the old clips
    (clips_dir,) = (tmp_path / "a").glob("clipped_clips_*")
    assert len(list(clips_dir.glob("frames-*.usdc"))) == -(-n_frames // 5)
    (tmp_path / "a").rename(tmp_path / "moved")  # asset paths are relative
    stage = Usd.Stage.Open(str(tmp_path / "moved" / "clipped.usdc"))
    assert stage.GetTimeCodesPerSecond() == 60.0 and stage.GetEndTimeCode() == n_frames - 1
    for f in range(n_frames):
        np.testing.assert_allclose(
            curve_points(stage, "/World/Strips/variant_0000", f)[:, :2], recording.frames[f, 0], atol=1e-7
        )


def test_sweep_variants_are_selected_by_range_and_by_parameter(tmp_path):
    sweep = wc.expand(
        {
            "run": {"duration_s": 0.1},
            "release": {"settle_time_s": 0.05},
            "sweep": {"grid": {"damping.gamma_per_s": [0.1, 0.2, 0.4, 0.8]}},
        }
    )
    wc.run_sweep(sweep, tmp_path / "sweep", workers=0, frames=True, probes="all", progress=False)
    picked = load_recording(tmp_path / "sweep", variants="1:4", where="damping.gamma_per_s<0.5")
    assert list(picked.variants) == [1, 2]
    single = wc.simulate(sweep.scenes[2])
    np.testing.assert_array_equal(picked.frames[:, 1], single.frames[:, 0])
    stage = Usd.Stage.Open(str(export_usd(picked, tmp_path / "sweep.usda")))
    assert [p.GetName() for p in stage.GetPrimAtPath("/World/Strips").GetChildren()] == ["variant_0001", "variant_0002"]
    with pytest.raises(wc.ArgumentError, match="^where: "):
        load_recording(tmp_path / "sweep", where="damping.gamma_per_s>9")
    with pytest.raises(wc.ArgumentError, match="^variants: "):
        load_recording(tmp_path / "sweep", variants="7")
    no_frames = wc.expand(
        {
            "run": {"duration_s": 0.05},
            "release": {"settle_time_s": 0.05},
            "sweep": {"grid": {"damping.gamma_per_s": [0.1]}},
        }
    )
    wc.run_sweep(no_frames, tmp_path / "bare", workers=0, progress=False)
    with pytest.raises(wc.DataFileError, match="--frames"):
        load_recording(tmp_path / "bare")


def test_a_failed_export_leaves_the_previous_file_whole(rotation_run, tmp_path, monkeypatch):
    recording = load_recording(rotation_run)
    target = tmp_path / "stage.usdc"
    export_usd(recording, target)
    before = target.read_bytes()

    def broken(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(usd, "_author_clamp", broken)
    with pytest.raises(OSError, match="disk full"):
        export_usd(recording, target)
    assert target.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["stage.usdc"]  # no temporaries left


def test_a_killed_export_leaves_a_complete_stage_or_none(swing_batch, tmp_path):
    # A real SIGKILL of an exporting process at several moments: the stage is either
    # absent or opens with every frame (it is only renamed into place when complete).
    script = (
        "import sys; from warpcloth import load_recording, export_usd;"
        "r = load_recording(sys.argv[1]); print('ready', flush=True);"
        "[export_usd(r, sys.argv[2] + f'/k{i}.usda', ribbon=True) for i in range(1000)]"
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", script, str(swing_batch), str(tmp_path)], stdout=subprocess.PIPE, text=True
    )
    assert proc.stdout.readline().strip() == "ready"
    time.sleep(1.5)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    n_frames = len(np.load(swing_batch / "frame_times.npy"))
    stages = sorted(tmp_path.glob("k*.usda"))
    assert stages, "no export finished in 1.5 s; the kill test needs at least one"
    for path in stages:
        stage = Usd.Stage.Open(str(path))
        points = UsdGeom.BasisCurves(stage.GetPrimAtPath("/World/Strips/variant_0002")).GetPointsAttr()
        assert points.GetNumTimeSamples() == n_frames
    # The one being written when the kill came is only a temporary directory.
    assert all(p.name.startswith(".k") for p in tmp_path.iterdir() if p.is_dir())


def test_a_diverged_strip_is_hidden_and_an_interrupted_run_is_cut(tmp_path):
    # Forward Euler at dt = 2e-5 s blows up the default strip (tests/test_batch.py); the
    # soft, damped one runs on. The diverged strip's frames are NaN on disk, it keeps
    # its last shape for drawing and is hidden from its divergence on; the clamp stays
    # finite.
    def hanging(**fields):
        return wc.load_scene(
            "damped_swing",
            overrides(
                release__enabled=False,
                integrator__dt_s=2e-5,
                integrator__scheme="forward",
                run__duration_s=0.3,
                **fields,
            ),
        )

    scenes = [
        hanging(damping__gamma_per_s=0.0),
        hanging(damping__gamma_per_s=400.0, material__tensile_gf_per_cm=[20.0, 0.0, 0.0, 0.0]),
    ]
    wc.simulate(scenes, out=tmp_path / "run", on_divergence="record")
    recording = load_recording(tmp_path / "run")
    alive = recording.alive
    assert alive[0, 0] and not alive[-1, 0] and alive[:, 1].all()
    last = int(np.nonzero(alive[:, 0])[0][-1])
    np.testing.assert_array_equal(recording.drawable_frames[-1, 0], recording.frames[last, 0])
    stage = Usd.Stage.Open(str(export_usd(recording, tmp_path / "d.usda")))
    hidden = UsdGeom.Imageable(stage.GetPrimAtPath("/World/Strips/variant_0000")).GetVisibilityAttr()
    assert hidden.Get(last) == UsdGeom.Tokens.inherited and hidden.Get(last + 1) == UsdGeom.Tokens.invisible
    healthy = UsdGeom.Imageable(stage.GetPrimAtPath("/World/Strips/variant_0001"))
    assert healthy.GetVisibilityAttr().GetNumTimeSamples() == 0
    clamp = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Clamps/variant_0000"))
    assert np.isfinite(np.array(clamp.ComputeLocalToWorldTransform(len(recording.frame_times) - 1))).all()
    # An interrupted run (meta.json still says incomplete): read up to its last frame.
    meta = tmp_path / "run" / "meta.json"
    info = json.loads(meta.read_text())
    info["complete"], info["committed"]["frames"] = False, 12
    meta.write_text(json.dumps(info))
    cut = load_recording(tmp_path / "run")
    assert not cut.complete and len(cut.frame_times) == 12 and np.isfinite(cut.frames[:, 1]).all()


def test_a_sweep_whose_material_file_changed_is_refused(tmp_path):
    import importlib.resources

    material = tmp_path / "fabric.toml"
    bundled = importlib.resources.files("warpcloth.scenes") / "materials" / "wool90-nylon10.toml"
    material.write_text(bundled.read_text())
    sweep = wc.expand(
        {
            "run": {"duration_s": 0.05},
            "release": {"settle_time_s": 0.05},
            "material": {"from_file": str(material)},
            "sweep": {"grid": {"damping.gamma_per_s": [0.1]}},
        }
    )
    wc.run_sweep(sweep, tmp_path / "sweep", workers=0, frames=True, probes="all", progress=False)
    assert load_recording(tmp_path / "sweep").scenes[0].material.density_g_per_cm2 == 0.0203
    material.write_text(material.read_text().replace("density_g_per_cm2 = 2.03e-2", "density_g_per_cm2 = 4e-2"))
    with pytest.raises(wc.DataFileError, match="no longer resolve"):
        load_recording(tmp_path / "sweep")
