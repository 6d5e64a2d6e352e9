"""3D renders of a recording with pyvista, off screen: a PNG per chosen frame and an
animation (GIF, or MP4 when imageio-ffmpeg is installed).

Each strip is drawn as a ribbon of its real width (z), the clamp as a grey box moving
rigidly with the clamp nodes, the time (from the release, or the start of the clamp
motion) stamped in a corner. The camera looks along −z at the x–y plane of the motion
with a parallel projection, framed once for the whole run so frames compare directly.
A woven sheet (:func:`render_sheet_run`) is drawn as its mesh of quads coloured by each
quad's shear angle, its clamp a grey box moving rigidly with it and a ruler in mm beside
it, seen from the front (+x), turned a little toward +z.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import imageio.v3 as imageio
import numpy as np

from warpcloth.errors import ArgumentError
from warpcloth.io.atomic import write_atomically
from warpcloth.io.recording import Recording, nearest_frames
from warpcloth.io.sheet_run_dir import SheetRun
from warpcloth.sheet.geometry import quad_shear_angles

if not os.environ.get("DISPLAY"):
    # Headless: go straight to EGL instead of trying an X server first.
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import pyvista as pv  # noqa: E402

from warpcloth.viz.geometry import (  # noqa: E402
    BOX_FACES,
    clamp_box,
    colour_values,
    ribbon_quads,
    ribbon_vertices,
    sheet_clamp_box,
    variant_colours,
)

WINDOW = (960, 720)
CAMERA_AZIMUTH_DEG = 25.0  # about the vertical, from the +z side
CAMERA_ELEVATION_DEG = 15.0
BACKGROUND = "white"
CLAMP_COLOUR = (0.35, 0.35, 0.38)
SHEAR_TITLE = "shear angle (°)"  # the render fonts lack φ
SHEAR_CMAP = "coolwarm"  # diverging, its middle a light grey that shows on the white background
RULER_GAP_M = 0.01  # between the sheet's furthest reach toward +z and the ruler


class Renderer:
    """An off-screen pyvista scene, updated frame by frame (:meth:`show_frame`), written as
    PNGs and animations; the time of each frame stamped in a corner."""

    def __init__(self, frame_times: np.ndarray, window_size: tuple[int, int] = WINDOW) -> None:
        self.frame_times = frame_times
        self.plotter = pv.Plotter(off_screen=True, window_size=list(window_size))
        self.plotter.set_background(BACKGROUND)

    def _stamp(self) -> None:
        self.stamp = self.plotter.add_text("", position="upper_left", font_size=12, color="black")

    def _look_at(self, centre: np.ndarray, direction: np.ndarray, span: float) -> None:
        # Framed once on everything the run visits, with a parallel projection and y up,
        # so frames compare directly.
        self.plotter.camera.focal_point = tuple(centre)
        self.plotter.camera.position = tuple(centre + direction)
        self.plotter.camera.up = (0.0, 1.0, 0.0)
        self.plotter.enable_parallel_projection()
        self.plotter.camera.parallel_scale = span / 2

    def move_to(self, frame: int) -> None:
        """Move the scene's meshes to ``frame``."""
        raise NotImplementedError

    def show_frame(self, frame: int) -> None:
        """Move the scene to ``frame`` and stamp its time."""
        self.move_to(frame)
        self.stamp.SetText(2, f"t = {self.frame_times[frame]:.3f} s")
        self.plotter.render()

    def screenshot(self, frame: int, path: str | Path) -> np.ndarray:
        """Render ``frame`` to a PNG; returns the image [row, column, rgb]."""
        self.show_frame(frame)
        image = self.plotter.screenshot(None, return_img=True)
        write_atomically(path, lambda tmp: imageio.imwrite(tmp, image))
        return image

    def animate(self, path: str | Path, frames: np.ndarray, fps: float) -> Path:
        """Write an animation of ``frames`` (GIF, or MP4 with imageio-ffmpeg)."""
        path = Path(path)
        if path.suffix == ".mp4":
            try:
                import imageio_ffmpeg  # noqa: F401
            except ImportError:
                raise ArgumentError(
                    "movie",
                    "MP4 needs the imageio-ffmpeg package (pip install imageio-ffmpeg); a .gif needs nothing more",
                ) from None
        elif path.suffix != ".gif":
            raise ArgumentError("movie", f"{path} must end in .gif or .mp4")

        def write(tmp: Path) -> None:
            if tmp.suffix == ".gif":
                self.plotter.open_gif(str(tmp), fps=fps)
            else:
                self.plotter.open_movie(str(tmp), framerate=fps)
            for f in frames:
                self.show_frame(int(f))
                self.plotter.write_frame()
            self.plotter.mwriter.close()

        return write_atomically(path, write)

    def close(self) -> None:
        """Release the render window."""
        self.plotter.close()


