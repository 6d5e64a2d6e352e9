"""3D renders of a recording with pyvista, off screen: a PNG per chosen frame and an
animation (GIF, or MP4 when imageio-ffmpeg is installed).

Each strip is drawn as a ribbon of its real width (z), the clamp as a grey box moving
rigidly with the clamp nodes, the time (from the release, or the start of the clamp
motion) stamped in a corner. The camera looks along −z at the x–y plane of the motion
with a parallel projection, framed once for the whole run so frames compare directly.
A woven sheet (:func:`render_sheet_run`) is drawn as its mesh of quads, seen from the
front (+x), turned a little toward +z.
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

if not os.environ.get("DISPLAY"):
    # Headless: go straight to EGL instead of trying an X server first.
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import pyvista as pv  # noqa: E402

from warpcloth.viz.geometry import (  # noqa: E402
    BOX_QUADS,
    clamp_box,
    colour_values,
    ribbon_quads,
    ribbon_vertices,
    variant_colours,
)

WINDOW = (960, 720)
CAMERA_AZIMUTH_DEG = 25.0  # about the vertical, from the +z side
CAMERA_ELEVATION_DEG = 15.0
BACKGROUND = "white"
SHEET_COLOUR = (0.55, 0.45, 0.35)  # as the USD export's displayColor


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
            clamp = pv.PolyData(box.copy(), np.hstack([[4, *BOX_QUADS[4 * k : 4 * k + 4]] for k in range(6)]))
            self.plotter.add_mesh(clamp, color=(0.35, 0.35, 0.38))
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
    """A sheet run's mesh (the quads of its geometry's faces, edges drawn, so the weave's
    shear shows as the cells' slant), seen from the front (+x, where a lab's camera films)
    turned toward +z, so both the swing out of the plane and the shear in it show. A
    sheet's frames after its divergence keep its last shape."""

    def __init__(self, run: SheetRun, sheet: int = 0, window_size: tuple[int, int] = WINDOW) -> None:
        super().__init__(run.frame_times, window_size)
        self.shapes = drawable_sheet_frames(run.frames[:, sheet], run.rest_positions)
        faces = np.hstack([np.full((len(run.faces), 1), 4), run.faces]).ravel()
        self.mesh = pv.PolyData(self.shapes[0].copy(), faces)
        self.plotter.add_mesh(
            self.mesh, color=SHEET_COLOUR, smooth_shading=True, show_edges=True, edge_color="grey", ambient=0.4
        )
        self._stamp()
        points = self.shapes.reshape(-1, 3)
        lo, hi = points.min(axis=0), points.max(axis=0)
        self._look_at((lo + hi) / 2, view_direction(90.0 - CAMERA_AZIMUTH_DEG), max(hi - lo) * 1.2 + 0.01)

    def move_to(self, frame: int) -> None:
        """Move the mesh to ``frame``."""
        self.mesh.points = self.shapes[frame]


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
    renders a strip's: PNGs of the frames at ``times``, an animation unless ``movie`` is None."""
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
