"""``warpcloth track calibrate`` and ``warpcloth track VIDEO``: from lab video to tracked shapes."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from warpcloth.errors import OptionError
from warpcloth.io.json_file import json_text

from .options import add_no_progress, add_overwrite, at_least, figure_path, new_file, path_text, positive

if TYPE_CHECKING:
    from warpcloth.track.markers import Tracked

SUBCOMMANDS = ("calibrate", "video")


def route(argv: Sequence[str]) -> list[str]:
    """``warpcloth track VIDEO ...`` is ``warpcloth track video VIDEO ...``: argparse cannot
    have a sub-command and a file in the same place, so the file's form is rewritten."""
    argv = list(argv)
    for i, word in enumerate(argv):
        if not word.startswith("-"):
            if word == "track" and i + 1 < len(argv) and argv[i + 1] not in (*SUBCOMMANDS, "-h", "--help"):
                argv.insert(i + 1, "video")
            break
    return argv


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``track calibrate`` and ``track VIDEO``."""
    track_p = sub.add_parser(
        "track",
        help="markers in lab video → tracked shapes (frame, t, s, x, y) for fit",
        description="warpcloth track calibrate IMAGE... -o plane.json; then warpcloth track VIDEO "
        "--plane plane.json -o shapes.csv (short for: warpcloth track video VIDEO ...)",
    )
    track_sub = track_p.add_subparsers(dest="track_command", required=True)
    cal = track_sub.add_parser("calibrate", help="camera, lens and the strip's plane from chessboard images")
    cal.set_defaults(handler=calibrate_command)
    cal.add_argument(
        "images",
        nargs="+",
        metavar="IMAGE",
        help="board images, the first held in the strip's plane (the plane view), the others in other "
        "poses (for the lens distortion)",
    )
    cal.add_argument("-o", "--output", type=path_text, required=True, help="the plane file to write (.json)")
    cal.add_argument(
        "--board",
        required=True,
        metavar="COLUMNSxROWS",
        help="the chessboard's inner corners, e.g. 11x10 for a board of 12 × 11 squares",
    )
    cal.add_argument("--square-mm", type=positive, required=True, help="the side of a square, mm")
    cal.add_argument(
        "--origin-corner",
        metavar="I,J",
        help="the inner corner (column, row, from 0, top left in the plane view) at the clamp's lowest "
        "point, the board's rows level",
    )
    cal.add_argument(
        "--clamp-edge-px",
        metavar="U1,V1,U2,V2",
        help="instead: two pixels of the plane view, the clamp's lowest point and a point along its lower "
        "edge towards +x",
    )
    cal.add_argument(
        "--max-rms-px",
        type=positive,
        default=0.3,
        help="refuse a calibration whose reprojection RMS in any image exceeds this (default: 0.3 px; "
        "a clean calibration has a fraction of that, the bundled example 0.07)",
    )
    add_overwrite(cal, "plane file -o")
    vid = track_sub.add_parser(
        "video", help="track the markers (or the centreline) of a video (warpcloth track VIDEO ... for short)"
    )
    vid.set_defaults(handler=video_command)
    vid.add_argument(
        "video",
        metavar="VIDEO",
        help="the video (any container and codec FFmpeg reads; its timestamps are each frame's time)",
    )
    vid.add_argument("--plane", required=True, help="plane.json from warpcloth track calibrate")
    vid.add_argument(
        "--marker-s",
        metavar="S,S,...|FIRST:LAST:STEP",
        help="the markers' arc lengths from the clamp's lowest point, mm, in order along the strip",
    )
    vid.add_argument("--marker-diameter-mm", type=positive, help="the markers' diameter, mm (with --marker-s)")
    vid.add_argument(
        "--marker-height-mm",
        type=float,
        default=0.0,
        help="how far the markers' centres stand in front of the calibrated plane, towards the camera (a "
        "sticker's thickness), mm: measured on that plane, free of the oblique view's parallax (default 0)",
    )
    vid.add_argument(
        "--centreline-s",
        metavar="S,S,...|FIRST:LAST:STEP",
        help="instead of markers: the strip's centreline at these arc lengths from the clamp's lowest "
        "point, mm, measured from the free end (needs --free-length-mm)",
    )
    vid.add_argument(
        "--edge-s",
        metavar="S,S,...|FIRST:LAST:STEP",
        help="instead of markers: the strip's dyed near edge (the seed paper's setup; a colour video) at these "
        "arc lengths from the clamp's lowest point, mm, measured from the free end (needs --free-length-mm "
        "and --edge-colour)",
    )
    vid.add_argument(
        "--edge-colour",
        metavar="R,G,B|auto",
        help="the dye's colour, 0-255 each, or auto: learned from the first frame (with --edge-s)",
    )
    vid.add_argument(
        "--thickness-mm",
        type=positive,
        help="the fabric's thickness: with --edge-s the edge's points are moved half of it into the fabric, onto "
        "the midline the model's chain represents (without it they are the edge's outer surface); with "
        "--centreline-s (where it is needed) the strip seen edge-on is this wide, and a strip seen wider is "
        "refused",
    )
    vid.add_argument(
        "--free-length-mm", type=positive, help="the strip's free length, mm (with --centreline-s or --edge-s)"
    )
    vid.add_argument("-o", "--output", type=path_text, required=True, help="the tracked shapes to write (.csv)")
    vid.add_argument(
        "--background",
        metavar="IMAGE",
        help="a frame of the scene without the strip (default: the per-pixel median of the video's "
        "frames, a fixed-camera background model)",
    )
    vid.add_argument(
        "--mask",
        metavar="IMAGE",
        help="an image the size of the frames, white (non-zero) where nothing is to be tracked: the "
        "clamp's sweep, a screw, a reflection; everywhere else black",
    )
    vid.add_argument(
        "--roi",
        metavar="X0,Y0,X1,Y1",
        help="track only inside this rectangle of the frame, px (columns X0 to X1, rows Y0 to Y1)",
    )
    vid.add_argument(
        "--threshold-dn",
        type=positive,
        default=None,
        help="darkening below the background that counts as marker, grey levels (default: 10× the "
        "sensor noise estimated in each frame)",
    )
    vid.add_argument("--overlay", metavar="PNG", help="also write a figure of what was tracked")
    vid.add_argument(
        "--overlay-video",
        metavar="AVI",
        help="also write every frame with its tracked points circled (grey FFV1 in AVI)",
    )
    vid.add_argument(
        "--overlay-frame", type=at_least(0), default=None, help="the frame the overlay shows (default: the middle one)"
    )
    add_no_progress(vid)
    add_overwrite(vid, "output file -o (and --overlay, --overlay-video)")


UNCERTAINTY_SAYS = {
    "markers": "u_px, u_mm: standard uncertainty of each coordinate, from the sensor noise through each dot's "
    "outline and the outline's lopsidedness",
    "centreline": "u_px, u_mm: standard uncertainty across the strip, from the sensor noise and the floor "
    "validation measured; u_along_mm: along it, the floor the arc from the free end was validated to, a "
    "frame's points sharing its error",
    "edge": "u_px, u_mm: standard uncertainty across the strip, from the silhouette's scatter and the validated "
    "floor; u_along_mm: along it, from the free end's noise and the validated floor, a frame's points sharing "
    "its error",
}
"""What each mode's ``u_px, u_mm`` hold, as the shapes file's header says."""


def hidden_notes(tracked: Tracked) -> list[str]:
    """One line per marker hidden under the mask in some frames: which, in how many, from when to when."""
    notes = []
    for m, s in enumerate(tracked.s_mm):
        gone = ~np.isfinite(tracked.mm[:, m, 0])
        if gone.any():
            notes.append(
                f"marker s = {s:g} mm hidden (behind the clamp or under --mask) in {gone.sum()} of {len(gone)} frames "
                f"(t = {tracked.t[gone][0]:.6g} to {tracked.t[gone][-1]:.6g} s): no rows for it there"
            )
    return notes


def _pair(text: str, option: str, sep: str) -> tuple[int, int]:
    try:
        a, b = (int(v) for v in text.lower().split(sep))
    except ValueError:
        raise OptionError(option, f"expected two whole numbers as A{sep}B, got {text!r}") from None
    if a < 0 or b < 0:
        raise OptionError(option, f"expected numbers ≥ 0, got {text!r}")
    return a, b


def marker_arcs(text: str, option: str = "--marker-s") -> np.ndarray:
    """``--marker-s`` (or ``--centreline-s``): ``5,15,25`` or ``5:95:10`` (FIRST to LAST
    included, STEP dividing LAST − FIRST), increasing, ≥ 0, at least two."""
    expected = f"expected S,S,... or FIRST:LAST:STEP (mm, FIRST < LAST, STEP > 0), got {text!r}"
    try:
        values = [float(v) for v in text.split(":" if ":" in text else ",")]
    except ValueError:
        raise OptionError(option, expected) from None
    if ":" in text and (
        len(values) != 3 or not np.all(np.isfinite(values)) or not values[0] < values[1] or not values[2] > 0
    ):
        raise OptionError(option, expected)
    if ":" in text:
        first, last, step = values
        steps = (last - first) / step
        # a STEP that does not reach LAST exactly would move the last point silently
        if not abs(steps - round(steps)) <= 1e-9 * max(steps, 1.0):
            raise OptionError(
                option,
                f"{text!r}: STEP {step:g} does not divide LAST − FIRST = {last - first:g} mm "
                "(LAST is the last arc length)",
            )
        values = np.linspace(first, last, round(steps) + 1)
    arcs = np.array(values)
    if len(arcs) < 2 or not np.all(np.isfinite(arcs)) or arcs[0] < 0 or np.any(np.diff(arcs) <= 0):
        raise OptionError(option, f"{text!r}: at least two arc lengths, ≥ 0 and increasing along the strip")
    return arcs


def _what_to_track(args: argparse.Namespace) -> np.ndarray:
    # markers (--marker-s with their diameter), the centreline (--centreline-s) or the dyed
    # edge (--edge-s with its colour), each of the last two with the free length
    given = [option for option in ("marker_s", "centreline_s", "edge_s") if getattr(args, option)]
    if len(given) != 1:
        raise OptionError(
            "--marker-s",
            "give --marker-s (markers), --centreline-s (the centreline without markers) or --edge-s (the dyed "
            "edge), one of them",
        )
    if args.edge_colour and not args.edge_s:
        raise OptionError("--edge-colour", "goes with --edge-s (the dyed edge's colour)")
    if args.marker_height_mm and not args.marker_s:
        raise OptionError("--marker-height-mm", "goes with --marker-s (how far the markers stand off the plane)")
    if args.thickness_mm is not None and not (args.edge_s or args.centreline_s):
        raise OptionError(
            "--thickness-mm", "goes with --edge-s (the midline lies half of it inside the edge) or --centreline-s"
        )
    if args.marker_s:
        if args.marker_diameter_mm is None:
            raise OptionError("--marker-diameter-mm", "is needed with --marker-s (the markers' diameter, mm)")
        return marker_arcs(args.marker_s)
    option = "--edge-s" if args.edge_s else "--centreline-s"
    if args.free_length_mm is None:
        raise OptionError("--free-length-mm", f"is needed with {option} (arc lengths are measured from the free end)")
    if args.edge_s and not args.edge_colour:
        raise OptionError("--edge-colour", "is needed with --edge-s: the dye's colour as R,G,B (0-255), or auto")
    if args.centreline_s and args.thickness_mm is None:
        raise OptionError(
            "--thickness-mm",
            "is needed with --centreline-s: the centre of what the camera sees is the midline only where it sees "
            "the strip edge-on, its thickness wide, and a camera off the strip's edge (or off its axis: a strip "
            "25 mm wide, 30 mm off the axis of a camera 450 mm away, shows 1.7 mm of its face) sees a face too; "
            "the fabric's thickness tells the two apart",
        )
    arcs = marker_arcs(args.edge_s or args.centreline_s, option)
    if arcs[-1] > args.free_length_mm:
        raise OptionError(
            option, f"{arcs[-1]:g} mm lies beyond the free end (--free-length-mm {args.free_length_mm:g})"
        )
    return arcs


def edge_colour(text: str) -> np.ndarray | None:
    """``--edge-colour``: ``R,G,B`` (0-255 each, not grey) or ``auto`` (None: learned)."""
    from warpcloth.track.coloured_edge import chroma_direction

    if text.strip().lower() == "auto":
        return None
    try:
        colour = np.array([float(v) for v in text.split(",")])
    except ValueError:
        colour = np.zeros(0)
    if colour.shape != (3,) or not np.all((colour >= 0) & (colour <= 255)):
        raise OptionError("--edge-colour", f"expected R,G,B (three numbers from 0 to 255) or auto, got {text!r}")
    chroma_direction(colour)
    return colour


def ignored_pixels(mask: str | None, roi: str | None, size: tuple[int, int]) -> np.ndarray | None:
    """The pixels ``--mask`` (non-zero) and ``--roi X0,Y0,X1,Y1`` (outside it) leave out of
    the tracking, as a bool array of the frames' shape; None when neither is given."""
    from warpcloth.track.calibration import read_image

    width, height = size
    ignore = None
    if mask:
        image = read_image(mask, "--mask")
        if image.shape != (height, width):
            raise OptionError(
                "--mask",
                f"{mask} is {image.shape[1]} × {image.shape[0]} px, the video's frames are {width} × {height} px",
            )
        ignore = image > 0
    if roi:
        try:
            x0, y0, x1, y1 = (int(v) for v in roi.split(","))
        except ValueError:
            raise OptionError("--roi", f"expected X0,Y0,X1,Y1 (whole px), got {roi!r}") from None
        if not (0 <= x0 < x1 <= width and 0 <= y0 < y1 <= height):
            raise OptionError(
                "--roi",
                f"{roi}: needs 0 ≤ X0 < X1 ≤ {width} and 0 ≤ Y0 < Y1 ≤ {height} (the frame, px)",
            )
        outside = np.ones((height, width), bool)
        outside[y0:y1, x0:x1] = False
        ignore = outside if ignore is None else ignore | outside
    if ignore is not None and ignore.all():
        raise OptionError("--mask" if mask else "--roi", "leaves no pixel of the frame to track")
    return ignore


