"""The dyed near edge, as the seed paper films it, on frames drawn analytically here: a
strip hanging 3° from the vertical, its near edge (0.5 mm thick) and the first 0.65 mm of its
visible face dyed red, the rest of the face white, a grey textured backdrop of the same
brightness as the dye on the other side, a dark clamp above. Lens blur, colour subsampled
4:2:0 as H.264 stores it, sensor noise; or the colour kept at every pixel (a lossless
recording), with the cut face lit a brighter red than the dyed side face beside it. The truth
is the geometry itself."""

from pathlib import Path

import numpy as np
import pytest

from warpcloth.errors import ArgumentError
from warpcloth.track.calibration import PlaneMapping
from warpcloth.track.coloured_edge import learn_edge_colour, track_coloured_edge
from warpcloth.track.video import Frames

MM_PER_PX = 0.2
SIZE = (300, 640)  # width, height, px
ROOT_PX = (150.0, 40.0)  # the clamp's lowest point
TILT = np.radians(3.0)
ALONG = np.array([np.sin(TILT), -np.cos(TILT)])  # down the strip, plane mm (y up)
ACROSS = np.array([np.cos(TILT), np.sin(TILT)])  # towards the visible face
LENGTH_MM, THICKNESS_MM, DYED_FACE_MM, FACE_MM = 100.0, 0.5, 0.65, 8.0
RED, WHITE, CLAMP = np.array([190.0, 22.0, 20.0]), np.array([205.0, 205.0, 205.0]), np.array([22.0, 24.0, 30.0])
LIT_CUT_FACE = 1.15 * RED  # the cut face facing the light: on the rig 15 % brighter than the side face
SUB = 6


def mapping() -> PlaneMapping:
    f = 1000.0
    k = np.array([[f, 0.0, ROOT_PX[0]], [0.0, f, ROOT_PX[1]], [0.0, 0.0, 1.0]])
    to_plane = np.diag([f * MM_PER_PX, -f * MM_PER_PX, 1.0])  # normalised → mm, y up
    return PlaneMapping(k, np.zeros(5), to_plane, SIZE)


