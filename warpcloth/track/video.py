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

from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

import numpy as np

from warpcloth.errors import DataFileError, OptionError

__all__ = ["Frames", "read_frames", "write_video"]

DROP_FACTOR = 1.5
"""A gap beyond this many nominal frame intervals is reported as dropped frames."""


@dataclass
class Frames:
    """Decoded grey frames ``[frame, row, column]`` (uint8) with their times (s), the
    index of each in the file's decode order, and what was found wrong with the timing."""

    images: np.ndarray
    t: np.ndarray
    index: np.ndarray
    nominal_interval_s: float
    dropped: list[str] = field(default_factory=list)
    duplicated: list[str] = field(default_factory=list)


def read_frames(path: str | Path, flag: str = "VIDEO", progress: bool = False) -> Frames:
    """Every frame of the first video stream of ``path`` as grey images, with its time."""
    import av
    from tqdm import tqdm

    path = Path(path)
    if not path.is_file():
        raise OptionError(flag, f"{path} does not exist" if not path.exists() else f"{path} is not a file")
    try:
        container = av.open(str(path))
    except (av.error.FFmpegError, UnicodeDecodeError) as exc:
        raise DataFileError(path, f"cannot be read as a video ({exc})") from None
    images, times, index = [], [], []
    level = av.logging.get_level()
    av.logging.set_level(av.logging.ERROR)  # a damaged frame is only logged by FFmpeg's decoders: catch it
    try:
        with container, av.logging.Capture() as logged:
            if not container.streams.video:
                raise DataFileError(path, "holds no video stream")
            stream = container.streams.video[0]
            frames = container.decode(stream)
            with tqdm(total=stream.frames or None, desc="reading frames", unit=" frames", disable=not progress) as bar:
                while True:
                    try:
                        frame = next(frames)
                    except StopIteration:
                        break
                    except av.error.FFmpegError as exc:
                        after = float(times[-1]) if times else 0.0
                        raise DataFileError(path, f"frame {len(images)} (after t = {after:g} s) cannot be decoded "
                                            f"({exc}); the file is damaged") from None
                    if logged:
                        said = "; ".join(" ".join(entry[2].split()) for entry in logged)
                        raise DataFileError(path, f"frame {len(images)} (t = {float(frame.pts * frame.time_base):g} s) "
                                            f"or the one before it is damaged: the decoder says {said!r}")
                    if frame.pts is None or frame.time_base is None:
                        raise DataFileError(path, f"frame {len(images)} has no timestamp; the container must give "
                                            "each frame's time (re-mux it, e.g. to .avi or .mkv)")
                    images.append(frame.to_ndarray(format="gray"))
                    times.append(Fraction(frame.pts) * frame.time_base)
                    index.append(len(index))
                    bar.update()
    finally:
        av.logging.set_level(level)
    if len(images) < 2:
        raise DataFileError(path, f"holds {len(images)} decodable frame(s); tracking needs at least two")
    return _checked(path, np.stack(images), times, np.array(index))


def _checked(path: Path, images: np.ndarray, times: list[Fraction], index: np.ndarray) -> Frames:
    steps = [b - a for a, b in zip(times, times[1:], strict=False)]
    for i, step in enumerate(steps):
        if step <= 0:
            raise DataFileError(path, f"frame {i + 1} has time {float(times[i + 1]):.6g} s, not after frame {i}'s "
                                f"{float(times[i]):.6g} s: the timestamps do not increase")
    nominal = sorted(steps)[len(steps) // 2]
    dropped = []
    for i, step in enumerate(steps):
        if step > DROP_FACTOR * nominal:
            missing = round(step / nominal) - 1
            dropped.append(f"{missing} frame(s) missing between frame {i} (t = {float(times[i]):.6g} s) and frame "
                           f"{i + 1} (t = {float(times[i + 1]):.6g} s), nominal interval {float(nominal):.6g} s")
    keep = [0]
    duplicated = []
    for i in range(1, len(images)):
        if np.array_equal(images[i], images[keep[-1]]):
            duplicated.append(f"frame {i} (t = {float(times[i]):.6g} s) repeats frame {keep[-1]} exactly; left out")
        else:
            keep.append(i)
    t = np.array([float(times[i]) for i in keep])
    return Frames(images[keep], t, index[keep], float(nominal), dropped, duplicated)


def write_video(path: str | Path, images: Sequence[np.ndarray], pts: Sequence[int], time_base: Fraction) -> None:
    """Grey uint8 frames to ``path`` (FFV1, lossless, in AVI: its time base is exact at any
    frame rate, unlike Matroska's millisecond clock), frame i at ``pts[i] · time_base`` s."""
    import av

    with av.open(str(path), "w", format="avi") as container:
        # FFV1 version 3 with slice CRCs, every frame a key frame: damage is caught where it is
        stream = container.add_stream("ffv1", rate=Fraction(1) / time_base)
        stream.codec_context.options = {"level": "3", "slicecrc": "1", "context": "1", "g": "1"}
        stream.height, stream.width = images[0].shape
        stream.pix_fmt = "gray"
        stream.time_base = time_base
        stream.codec_context.time_base = time_base
        for image, stamp in zip(images, pts, strict=True):
            frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(image, dtype=np.uint8), format="gray")
            frame.pts, frame.time_base = int(stamp), time_base
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