def calibrate_command(args: argparse.Namespace) -> int:
    """Calibrate camera and plane, write plane.json."""

    from warpcloth.io.atomic import write_text_atomically
    from warpcloth.io.provenance import provenance
    from warpcloth.track.calibration import calibrate_plane

    inner = _pair(args.board, "--board", "x")
    if min(inner) < 2:
        raise OptionError("--board", f"{args.board}: a chessboard has at least 2 × 2 inner corners")
    corner = _pair(args.origin_corner, "--origin-corner", ",") if args.origin_corner else None
    out = new_file(args.output, args.overwrite, "-o")
    if out.suffix.lower() != ".json":
        raise OptionError("-o", f"{out} must end in .json")
    _, record = calibrate_plane(
        args.images,
        inner,
        args.square_mm,
        origin_corner=corner,
        clamp_edge_px=args.clamp_edge_px,
        max_rms_px=args.max_rms_px,
    )
    record["provenance"] = provenance(device="cpu")
    write_text_atomically(out, json_text(record) + "\n")
    view = record["plane_view"]
    print(
        f"{len(args.images)} board images: reprojection RMS {record['reprojection_rms_px']:.3g} px (worst image "
        f"{max(v['rms_px'] for v in record['views']):.3g} px); plane view {view['rms_px']:.3g} px = "
        f"{view['rms_mm']:.3g} mm, {view['mm_per_px'][0]:.3g} to {view['mm_per_px'][1]:.3g} mm/px"
    )
    print(f"wrote {out}")
    return 0


