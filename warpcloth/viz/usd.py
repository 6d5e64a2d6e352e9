"""USD export: the strips as animated ``BasisCurves`` (and optional ribbons), the clamp
as an animated box, per-variant parameters as primvars.

Stage conventions (written explicitly, since viewers disagree on defaults): upAxis Y,
metersPerUnit 1 (positions are SI metres; an unwritten metersPerUnit reads as 0.01 and
the strip would open 100× too small), time code = shape frame index with
timeCodesPerSecond = framesPerSecond = the scene's frame rate, defaultPrim ``/World``.

Layout: up to ``PRIM_PER_STRIP_LIMIT`` variants get one prim each
(``/World/Strips/variant_0007``, its parameters as constant primvars); more share one
``BasisCurves`` prim with one curve per variant (parameters and colours as uniform
primvars, one value per curve). Long or wide exports are split into value clips
(one layer per chunk of frames, stitched with ``UsdUtils.StitchClips``) so no single
layer grows without bound. Every file is written under a temporary name and renamed:
a killed export leaves the previous file or none, never half a stage.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pandas as pd
from pxr import Gf, Sdf, Tf, Usd, UsdGeom, UsdUtils, Vt

from warpcloth.errors import ArgumentError, InternalError, checked_instance, checked_path
from warpcloth.io.atomic import write_atomically
from warpcloth.io.provenance import provenance
from warpcloth.io.recording import Recording
from warpcloth.io.sheet_run_dir import SheetRun
from warpcloth.viz.geometry import (
    BOX_QUADS,
    clamp_box,
    colour_values,
    points3,
    ribbon_quads,
    ribbon_vertices,
    variant_colours,
)

PRIM_PER_STRIP_LIMIT = 64  # above this, one BasisCurves prim holds every variant
CURVE_WIDTH_M = 1.0e-3  # display width of a curve (the fabric's thickness is not modelled)
CLIP_POINTS = 2_000_000  # node positions per layer above which frames go to value clips
USD_SUFFIXES = (".usd", ".usda", ".usdc")


def check_stage_path(path: str | Path, argument: str = "out_file") -> Path:
    """``path`` as a Path if it names a USD stage file, else an ArgumentError of
    ``argument`` (the caller's name for ``path``)."""
    out = Path(checked_path(argument, path))
    if out.suffix not in USD_SUFFIXES:
        raise ArgumentError(argument, f"{out} must end in one of {', '.join(USD_SUFFIXES)}")
    return out


def _primvar_name(field: str) -> str:
    return "warpcloth:" + field.replace(".", ":")


def _extent(points: np.ndarray, pad: float) -> Vt.Vec3fArray:
    lo, hi = points.min(axis=0) - pad, points.max(axis=0) + pad
    return Vt.Vec3fArray([Gf.Vec3f(*map(float, lo)), Gf.Vec3f(*map(float, hi))])


def _author(stage: Usd.Stage, recording: Recording, frames: range, ribbon: bool) -> None:
    """Define the prims, their static attributes and the time samples of ``frames``."""
    n_variants = len(recording.variants)
    one_prim = n_variants > PRIM_PER_STRIP_LIMIT
    colours = variant_colours(colour_values(recording))
    n_nodes = recording.frames.shape[2]
    points = points3(recording.drawable_frames)  # [frame, variant, node, 3]
    alive = recording.alive
    UsdGeom.Xform.Define(stage, "/World")
    UsdGeom.Scope.Define(stage, "/World/Strips")
    UsdGeom.Scope.Define(stage, "/World/Clamps")
    pad = CURVE_WIDTH_M / 2
    if one_prim:
        curves = UsdGeom.BasisCurves.Define(stage, "/World/Strips/curves")
        curves.CreateTypeAttr(UsdGeom.Tokens.linear)
        curves.CreateWrapAttr(UsdGeom.Tokens.nonperiodic)
        curves.CreateCurveVertexCountsAttr(Vt.IntArray([n_nodes] * n_variants))
        curves.CreateWidthsAttr(Vt.FloatArray([CURVE_WIDTH_M]))
        curves.SetWidthsInterpolation(UsdGeom.Tokens.constant)
        _write_primvars(curves, recording, slice(None), UsdGeom.Tokens.uniform, colours)
        for f in frames:
            flat = points[f].reshape(-1, 3)
            curves.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy(flat), f)
            curves.GetExtentAttr().Set(_extent(flat, pad), f)
    else:
        for j, variant in enumerate(recording.variants):
            name = f"variant_{variant:04d}"
            curve = UsdGeom.BasisCurves.Define(stage, f"/World/Strips/{name}")
            curve.CreateTypeAttr(UsdGeom.Tokens.linear)
            curve.CreateWrapAttr(UsdGeom.Tokens.nonperiodic)
            curve.CreateCurveVertexCountsAttr(Vt.IntArray([n_nodes]))
            curve.CreateWidthsAttr(Vt.FloatArray([CURVE_WIDTH_M]))
            curve.SetWidthsInterpolation(UsdGeom.Tokens.constant)
            _write_primvars(curve, recording, slice(j, j + 1), UsdGeom.Tokens.constant, colours[j : j + 1])
            for f in frames:
                curve.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy(points[f, j]), f)
                curve.GetExtentAttr().Set(_extent(points[f, j], pad), f)
            _hide_after_divergence(curve, alive[:, j], frames)
            if ribbon:
                _hide_after_divergence(
                    _author_ribbon(stage, recording, j, name, frames, colours[j]), alive[:, j], frames
                )
    for j, variant in enumerate(recording.variants):
        _author_clamp(stage, recording, j, f"/World/Clamps/variant_{variant:04d}", frames)