class StripRenderer(Renderer):
    """The selected variants of a recording: each strip a ribbon of its real width, its clamp a
    grey box moving rigidly with the clamp nodes; seen from the +z side, x left to right."""

    def __init__(self, recording: Recording, window_size: tuple[int, int] = WINDOW) -> None:
        super().__init__(recording.frame_times, window_size)
        self.recording = recording
        n_nodes = recording.frames.shape[2]
        counts, indices = ribbon_quads(n_nodes)
        faces = np.hstack([[c, *indices[4 * i : 4 * i + 4]] for i, c in enumerate(counts)])
        colours = variant_colours(colour_values(recording))
        self.ribbons = []
        self.clamps = []
        for j in range(len(recording.variants)):
            ribbon = pv.PolyData(self._ribbon_points(0, j), faces)
            self.plotter.add_mesh(ribbon, color=colours[j], smooth_shading=True)
            self.ribbons.append(ribbon)
            box = clamp_box(recording, j)
            clamp = pv.PolyData(box.copy(), BOX_FACES)
            self.plotter.add_mesh(clamp, color=CLAMP_COLOUR)
            self.clamps.append((clamp, box))
        self.angle_and_shift = [recording.clamp_pose(j) for j in range(len(recording.variants))]
        self._stamp()
        self._frame_camera()

    def _ribbon_points(self, frame: int, j: int) -> np.ndarray:
        width = self.recording.scenes[j].strip.width_mm * 1e-3
        return ribbon_vertices(self.recording.drawable_frames[frame, j], width).astype(float)

    def _frame_camera(self) -> None:
        # Seen slightly from the side and above, so the ribbon's width shows, while x
        # still runs left to right.
        xy = self.recording.drawable_frames.reshape(-1, 2)
        lo, hi = xy.min(axis=0), xy.max(axis=0)
        centre = (lo + hi) / 2
        self._look_at(
            np.array([centre[0], centre[1], 0.0]), view_direction(CAMERA_AZIMUTH_DEG), max(hi - lo) * 1.2 + 0.01
        )

    def move_to(self, frame: int) -> None:
        """Move every ribbon and clamp to ``frame``."""
        for j, ribbon in enumerate(self.ribbons):
            ribbon.points = self._ribbon_points(frame, j)
            angle, shift = self.angle_and_shift[j]
            c, s = np.cos(angle[frame]), np.sin(angle[frame])
            clamp, box = self.clamps[j]
            moved = box.copy()
            moved[:, 0] = c * box[:, 0] - s * box[:, 1] + shift[frame, 0]
            moved[:, 1] = s * box[:, 0] + c * box[:, 1] + shift[frame, 1]
            clamp.points = moved


