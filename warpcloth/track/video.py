"""Video frames and their times, read (and written) with PyAV.

Each frame's time is the container's presentation timestamp, exact as a fraction of the
stream's time base; nothing is re-timed. A gap of more than 1.5 nominal intervals between
two frames is a dropped frame, reported; a frame bit-identical to the one before it is a
duplicate (a camera's sensor noise never repeats), reported and left out, since its
timestamp would claim a position the camera did not see there. Timestamps that do not
increase, a frame without one, or a frame that cannot be decoded are errors naming the
file and the frame.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

import numpy as np

from warpcloth.errors import ArgumentError, DataFileError

__all__ = ["FrameStream", "Frames", "median_background", "read_frames", "write_video"]

DROP_FACTOR = 1.5
"""A gap beyond this many nominal frame intervals is reported as dropped frames."""


@dataclass
class Frames:
    """Decoded frames ``[frame, row, column]`` (grey) or ``[frame, row, column, rgb]`` (uint8) with their times (s), the
    index of each in the file's decode order, what was found wrong with the timing, and how
    many pixels shared one colour sample in the file (across, down; None: not known).
    Iterating gives ``(index, t, image)`` per frame, as :class:`FrameStream` does."""

    images: np.ndarray
    t: np.ndarray
    index: np.ndarray
    nominal_interval_s: float
    dropped: list[str] = field(default_factory=list)
    duplicated: list[str] = field(default_factory=list)
    chroma_subsampling: tuple[int, int] | None = None

    @property
    def total(self) -> int:
        """How many frames there are."""
        return len(self.t)

    def __iter__(self) -> Iterator[tuple[int, float, np.ndarray]]:
        return zip(self.index.tolist(), self.t.tolist(), self.images, strict=True)


class FrameStream:
    """The frames of a video's first stream, decoded one at a time as it is iterated (a long
    recording is never held whole): ``(index, t, image)`` per frame kept, duplicates left
    out. After an iteration, :attr:`dropped`, :attr:`duplicated` and
    :attr:`nominal_interval_s` describe its timing; each iteration decodes the file again.
    :attr:`chroma_subsampling` is how many pixels share one colour sample (across, down;
    None where the format does not say)."""

    def __init__(self, path: str | Path, argument: str = "path", colour: bool = False) -> None:
        import av

        self.path = Path(path)
        self.colour = colour  # frames as RGB [row, column, 3] rather than grey
        if not self.path.is_file():
            raise ArgumentError(
                argument, f"{self.path} does not exist" if not self.path.exists() else f"{self.path} is not a file"
            )
        try:
            with av.open(str(self.path)) as container:
                if not container.streams.video:
                    raise DataFileError(self.path, "holds no video stream")
                stream = container.streams.video[0]
                self.width, self.height = stream.codec_context.width, stream.codec_context.height
                self.chroma_subsampling = colour_sampling(stream.codec_context.format)
                # the container's count, else its packets counted (read, not decoded)
                self.total = stream.frames or sum(1 for packet in container.demux(stream) if packet.size)
        except (av.error.FFmpegError, UnicodeDecodeError) as exc:
            raise DataFileError(self.path, f"cannot be read as a video ({exc})") from None
        self.times: list[Fraction] = []
        self.duplicated: list[str] = []

    def __iter__(self) -> Iterator[tuple[int, float, np.ndarray]]:
        import av

        self.times, self.duplicated = [], []
        previous = None
        level = av.logging.get_level()
        av.logging.set_level(av.logging.ERROR)  # a damaged frame is only logged by FFmpeg's decoders: catch it
        try:
            with av.open(str(self.path)) as container, av.logging.Capture() as logged:
                frames = container.decode(container.streams.video[0])
                while True:
                    i = len(self.times)
                    try:
                        frame = next(frames)
                    except StopIteration:
                        break
                    except av.error.FFmpegError as exc:
                        after = float(self.times[-1]) if self.times else 0.0
                        raise DataFileError(
                            self.path,
                            f"frame {i} (after t = {after:g} s) cannot be decoded ({exc}); the file is damaged",
                        ) from None
                    if frame.pts is None or frame.time_base is None:
                        raise DataFileError(
                            self.path,
                            f"frame {i} has no timestamp; the container must give each "
                            "frame's time (re-mux it, e.g. to .avi or .mkv)",
                        )
                    t = Fraction(frame.pts) * frame.time_base
                    if logged:
                        said = "; ".join(" ".join(entry[2].split()) for entry in logged)
                        raise DataFileError(
                            self.path,
                            f"frame {i} (t = {float(t):g} s) or the one before it is "
                            f"damaged: the decoder says {said!r}",
                        )
                    if self.times and t <= self.times[-1]:
                        raise DataFileError(
                            self.path,
                            f"frame {i} has time {float(t):.6g} s, not after frame "
                            f"{i - 1}'s {float(self.times[-1]):.6g} s: the timestamps do not increase",
                        )
                    self.times.append(t)
                    image = frame.to_ndarray(format="rgb24" if self.colour else "gray")
                    if previous is not None and np.array_equal(image, previous[1]):
                        self.duplicated.append(
                            f"frame {i} (t = {float(t):.6g} s) repeats frame {previous[0]} exactly; left out"
                        )
                        continue
                    previous = (i, image)
                    yield i, float(t), image
        finally:
            av.logging.set_level(level)
        if len(self.times) < 2:
            raise DataFileError(self.path, f"holds {len(self.times)} decodable frame(s); tracking needs at least two")

    @property
    def nominal_interval_s(self) -> float:
        """The median interval between frames of the last iteration (s)."""
        steps = sorted(b - a for a, b in zip(self.times, self.times[1:], strict=False))
        return float(steps[len(steps) // 2])

    @property
    def dropped(self) -> list[str]:
        """Gaps of more than 1.5 nominal intervals in the last iteration, one note each."""
        steps = [b - a for a, b in zip(self.times, self.times[1:], strict=False)]
        nominal = sorted(steps)[len(steps) // 2]
        return [
            f"{round(step / nominal) - 1} frame(s) missing between frame {i} (t = {float(self.times[i]):.6g} s) "
            f"and frame {i + 1} (t = {float(self.times[i + 1]):.6g} s), nominal interval {float(nominal):.6g} s"
            for i, step in enumerate(steps)
            if step > DROP_FACTOR * nominal
        ]


def colour_sampling(stored: object) -> tuple[int, int] | None:
    """How many pixels of a frame stored as ``stored`` (an ``av.VideoFormat``, or None) share
    one colour sample, across and down: 1, 1 where every pixel's colour is kept (RGB,
    4:4:4), 2, 2 for 4:2:0 (H.264's usual) and for a Bayer mosaic (one colour per pixel, the
    others interpolated), 2, 1 for 4:2:2; None where the format does not say."""
    if stored is None:
        return None
    if stored.is_bayer:
        return (2, 2)
    if not stored.chroma_width() or not stored.width:
        return None
    return (round(stored.width / stored.chroma_width()), round(stored.height / stored.chroma_height()))


def read_frames(path: str | Path, argument: str = "path", colour: bool = False) -> Frames:
    """Every frame of the first video stream of ``path`` in memory (a short clip; tracking
    streams a :class:`FrameStream`), grey or, with ``colour``, RGB."""
    stream = FrameStream(path, argument, colour)
    index, t, images = zip(*stream, strict=True)
    return Frames(
        np.stack(images),
        np.array(t),
        np.array(index),
        stream.nominal_interval_s,
        stream.dropped,
        stream.duplicated,
        stream.chroma_subsampling,
    )


def median_background(frames: Iterable[tuple[int, float, np.ndarray]], most: int = 64) -> np.ndarray:
    """The per-pixel median of at most ``most`` frames spread over the whole recording (every
    frame while there are fewer; the stride doubles as it grows), a fixed-camera background."""
    kept, stride = [], 1
    for position, (_, _, image) in enumerate(frames):
        if position % stride == 0:
            kept.append(image)
            if len(kept) > most:
                kept, stride = kept[::2], 2 * stride
    return np.median(np.stack(kept), axis=0)


def write_video(path: str | Path, images: Iterable[np.ndarray], pts: Sequence[int], time_base: Fraction) -> None:
    """Grey (or RGB) uint8 frames to ``path`` (FFV1, lossless, in AVI: its time base is exact at any
    frame rate up to 1000 frames/s, unlike Matroska's millisecond clock; FFmpeg replaces a
    finer one by 1/600 s), frame i at ``pts[i] · time_base`` s, each encoded as it comes
    (``images`` may be a generator: none is held)."""
    import av

    with av.open(str(path), "w", format="avi") as container:
        # FFV1 version 3 with slice CRCs, every frame a key frame: damage is caught where it is
        stream = container.add_stream("ffv1", rate=Fraction(1) / time_base)
        stream.codec_context.options = {"level": "3", "slicecrc": "1", "context": "1", "g": "1"}
        stream.time_base = time_base
        stream.codec_context.time_base = time_base
        for i, (image, stamp) in enumerate(zip(images, pts, strict=True)):
            colour = image.ndim == 3  # RGB: stored as planes, every pixel's colour kept
            if i == 0:
                stream.height, stream.width = image.shape[:2]
                stream.pix_fmt = "bgr0" if colour else "gray"
                if stamp > 0:
                    # AVI has no start time: a frame's time is its slot, so the first is
                    # moved to its own by an empty slot at 0 (the muxer fills the rest)
                    lead = av.Packet(0)
                    lead.pts = lead.dts = 0
                    lead.time_base, lead.stream = time_base, stream
                    container.mux(lead)
            frame = av.VideoFrame.from_ndarray(
                np.ascontiguousarray(image, dtype=np.uint8), format="rgb24" if colour else "gray"
            )
            if colour:
                frame = frame.reformat(format="bgr0")
            frame.pts, frame.time_base = int(stamp), time_base
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