def _hide_after_divergence(prim: UsdGeom.Imageable, alive: np.ndarray, frames: range) -> None:
    # A strip that diverged is hidden from then on (its points hold the last shape).
    if alive.all():
        return
    attr = prim.CreateVisibilityAttr()
    for f in frames:
        attr.Set(UsdGeom.Tokens.inherited if alive[f] else UsdGeom.Tokens.invisible, f)


def _write_primvars(
    prim: UsdGeom.Gprim, recording: Recording, rows: slice, interpolation: str, colours: np.ndarray
) -> None:
    api = UsdGeom.PrimvarsAPI(prim)
    table = recording.parameters.iloc[rows]
    api.CreatePrimvar("warpcloth:variant", Sdf.ValueTypeNames.IntArray, interpolation).Set(
        Vt.IntArray([int(v) for v in table["variant"]])
    )
    for name in table.columns:
        if name == "variant":
            continue
        if pd.api.types.is_numeric_dtype(table[name]):
            api.CreatePrimvar(_primvar_name(name), Sdf.ValueTypeNames.DoubleArray, interpolation).Set(
                Vt.DoubleArray([float(v) for v in table[name]])
            )
        else:  # a choice, e.g. the bending law
            api.CreatePrimvar(_primvar_name(name), Sdf.ValueTypeNames.StringArray, interpolation).Set(
                Vt.StringArray([str(v) for v in table[name]])
            )
    prim.CreateDisplayColorPrimvar(interpolation).Set(Vt.Vec3fArray([Gf.Vec3f(*map(float, c)) for c in colours]))


def _author_ribbon(
    stage: Usd.Stage, recording: Recording, j: int, name: str, frames: range, colour: np.ndarray
) -> UsdGeom.Mesh:
    width = recording.scenes[j].strip.width_mm * 1e-3
    mesh = UsdGeom.Mesh.Define(stage, f"/World/Ribbons/{name}")
    counts, indices = ribbon_quads(recording.frames.shape[2])
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray(counts))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray(indices))
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    mesh.CreateDoubleSidedAttr(True)
    mesh.CreateDisplayColorPrimvar(UsdGeom.Tokens.constant).Set(Vt.Vec3fArray([Gf.Vec3f(*map(float, colour))]))
    for f in frames:
        vertices = ribbon_vertices(recording.drawable_frames[f, j], width)
        mesh.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy(vertices), f)
        mesh.GetExtentAttr().Set(_extent(vertices, 0.0), f)
    return mesh