def _outputs(args: argparse.Namespace) -> tuple[Path, Path | None, Path | None]:
    # the shapes file, the overlay figure and the overlay video: distinct, each of its kind, each new
    named = {
        option: Path(text)
        for option, text in (("-o", args.output), ("--overlay", args.overlay), ("--overlay-video", args.overlay_video))
        if text
    }
    seen: dict[Path, str] = {}
    for option, path in named.items():
        where = path.resolve()
        if where in seen:
            raise OptionError(option, f"{path} is also {seen[where]}'s file; each output needs a path of its own")
        seen[where] = option
    if named["-o"].suffix.lower() != ".csv":
        raise OptionError("-o", f"{named['-o']} must end in .csv (the tracked shapes)")
    out = new_file(named["-o"], args.overwrite, "-o")
    overlay = figure_path(named["--overlay"], args.overwrite, "--overlay") if args.overlay else None
    movie = None
    if args.overlay_video:
        if named["--overlay-video"].suffix.lower() != ".avi":
            raise OptionError("--overlay-video", f"{args.overlay_video} must end in .avi")
        movie = new_file(named["--overlay-video"], args.overwrite, "--overlay-video")
    return out, overlay, movie


def video_command(args: argparse.Namespace) -> int:
    """Track the markers of a video, write the shapes CSV (and the overlay)."""
    from warpcloth.io.atomic import write_text_atomically
    from warpcloth.io.provenance import file_checksum
    from warpcloth.track.calibration import read_image, read_plane
    from warpcloth.track.centreline import track_centreline
    from warpcloth.track.coloured_edge import track_coloured_edge
    from warpcloth.track.markers import track_markers
    from warpcloth.track.overlay import avi_timing, write_overlay, write_overlay_video
    from warpcloth.track.video import FrameStream, median_background

    arcs = _what_to_track(args)
    mode = "markers" if args.marker_s else "centreline" if args.centreline_s else "edge"
    what = {"markers": "markers", "centreline": "centreline points", "edge": "points of the dyed edge"}[mode]
    colour = edge_colour(args.edge_colour) if args.edge_s else None
    mapping = read_plane(args.plane, "--plane")
    out, overlay, movie = _outputs(args)
    in_colour = bool(args.edge_s)  # only the dyed edge needs the frames' colour
    background = read_image(args.background, "--background", in_colour) if args.background else None
    # decoded as it is tracked: a long recording is never held whole
    frames = FrameStream(args.video, "VIDEO", in_colour)
    if args.overlay_frame is not None and args.overlay_frame >= frames.total:
        raise OptionError(
            "--overlay-frame",
            f"{args.overlay_frame} is not a frame of {args.video}, which has "
            f"{frames.total} in its container (0 to {frames.total - 1})",
        )
    size = (frames.width, frames.height)
    if tuple(size) != tuple(mapping.image_size):
        raise OptionError(
            "--plane",
            f"{args.plane} was calibrated for {mapping.image_size[0]} × "
            f"{mapping.image_size[1]} px images, the video's frames are {size[0]} × {size[1]} px",
        )
    ignore = ignored_pixels(args.mask, args.roi, size)
    if background is None:
        background = median_background(frames)
        source = "the median of the frames"
    elif background.shape[:2] != (size[1], size[0]):
        raise OptionError(
            "--background",
            f"{args.background} is {background.shape[1]} × {background.shape[0]} px, "
            f"the video's frames are {size[0]} × {size[1]} px",
        )
    else:
        source = str(args.background)
    if args.marker_s:
        tracked = track_markers(
            frames,
            background,
            mapping.raised(args.marker_height_mm) if args.marker_height_mm else mapping,
            arcs,
            args.marker_diameter_mm,
            args.video,
            threshold_dn=args.threshold_dn,
            progress=not args.no_progress,
            ignore=ignore,
        )
    elif args.edge_s:
        tracked = track_coloured_edge(
            frames,
            background,
            mapping,
            arcs,
            args.free_length_mm,
            colour,
            args.video,
            thickness_mm=args.thickness_mm,
            ignore=ignore,
            progress=not args.no_progress,
        )
    else:
        tracked = track_centreline(
            frames,
            background,
            mapping,
            arcs,
            args.free_length_mm,
            args.video,
            threshold_dn=args.threshold_dn,
            progress=not args.no_progress,
            ignore=ignore,
            thickness_mm=args.thickness_mm,
        )
    dropped, duplicated = frames.dropped, frames.duplicated
    times = [frames.times[i] for i in tracked.frame]  # exact, before the overlay's pass decodes them again
    off = avi_timing(times)[2] if movie is not None else 0.0  # AVI refuses > 1000 frames/s: before writing
    for note in (*dropped, *duplicated):
        print(f"warpcloth track: warning: {args.video}: {note}", file=sys.stderr)
    kept = len(tracked.t)
    if args.overlay_frame is not None and args.overlay_frame >= kept:
        raise OptionError(
            "--overlay-frame", f"{args.overlay_frame} is not one of the {kept} frames kept (0 to {kept - 1})"
        )
    hidden = hidden_notes(tracked)
    for note in hidden:
        print(f"warpcloth track: note: {args.video}: {note}", file=sys.stderr)
    seen = []
    if tracked.seen_width_mm is not None:
        w = tracked.seen_width_mm
        seen = [
            f"the strip is seen {np.min(w):.3g} to {np.max(w):.3g} mm wide across (median {np.median(w):.3g} mm), "
            f"as the {args.thickness_mm:g} mm --thickness-mm allows"
        ]
        for note in seen:
            print(f"warpcloth track: note: {args.video}: {note}", file=sys.stderr)
    colour_notes = []
    if mode == "edge" and frames.chroma_subsampling != (1, 1):
        stored = (
            "one colour sample per {} × {} pixels".format(*frames.chroma_subsampling)
            if frames.chroma_subsampling
            else "its colour in a format that does not say at what resolution"
        )
        colour_notes = [
            f"the video stores {stored}: the dyed edge's cut face is not resolved, and its points are as good as "
            "on the rig's H.264 4:2:0 (docs/calibration.md: the midline 0.05 mm across and 0.06 mm along RMS, "
            "the silhouette 0.06 and 0.10 mm, in u_mm and u_along_mm); a lossless recording (FFV1, raw RGB) and "
            "--thickness-mm give 0.02 mm"
        ]
    elif mode == "edge" and args.thickness_mm is None:
        colour_notes = [
            "without --thickness-mm the dyed edge's cut face is not fitted apart from the dye behind it: lit "
            "unlike it, it moves the silhouette by up to a quarter pixel (docs/calibration.md)"
        ]
    for note in colour_notes:
        print(f"warpcloth track: note: {args.video}: {note}", file=sys.stderr)
    video = file_checksum(args.video)
    header = [
        f"# warpcloth track {args.video} (sha256 {video['sha256']}), plane {args.plane}, background {source}",
        f"# {len(arcs)} {what}, {kept} frames; sensor noise {np.median(tracked.noise_dn):.3g} grey "
        f"levels; {UNCERTAINTY_SAYS[mode]} (the calibration's is in the plane file); fit judges its RMS "
        "against u_mm",
        *(f"# hidden: {note}" for note in hidden),
        *(f"# seen: {note}" for note in seen),
        *(f"# colour: {note}" for note in colour_notes),
        *(f"# dropped: {note}" for note in dropped),
        *(f"# duplicated: {note}" for note in duplicated),
        tracked.columns,
    ]
    write_text_atomically(out, "\n".join(header + tracked.csv_rows()) + "\n")
    if overlay is not None:
        shown = args.overlay_frame if args.overlay_frame is not None else kept // 2
        image = next(image for position, (_, _, image) in enumerate(frames) if position == shown)
        write_overlay(overlay, image, tracked, shown)
    if movie is not None:
        write_overlay_video(movie, frames, tracked, times)
        if off:
            print(
                f"warpcloth track: warning: {movie}: AVI holds no time base finer than 1/1000 s; frame times are "
                f"rounded, by up to {off:.3g} s",
                file=sys.stderr,
            )
    print(
        f"tracked {len(arcs)} {what} in {kept} frames (t = {tracked.t[0]:.6g} to {tracked.t[-1]:.6g} s): "
        f"median uncertainty {np.nanmedian(tracked.u_mm):.2g} mm ({np.nanmedian(tracked.u_px):.2g} px), sensor noise "
        f"{np.median(tracked.noise_dn):.3g} grey levels; {len(dropped)} gaps of dropped frames, "
        f"{len(duplicated)} duplicated frames left out"
    )
    print(f"wrote {', '.join(str(p) for p in (out, overlay, movie) if p is not None)}")
    return 0