def frame(rng: np.random.Generator, subsampled: bool) -> np.ndarray:
    import cv2

    w, h = SIZE
    v, u = (np.mgrid[0 : h * SUB, 0 : w * SUB] + 0.5) / SUB - 0.5
    x, y = (u - ROOT_PX[0]) * MM_PER_PX, -(v - ROOT_PX[1]) * MM_PER_PX
    s = x * ALONG[0] + y * ALONG[1]
    n = x * ACROSS[0] + y * ACROSS[1]
    texture = cv2.resize(rng.uniform(0.75, 1.25, (12, 8)), (w * SUB, h * SUB), interpolation=cv2.INTER_CUBIC)
    image = np.repeat((95.0 * texture)[..., None], 3, axis=2)  # grey, as bright as the dye
    on_strip = (s >= 0) & (s <= LENGTH_MM)
    image[on_strip & (n >= -THICKNESS_MM / 2) & (n < THICKNESS_MM / 2 + FACE_MM)] = WHITE
    image[on_strip & (n >= -THICKNESS_MM / 2) & (n < THICKNESS_MM / 2 + DYED_FACE_MM)] = RED
    if not subsampled:
        image[on_strip & (n >= -THICKNESS_MM / 2) & (n < THICKNESS_MM / 2)] = LIT_CUT_FACE
    image[y > 0] = CLAMP
    image = image.reshape(h, SUB, w, SUB, 3).mean(axis=(1, 3))
    image = cv2.GaussianBlur(image, (0, 0), 0.6)
    if subsampled:  # 4:2:0: the chroma kept at half resolution each way, as an H.264 file holds it
        ycc = cv2.cvtColor(image.astype(np.float32) / 255.0, cv2.COLOR_RGB2YCrCb)
        for c in (1, 2):
            half = cv2.resize(ycc[..., c], (w // 2, h // 2), interpolation=cv2.INTER_AREA)
            ycc[..., c] = cv2.resize(half, (w, h), interpolation=cv2.INTER_LINEAR)
        image = cv2.cvtColor(ycc, cv2.COLOR_YCrCb2RGB) * 255.0
    image = image + rng.normal(0.0, 1.5, (h, w, 3))
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)


@pytest.fixture(scope="module", params=[(2, 2), (1, 1)], ids=["4:2:0", "full colour"])
def frames(request):
    rng = np.random.default_rng(11)
    subsampled = request.param == (2, 2)
    images = np.stack([frame(rng, subsampled) for _ in range(3)])
    return Frames(images, np.arange(3) / 60.0, np.arange(3), 1 / 60.0, chroma_subsampling=request.param)


@pytest.fixture(scope="module")
def background(frames):
    import cv2

    rng = np.random.default_rng(11)
    w, h = SIZE
    texture = cv2.resize(rng.uniform(0.75, 1.25, (12, 8)), (w, h), interpolation=cv2.INTER_CUBIC)
    image = np.repeat((95.0 * texture)[..., None], 3, axis=2)
    image[: int(ROOT_PX[1]) + 1] = CLAMP
    return image


S_MM = np.arange(10.0, 91.0, 10.0)


@pytest.mark.parametrize("thickness", [None, THICKNESS_MM])
@pytest.mark.parametrize("colour", [RED, None])
def test_the_dyed_edge_is_found_at_its_silhouette_within_a_fiftieth_of_a_mm(frames, background, thickness, colour):
    tracked = track_coloured_edge(
        frames, background, mapping(), S_MM, LENGTH_MM, colour, "synthetic", thickness_mm=thickness
    )
    # the midline at s, or the silhouette half the thickness beyond it on the backdrop's side
    truth = S_MM[:, None] * ALONG - (0.0 if thickness else THICKNESS_MM / 2) * ACROSS
    error = tracked.mm - truth[None]
    bias, rms = error.reshape(-1, 2).mean(axis=0), np.sqrt(np.mean(error.reshape(-1, 2) ** 2, axis=0))
    if thickness or frames.chroma_subsampling != (1, 1):
        assert np.all(np.abs(bias) <= 0.02) and np.all(rms <= 0.05), (bias, rms)
    else:
        # the silhouette alone cannot tell the brighter cut face from the side face without
        # its width (the thickness): its rise is cut short, and the edge is found 0.13 px
        # towards the backdrop (measured -0.027 mm across); the stated u still covers it
        assert 0.02 < -bias[0] < 0.04 and abs(bias[1]) <= 0.02, bias
    # the stated uncertainty covers each point's error (2σ) across the strip (u_mm) and along it (u_along_mm)
    assert np.mean(np.abs(error @ ACROSS) <= 2.0 * tracked.u_mm) >= 0.9, (error, tracked.u_mm)
    assert np.mean(np.abs(error @ ALONG) <= 2.0 * tracked.u_along_mm) >= 0.9, (error, tracked.u_along_mm)


def test_a_grey_first_frame_teaches_no_colour(background):
    grey = np.repeat(background.mean(axis=2, keepdims=True), 3, axis=2)
    grey[300:310, 140:160] = 250.0  # a white patch: it differs, but holds no colour
    with pytest.raises(ArgumentError, match="--edge-colour"):
        learn_edge_colour(grey, np.repeat(background.mean(axis=2, keepdims=True), 3, axis=2), None)


def test_a_band_with_a_brighter_face_is_fitted_at_its_edge_only_with_the_face_step():
    # blurred steps drawn exactly (the error function): backdrop 5, a cut face 2.4 px wide at
    # 104, the dyed side face at 90 to 6 px, then the undyed face at 0, blur σ 1.4 px
    from scipy.special import ndtr

    from warpcloth.track.edges import band_edges

    x = np.linspace(-12.0, 12.0, 97)
    edge = np.array([-3.0, -2.7, -2.5, -2.2])
    z = (x[None, :] - edge[:, None]) / 1.4
    profiles = 5.0 + 99.0 * ndtr(z) - 14.0 * ndtr(z - 2.4 / 1.4) - 90.0 * ndtr(z - 6.0 / 1.4)
    two, _, _, _ = band_edges(profiles, x, edge - 0.5, edge + 5.0)
    three, inner, _, misfit = band_edges(profiles, x, edge - 0.5, edge + 5.0, face=2.4)
    assert np.all(np.abs(three - edge) < 1e-3) and np.all(np.abs(inner - edge - 6.0) < 1e-3), (three, inner)
    assert np.all(misfit < 1e-3)
    # without it the brighter face's peak pulls the edge outwards by a fifth of a pixel
    assert np.all(two - edge < -0.1), two - edge


@pytest.mark.parametrize(
    ("stored", "shared"),
    [("yuv420p", (2, 2)), ("nv12", (2, 2)), ("yuv422p", (2, 1)), ("yuv444p", (1, 1)), ("rgb24", (1, 1)),
     ("bgr0", (1, 1)), ("bayer_rggb8", (2, 2))],
)  # fmt: skip
def test_a_videos_colour_resolution_is_read_from_its_format(stored, shared):
    # only where every pixel's colour is stored is the cut face fitted apart (a Bayer
    # mosaic interpolates two of three colours at every pixel: as coarse as 4:2:0)
    import av

    from warpcloth.track.video import FrameStream, colour_sampling

    assert colour_sampling(av.VideoFormat(stored, 768, 720)) == shared
    assert colour_sampling(None) is None
    rig = Path(__file__).resolve().parents[1] / "scenes" / "data" / "rig" / "edge.mp4"
    assert FrameStream(rig, colour=True).chroma_subsampling == (2, 2)