def _author_clamp(stage: Usd.Stage, recording: Recording, j: int, path: str, frames: range) -> None:
    clamp = UsdGeom.Mesh.Define(stage, path)
    box = clamp_box(recording, j)
    clamp.CreatePointsAttr(Vt.Vec3fArray([Gf.Vec3f(*map(float, p)) for p in box]))
    clamp.CreateFaceVertexCountsAttr(Vt.IntArray([4] * 6))
    clamp.CreateFaceVertexIndicesAttr(Vt.IntArray(BOX_QUADS))
    clamp.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    clamp.CreateExtentAttr(_extent(box, 0.0))
    clamp.CreateDisplayColorPrimvar(UsdGeom.Tokens.constant).Set(Vt.Vec3fArray([Gf.Vec3f(0.35, 0.35, 0.38)]))
    op = clamp.AddTransformOp()
    angle, shift = recording.clamp_pose(j)
    for f in frames:
        c, s = np.cos(angle[f]), np.sin(angle[f])
        # Row-vector convention (USD): p' = p M, so the rotation block is transposed.
        matrix = Gf.Matrix4d(c, s, 0, 0, -s, c, 0, 0, 0, 0, 1, 0, shift[f, 0], shift[f, 1], 0, 1)
        op.Set(matrix, f)


def _set_stage_metadata(stage: Usd.Stage, n_frames: int, fps: float) -> None:
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetTimeCodesPerSecond(fps)
    stage.SetFramesPerSecond(fps)
    stage.SetStartTimeCode(0)
    stage.SetEndTimeCode(max(n_frames - 1, 0))
    # where the stage came from, as strings (USD layer metadata holds plain values)
    stage.GetRootLayer().customLayerData = {
        "warpcloth_provenance": {k: json.dumps(v) if not isinstance(v, str) else v for k, v in provenance().items()}
    }


@contextlib.contextmanager
def usd_write_errors(out: Path) -> Iterator[None]:
    """USD reports a failed write (a full disk, a file-size limit) as a Tf error, not an
    OSError; make it one that names the stage, so the CLI says it in one line."""
    try:
        yield
    except Tf.ErrorException as exc:
        text = str(exc)
        code = next(
            (c for c, words in ((errno.EFBIG, "File too large"), (errno.ENOSPC, "No space left")) if words in text),
            errno.EIO,
        )
        raise OSError(
            code, os.strerror(code) if code != errno.EIO else "USD could not write the stage", str(out)
        ) from None