class SheetRenderer(Renderer):
    """A sheet run's mesh (the quads of its geometry's faces, edges drawn), each quad coloured
    by its shear angle on a diverging map whose limits hold over the whole run, so frames
    compare; the clamp's jaws a grey box moving rigidly with the clamp; a ruler in mm beside
    the sheet. Seen from the front (+x, where a lab's camera films) turned toward +z, so
    both the swing out of the plane and the shear in it show. A sheet's frames after its
    divergence keep its last shape."""

    def __init__(self, run: SheetRun, sheet: int = 0, window_size: tuple[int, int] = WINDOW) -> None:
        super().__init__(run.frame_times, window_size)
        self.shapes = drawable_sheet_frames(run.frames[:, sheet], run.rest_positions)
        self.shear_deg = np.degrees(quad_shear_angles(self.shapes, run.faces))
        limit = colour_limit(float(np.abs(self.shear_deg).max()))
        faces = np.hstack([np.full((len(run.faces), 1), 4), run.faces]).ravel()
        self.mesh = pv.PolyData(self.shapes[0].copy(), faces)
        self.mesh.cell_data[SHEAR_TITLE] = self.shear_deg[0]
        self.plotter.add_mesh(
            self.mesh,
            scalars=SHEAR_TITLE,
            cmap=SHEAR_CMAP,
            clim=(-limit, limit),
            show_edges=True,
            edge_color=(0.3, 0.3, 0.3),
            # lit mostly by ambient light, so a quad's colour reads off the colour bar,
            # with enough diffuse light that the sheet's curvature still shows
            ambient=0.6,
            diffuse=0.4,
            scalar_bar_args={
                "title": SHEAR_TITLE,
                "vertical": True,
                "position_x": 0.86,
                "position_y": 0.2,
                "height": 0.6,
                "width": 0.06,
                "n_labels": 5,
                "fmt": "%.3g",
                "color": "black",
                "title_font_size": 16,
                "label_font_size": 14,
            },
        )
        box = sheet_clamp_box(run.rest_positions, run.clamped)
        self.clamp_boxes = clamp_positions(run, box, sheet)
        self.clamp = pv.PolyData(self.clamp_boxes[0].copy(), BOX_FACES)
        self.plotter.add_mesh(self.clamp, color=CLAMP_COLOUR)
        self._stamp()
        points = np.concatenate([self.shapes.reshape(-1, 3), self.clamp_boxes.reshape(-1, 3)])
        lo, hi = points.min(axis=0), points.max(axis=0)
        self._ruler(run.rest_positions, hi[2])
        self._look_at((lo + hi) / 2, view_direction(90.0 - CAMERA_AZIMUTH_DEG), max(hi - lo) * 1.2 + 0.01)

    def _ruler(self, rest: np.ndarray, z: float) -> None:
        # Upright, from the clamp edge (0) down the sheet's rest length in whole centimetres
        # (labelled every 10, 20, 25 or 50 mm, so the labels are round), beside the sheet on
        # its +z side (left on screen) where no frame reaches: vertical lengths are seen at
        # cos(elevation) = 0.97 of true, so the ruler reads the sheet's size directly.
        length_mm = max(10, int(-rest[:, 1].min() * 1e3 + 1e-6) // 10 * 10)
        step = next(s for s in (10, 20, 25, 50, 100, 200, 500, length_mm) if length_mm % s == 0 and length_mm / s <= 6)
        self.plotter.add_ruler(
            (0.0, 0.0, z + RULER_GAP_M),
            (0.0, -length_mm * 1e-3, z + RULER_GAP_M),
            number_labels=length_mm // step + 1,
            title="",  # the unit is on every label: a title would sit among them
            label_format="%.0f mm",
            label_color="black",
            tick_color="black",
            font_size_factor=0.8,
            scale=1e3,
        )

    def move_to(self, frame: int) -> None:
        """Move the mesh and the clamp to ``frame`` and colour the mesh by its shear there."""
        self.mesh.points = self.shapes[frame]
        self.mesh.cell_data[SHEAR_TITLE] = self.shear_deg[frame]
        self.clamp.points = self.clamp_boxes[frame]


def clamp_positions(run: SheetRun, box: np.ndarray, sheet: int = 0) -> np.ndarray:
    """Where the clamp's rigid motion carries the points ``box`` ``[point, xyz]`` (at rest) at
    each of the run's frames: ``[frame, point, xyz]``, the clamp's angle and travel
    interpolated from the probes (a diverged sheet's clamp stops where its probes stop)."""
    from warpcloth.scene.sheet_build import sheet_clamp
    from warpcloth.viz.figures.sheet import carried_by_clamp

    probes = run.probes[run.probes["sheet"] == sheet]
    t = probes["t"].to_numpy()
    angle = np.interp(run.frame_times, t, probes["clamp_angle"].to_numpy())
    travel = np.interp(run.frame_times, t, probes["clamp_displacement"].to_numpy())
    return carried_by_clamp(box, angle, travel, sheet_clamp(run.scene))


def colour_limit(peak: float) -> float:
    """The colour bar's half range for values up to ``peak`` in magnitude: the next of
    1, 1.5, 2, 3, 4, 5, 6, 8 times a power of ten at or above it, so its labels are round
    numbers (1e-6 for a sheet that never shears, whose quads then show the map's middle)."""
    if not peak > 1e-6:
        return 1e-6
    power = 10.0 ** np.floor(np.log10(peak))
    return float(next(m * power for m in (1, 1.5, 2, 3, 4, 5, 6, 8, 10) if m * power >= peak * (1 - 1e-9)))


def view_direction(azimuth_deg: float) -> np.ndarray:
    """Unit vector from the focal point to the camera: ``azimuth_deg`` about the vertical from
    +z toward +x, raised by CAMERA_ELEVATION_DEG."""
    azimuth, elevation = np.radians(azimuth_deg), np.radians(CAMERA_ELEVATION_DEG)
    return np.array([np.sin(azimuth) * np.cos(elevation), np.sin(elevation), np.cos(azimuth) * np.cos(elevation)])


def drawable_sheet_frames(frames: np.ndarray, rest: np.ndarray) -> np.ndarray:
    """``frames[frame, node, xyz]`` with each frame a sheet never reached (NaN) replaced by
    the last one it did (the rest shape before any)."""
    shapes = np.array(frames, dtype=float)
    last = rest
    for f, shape in enumerate(shapes):
        if np.isfinite(shape).all():
            last = shape
        else:
            shapes[f] = last
    return shapes


def gif_stride(frame_rate: float, stride: int = 1) -> int:
    """The smallest stride ≥ ``stride`` at which a GIF plays in real time.

    A GIF frame lasts a whole number of centiseconds, and browsers show anything under
    2 cs as 10 cs: 60 frames/s (1.67 cs) would play 6× slow. So take every k-th frame,
    with k·100/frame_rate a whole number of centiseconds, at least 2 (60 Hz: k = 3, 5 cs).
    """
    k = max(1, stride)
    while k < 10_000:
        delay = 100.0 * k / frame_rate
        if delay >= 2 - 1e-9 and abs(delay - round(delay)) < 1e-6 * max(delay, 1):
            return k
        k += 1
    return max(1, stride)


def render_run(
    recording: Recording,
    out_dir: str | Path,
    *,
    times: np.ndarray | None = None,
    movie: str | None = "motion.gif",
    stride: int = 1,
) -> list[Path]:
    """PNGs of the frames at ``times`` (default: six spread over the run) and, unless
    ``movie`` is None, an animation of every ``stride``-th frame at real speed."""
    return render_frames(
        lambda: StripRenderer(recording), recording.frame_times, recording.frame_rate, out_dir, times, movie, stride
    )


def render_sheet_run(
    run: SheetRun,
    out_dir: str | Path,
    *,
    times: np.ndarray | None = None,
    movie: str | None = "motion.gif",
    stride: int = 1,
) -> list[Path]:
    """A sheet run (:func:`warpcloth.io.sheet_run_dir.read_sheet_run`) as :func:`render_run`
    renders a strip's: PNGs of the frames at ``times``, an animation unless ``movie`` is None;
    each coloured by the quads' shear angle, with the clamp and a ruler (:class:`SheetRenderer`)."""
    return render_frames(lambda: SheetRenderer(run), run.frame_times, run.frame_rate, out_dir, times, movie, stride)


def render_frames(
    renderer: Callable[[], Renderer],
    frame_times: np.ndarray,
    frame_rate: float,
    out_dir: str | Path,
    times: np.ndarray | None,
    movie: str | None,
    stride: int,
) -> list[Path]:
    """Write ``frame_NNNNN.png`` for the frames nearest ``times`` and the ``movie`` of every
    ``stride``-th frame (a GIF's stride raised to play in real time) with the scene
    ``renderer()`` makes; returns the paths."""
    if stride > len(frame_times):
        raise ArgumentError("stride", f"{stride} is more than the {len(frame_times)} frames recorded")
    picks = nearest_frames(frame_times, np.linspace(frame_times[0], frame_times[-1], 6) if times is None else times)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    scene = renderer()
    written = []
    try:
        for f in picks:
            path = out / f"frame_{f:05d}.png"
            scene.screenshot(int(f), path)
            written.append(path)
        if movie:
            if Path(movie).suffix == ".gif":
                stride = gif_stride(frame_rate, stride)
            frames = np.arange(0, len(frame_times), max(1, stride))
            written.append(scene.animate(out / movie, frames, frame_rate / max(1, stride)))
    finally:
        scene.close()
    return written