def export_usd(
    recording: Recording, out_file: str | Path, *, ribbon: bool = False, frames_per_clip: int | None = None
) -> Path:
    """Write ``recording`` as a USD stage at ``out_file`` (.usd, .usda or .usdc).

    ``frames_per_clip`` splits the time samples into value-clip layers of that many
    frames in ``<stem>_clips_<token>/`` beside the file; by default they are split only when
    one layer would hold more than ``CLIP_POINTS`` node positions.
    """
    checked_instance("recording", recording, Recording, "warpcloth.load_recording(run_dir)")
    out = check_stage_path(out_file)
    if ribbon and len(recording.variants) > PRIM_PER_STRIP_LIMIT:
        raise ArgumentError(
            "ribbon",
            f"ribbons are written per variant; select at most {PRIM_PER_STRIP_LIMIT} "
            f"of the {len(recording.variants)} variants (--variants, --where)",
        )
    n_frames, n_variants, n_nodes = recording.frames.shape[:3]
    if frames_per_clip is None and n_frames * n_variants * n_nodes > CLIP_POINTS:
        frames_per_clip = max(1, CLIP_POINTS // (n_variants * n_nodes))
    if frames_per_clip is not None and frames_per_clip < 1:
        raise ArgumentError("frames_per_clip", f"{frames_per_clip} must be at least 1")
    out.parent.mkdir(parents=True, exist_ok=True)
    fps = recording.frame_rate
    with tempfile.TemporaryDirectory(dir=out.parent, prefix=f".{out.stem}.") as tmp, usd_write_errors(out):
        staging = Path(tmp)
        root_path = staging / out.name
        # Clips of each export get a directory of their own, so the previous root keeps
        # its clips until the new root has replaced it.
        clips_dir = out.with_name(f"{out.stem}_clips_{staging.name.rsplit('.', 1)[-1]}")
        stage = Usd.Stage.CreateNew(str(root_path))
        _set_stage_metadata(stage, n_frames, fps)
        if frames_per_clip is None or frames_per_clip >= n_frames:
            _author(stage, recording, range(n_frames), ribbon)
        else:
            stitched = _write_clips(staging / clips_dir.name, recording, frames_per_clip, ribbon, n_frames, fps)
            stage.GetRootLayer().subLayerPaths.append(f"./{clips_dir.name}/{stitched.name}")
        stage.SetDefaultPrim(stage.DefinePrim("/World"))
        stage.GetRootLayer().Save()
        # Clips first, the root layer last: the root's appearance marks the export
        # complete; only then do the previous export's clips go.
        if (staging / clips_dir.name).exists():
            os.replace(staging / clips_dir.name, clips_dir)
        os.replace(root_path, out)
    for old in out.parent.glob(f"{out.stem}_clips_*"):
        if old != clips_dir and old.is_dir():
            shutil.rmtree(old)
    return out


def _write_clips(
    clips: Path, recording: Recording, frames_per_clip: int, ribbon: bool, n_frames: int, fps: float
) -> Path:
    clips.mkdir()
    files = []
    for k, first in enumerate(range(0, n_frames, frames_per_clip)):
        path = clips / f"frames-{k:04d}.usdc"
        stage = Usd.Stage.CreateNew(str(path))
        chunk = range(first, min(first + frames_per_clip, n_frames))
        _set_stage_metadata(stage, n_frames, fps)
        # StitchClips makes each clip active over its layer's own time-code range.
        stage.SetStartTimeCode(chunk[0])
        stage.SetEndTimeCode(chunk[-1])
        _author(stage, recording, chunk, ribbon)
        stage.GetRootLayer().Save()
        files.append(str(path))
    stitched = Sdf.Layer.CreateNew(str(clips / "stitched.usda"))
    if not UsdUtils.StitchClips(stitched, files, Sdf.Path("/World"), 0, n_frames - 1):
        raise InternalError(
            f"UsdUtils.StitchClips failed for {clips}, the clips this export has just written: a bug in "
            "warpcloth (or USD), please report it"
        )
    # Every layer states the frame rate: USD rescales time across layers whose
    # timeCodesPerSecond differ, and an unwritten one reads as 24.
    for layer_path in (stitched.realPath, str(clips / "stitched.topology.usda"), str(clips / "stitched.manifest.usda")):
        layer = Sdf.Layer.FindOrOpen(layer_path)
        layer.timeCodesPerSecond = layer.framesPerSecond = fps
        layer.Save()
    # StitchClips records absolute asset paths; make them relative so the export can move.
    prim = stitched.GetPrimAtPath("/World")
    info = dict(prim.GetInfo("clips"))
    default = dict(info["default"])
    default["assetPaths"] = Sdf.AssetPathArray([f"./{Path(p.path).name}" for p in default["assetPaths"]])
    default["manifestAssetPath"] = Sdf.AssetPath(f"./{Path(default['manifestAssetPath'].path).name}")
    info["default"] = default
    prim.SetInfo("clips", info)
    stitched.subLayerPaths = [f"./{Path(p).name}" for p in stitched.subLayerPaths]
    stitched.Save()
    return Path(stitched.realPath)


def export_sheet_usd(run: SheetRun, out_file: str | Path) -> Path:
    """Write a sheet run (:func:`warpcloth.io.sheet_run_dir.read_sheet_run`) as a USD stage
    at ``out_file``: one animated ``UsdGeom.Mesh`` per sheet (``/World/Sheets/sheet_0000``),
    quads from the geometry's faces, the node positions time-sampled per frame, and the
    weave as primvars: per vertex its lattice position ``warpcloth:lattice`` (i along the
    warp, j along the weft), per face the rest directions of the warp and the weft
    (``warpcloth:warp_direction``, ``warpcloth:weft_direction``). Frames after a
    divergence hold the last shape and are invisible. Written whole under a temporary
    name and renamed."""
    out = check_stage_path(out_file)
    frames = run.frames
    n_frames = len(frames)
    faces = run.faces
    rest = run.rest_positions
    warp = rest[faces[:, 1]] - rest[faces[:, 0]]
    weft = rest[faces[:, 3]] - rest[faces[:, 0]]
    warp /= np.linalg.norm(warp, axis=1, keepdims=True)
    weft /= np.linalg.norm(weft, axis=1, keepdims=True)

    def author(path: Path) -> None:
        stage = Usd.Stage.CreateNew(str(path))
        _set_stage_metadata(stage, n_frames, run.frame_rate)
        UsdGeom.Xform.Define(stage, "/World")
        UsdGeom.Scope.Define(stage, "/World/Sheets")
        for sheet in range(frames.shape[1]):
            mesh = UsdGeom.Mesh.Define(stage, f"/World/Sheets/sheet_{sheet:04d}")
            mesh.CreateFaceVertexCountsAttr(Vt.IntArray([4] * len(faces)))
            mesh.CreateFaceVertexIndicesAttr(Vt.IntArray([int(v) for v in faces.ravel()]))
            mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
            mesh.CreateDoubleSidedAttr(True)
            api = UsdGeom.PrimvarsAPI(mesh)
            api.CreatePrimvar("warpcloth:lattice", Sdf.ValueTypeNames.Int2Array, UsdGeom.Tokens.vertex).Set(
                Vt.Vec2iArray([Gf.Vec2i(int(i), int(j)) for i, j in run.lattice])
            )
            for name, directions in (("warp_direction", warp), ("weft_direction", weft)):
                api.CreatePrimvar(f"warpcloth:{name}", Sdf.ValueTypeNames.Float3Array, UsdGeom.Tokens.uniform).Set(
                    Vt.Vec3fArray.FromNumpy(directions.astype(np.float32))
                )
            mesh.CreateDisplayColorPrimvar(UsdGeom.Tokens.constant).Set(Vt.Vec3fArray([Gf.Vec3f(0.55, 0.45, 0.35)]))
            visibility = mesh.CreateVisibilityAttr()
            last = rest
            for f in range(n_frames):
                shape = frames[f, sheet]
                alive = bool(np.isfinite(shape).all())
                last = shape if alive else last
                mesh.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy(last.astype(np.float32)), f)
                mesh.GetExtentAttr().Set(_extent(last, 0.0), f)
                visibility.Set(UsdGeom.Tokens.inherited if alive else UsdGeom.Tokens.invisible, f)
        stage.SetDefaultPrim(stage.GetPrimAtPath("/World"))
        stage.GetRootLayer().Save()

    out.parent.mkdir(parents=True, exist_ok=True)
    with usd_write_errors(out):
        write_atomically(out, author)
    return out


def export_run_usd(run_dir: str | Path, out_file: str | Path) -> Path:
    """A strip run directory's every variant as an animated USD stage (:func:`export_usd`)."""
    from warpcloth.io.load import load_recording

    return export_usd(load_recording(run_dir), out_file)


def export_sheet_run_usd(run_dir: str | Path, out_file: str | Path) -> Path:
    """A sheet run directory as an animated USD mesh (:func:`export_sheet_usd`)."""
    from warpcloth.io.sheet_run_dir import read_sheet_run

    return export_sheet_usd(read_sheet_run(run_dir), out_file)
