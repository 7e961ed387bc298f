"""The one interface every tracker shares, and the registry that names them.

Shaped like OpenCV's ``Tracker``: ``init(frame, roi)`` once, then ``update(frame) -> (ok, state)`` per frame.
Frames are decoded BGR (or grey) uint8 arrays and are never modified. ``ok=False`` means "not found in this
frame" -- data, not an error -- and ``state`` then holds the last good geometry.
"""

from __future__ import annotations

import difflib
import functools
import inspect
import math
import re
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import ClassVar, Iterable

import numpy as np

from ..errors import LptrackError, NotStartedError, UsageError, is_real, is_whole
from ..geometry import Ellipse, as_ellipse, check_roi_fits, wrap_degrees
from ..images import check_frame, frame_layout, to_gray


@dataclass(frozen=True)
class TrackState:
    """Where the object is in one frame.

    Attributes
    ----------
    ellipse : Ellipse
        Current outline in pixels; its ``angle_deg`` is the initial angle plus ``rotation_deg``, not wrapped (the
        CSV's ``angle_deg`` is, into (-180, 180]).
    scale : float
        Size relative to the initial ROI (1.0 at init).
    rotation_deg : float or None
        Cumulative (unwrapped) counter-clockwise rotation since init, in degrees; ``None`` for trackers that
        cannot measure rotation (OpenCV's).
    score : float
        Match confidence in [0, 1].
    """

    ellipse: Ellipse
    scale: float
    rotation_deg: float | None
    score: float

    @property
    def centre(self) -> tuple[float, float]:
        return self.ellipse.centre


class Tracker(ABC):
    """Interface of every tracker: ``init`` on a frame and a ROI, then ``update`` on each following frame."""

    #: Registry name, used by ``--tracker`` and ``lptrack bench``.
    name: ClassVar[str] = ""
    #: One line for ``--help`` and tables.
    summary: ClassVar[str] = ""
    #: Whether ``rotation_deg`` is measured.
    measures_rotation: ClassVar[bool] = True

    def __init_subclass__(cls, **kwargs) -> None:
        # Every construction checks its keyword tuning against the kinds of its defaults (see _check_kind), made
        # through create_tracker or with the class itself: LogPolarCorrelationTracker(long_term="false") was True.
        super().__init_subclass__(**kwargs)
        init = cls.__dict__.get("__init__")
        if init is None:
            return
        defaults = {p.name: p.default for p in inspect.signature(init).parameters.values()
                    if p.kind is p.KEYWORD_ONLY and p.default is not p.empty}
        if not defaults:
            return

        @functools.wraps(init)  # inspect.signature, and so tracker_parameters, still see the signature
        def checked_init(self, *args, **params):
            for key, value in params.items():
                if key in defaults:
                    _check_kind(type(self).name or type(self).__name__, key, value, defaults[key])
            init(self, *args, **params)

        cls.__init__ = checked_init

    @classmethod
    def available(cls) -> bool:
        """Whether this install can run the tracker (OpenCV's need the contrib build)."""
        return True

    @classmethod
    def unavailable_reason(cls) -> str:
        """Why :meth:`available` is False, and what to install; '' when it is True."""
        return ""

    @abstractmethod
    def init(self, frame: np.ndarray, roi: Ellipse) -> TrackState:
        """Start tracking the object inside ``roi`` on ``frame``; returns the initial state (score 1).

        ``frame`` is an image as OpenCV reads it: ``(H, W, 3)`` BGR (or BGRA, or grey), uint8, or float32 from 0 to
        255 (see :func:`~logpolar_track.images.check_frame`); every later frame must be laid out alike.

        ``roi`` is an :class:`~logpolar_track.geometry.Ellipse`, or a ``--roi`` string or its 3 or 5 numbers
        (:func:`~logpolar_track.geometry.as_ellipse`): pixels, degrees counter-clockwise on screen."""

    @abstractmethod
    def update(self, frame: np.ndarray) -> tuple[bool, TrackState]:
        """Find the object in the next ``frame``; ``ok`` is False when it is lost (state = last good)."""


@dataclass(frozen=True)
class Similarity:
    """A tracker's raw estimate for one frame: centre (pixels), scale, cumulative rotation (deg CCW), score."""

    cx: float
    cy: float
    scale: float
    rotation_deg: float
    score: float


class SimilarityTracker(Tracker):
    """Shared bookkeeping of lptrack's own trackers, which estimate a similarity transform per frame.

    Subclasses implement :meth:`_start` and :meth:`_estimate` on a grey frame (:attr:`gray_dtype`); this class
    turns their estimates into :class:`TrackState`, marks frames whose score is below ``lost_threshold`` (or
    that :meth:`_searching` says are a search) as lost, and keeps the last good state for them.
    """

    #: Element type of the grey frames given to :meth:`_start` and :meth:`_estimate`: float32, or None for
    #: trackers that take frames as decoded and convert only the regions they sample (less memory and time on
    #: large frames).
    gray_dtype: ClassVar[type | None] = np.float32

    def __init__(self, *, lost_threshold: float):
        self.lost_threshold = float(lost_threshold)
        self.roi: Ellipse | None = None
        self.given_roi: Ellipse | None = None
        self.last: Similarity | None = None

    def init(self, frame: np.ndarray, roi: Ellipse) -> TrackState:
        frame = np.asarray(frame)
        roi = check_start(frame, roi)
        if abs(roi.angle_deg) > 360.0:
            # The same ellipse, its angle within a turn: a huge one (1e300, through the API) left no precision for
            # the turns tracked (4041 degrees reported for 39.5).
            roi = Ellipse(roi.cx, roi.cy, roi.a, roi.b, wrap_degrees(roi.angle_deg))
        #: The ROI as given, which the states report moved, scaled and turned.
        self.given_roi = roi
        #: The ROI as tracked: one spelling of each ellipse, so that an ellipse is tracked alike however it is
        #: written (a tall box's ellipse as the benchmark writes it, ``w/2,h/2,0``, and as ``lptrack roi`` prints
        #: it, ``h/2,w/2,90``, were tracked on grids turned by 90 degrees: the same numbers up to rounding, which a
        #: hard sequence amplifies, crossing 0.775 against 0.787).
        self.roi = roi.axis_a_nearest_x()
        roi = self.roi
        self.frame_size = frame.shape[1], frame.shape[0]  # (width, height), pixels
        self.frame_layout = frame_layout(frame)
        self.last = Similarity(roi.cx, roi.cy, 1.0, 0.0, 1.0)
        self._start(self._prepared(frame), roi)
        return self._state(self.last)

    def update(self, frame: np.ndarray) -> tuple[bool, TrackState]:
        if self.last is None:
            raise NotStartedError("update() called before init(); start the tracker on a frame and a ROI first")
        frame = np.asarray(frame)
        check_frame(frame, self.frame_size, self.frame_layout)
        estimate = self._onto_frame(self._estimate(self._prepared(frame), self.last))
        # An estimate whose centre left the frame is lost whatever it scored: the search there matched the frame's
        # replicated border (``spatial`` followed an object out of view, tracked at 0.7, 90 px beyond the edge).
        ok = (estimate is not None and estimate.score >= self.lost_threshold and _finite(estimate)
              and self._inside(estimate) and not self._searching())
        if ok:
            self.last = estimate
            self._accept(estimate)
            return True, self._state(estimate)
        score = 0.0 if estimate is None or not math.isfinite(estimate.score) else estimate.score
        return False, self._state(self.last, score=score)

    def _onto_frame(self, estimate: Similarity | None) -> Similarity | None:
        """``estimate`` with a centre less than half a pixel beyond the outermost pixel centres moved onto them.

        A ROI may be centred on the outermost pixel centre (:func:`~logpolar_track.geometry.check_roi_fits`); an
        object resting there is estimated a few hundredths of a pixel either side of it, and those beyond were
        reported lost (a still object at ``cx`` = width - 1 lost on every frame, at scores of 0.95). Within its
        outermost pixel is still in the frame; farther out is left to :meth:`_inside`."""
        if estimate is None or not _finite(estimate):
            return estimate
        width, height = self.frame_size
        cx, cy = _onto_pixels(estimate.cx, width), _onto_pixels(estimate.cy, height)
        if cx == estimate.cx and cy == estimate.cy:
            return estimate
        return Similarity(cx, cy, estimate.scale, estimate.rotation_deg, estimate.score)

    def _inside(self, estimate: Similarity) -> bool:
        """Whether the estimate's centre is within the frame (its outermost pixel centres)."""
        width, height = self.frame_size
        return 0.0 <= estimate.cx <= width - 1 and 0.0 <= estimate.cy <= height - 1

    def _prepared(self, frame: np.ndarray) -> np.ndarray:
        return frame if self.gray_dtype is None else to_gray(frame, self.gray_dtype)

    def _state(self, sim: Similarity, score: float | None = None) -> TrackState:
        # Plain floats: estimates come out of NumPy arithmetic, whose scalars would otherwise reach the caller.
        scale, rotation = float(sim.scale), float(sim.rotation_deg)
        ellipse = self.given_roi.moved(float(sim.cx), float(sim.cy), scale, rotation)
        return TrackState(ellipse, scale, rotation, float(sim.score if score is None else score))

    @abstractmethod
    def _start(self, gray: np.ndarray, roi: Ellipse) -> None:
        """Build the appearance model from the first frame (float32 grey, or as decoded when the class's
        ``gray_dtype`` is None)."""

    @abstractmethod
    def _estimate(self, gray: np.ndarray, last: Similarity) -> Similarity | None:
        """Estimate the object's similarity in ``gray``; ``last`` is the last good estimate (a tracker may search
        from its own latest one instead, reported lost or not: ``lpcf`` does)."""

    def _accept(self, estimate: Similarity) -> None:
        """Hook called with every estimate accepted as tracked (e.g. to update a template)."""

    def _searching(self) -> bool:
        """Whether the last estimate is a search for a lost object rather than a track: it is then reported
        lost, whatever its score."""
        return False


def check_start(frame: np.ndarray, roi) -> Ellipse:
    """``roi`` as an :class:`Ellipse` (:func:`~logpolar_track.geometry.as_ellipse`: also a ``--roi`` string or its
    numbers), once ``frame`` is known to be an image (:func:`~logpolar_track.images.check_frame`) and the ROI to fit it
    (:func:`~logpolar_track.geometry.check_roi_fits`): what every tracker's ``init`` needs.

    Raises
    ------
    UsageError
        The frame is not an image, or is float32 with values within 0 to 1 (not 0 to 255).
    RoiError
        The ROI is not one, is too small or does not fit the frame (an :class:`Ellipse` is finite, with
        semi-axes > 0, by construction).
    """
    frame = np.asarray(frame)
    check_frame(frame)
    if frame.dtype == np.float32 and 0.0 < float(frame.max()) <= 1.0:
        # Checked on the first frame only: a frame of 0 to 255 that is all at most 1 would be black. (OpenCV's
        # trackers rounded such frames to an image of 0s and 1s; lptrack's own track them alike.)
        raise UsageError("a float32 frame must have values from 0 to 255 (as OpenCV's are), but this one's are all "
                         "within 0 to 1: multiply it by 255 first")
    roi = as_ellipse(roi)
    check_roi_fits(roi, frame.shape[1], frame.shape[0])
    return roi


def _finite(sim: Similarity) -> bool:
    return all(math.isfinite(v) for v in (sim.cx, sim.cy, sim.scale, sim.rotation_deg)) and sim.scale > 0


#: Largest search window of the thesis trackers and the spatial baseline, pixels a side: 101 x 101 centres
#: already take seconds a frame, and much larger ones exhaust memory.
MAX_WINDOW = 101

def check_ranges(tracker, ranges: dict[str, tuple[float, float | None]], *, positive=frozenset(),
                 odd=frozenset()) -> None:
    """Raise :class:`UsageError` naming the first of ``tracker``'s parameters (attributes) outside its ``(low,
    high)`` range: inclusive, but exclusive at a low of 0 for names in ``positive``; ``high`` None is unbounded;
    values must be finite, and odd for names in ``odd``. One line says what is accepted."""
    for name, (low, high) in ranges.items():
        value = getattr(tracker, name)
        above = value > low if name in positive else value >= low
        if not ((isinstance(value, int) or math.isfinite(value)) and above and (high is None or value <= high)
                and (name not in odd or value % 2 == 1)):
            lower = f"above {_number(low)}" if name in positive else f"at least {_number(low)}"
            accepted = lower if high is None else f"{lower} and at most {_number(high)}"
            accepted = f"an odd number {accepted}" if name in odd else accepted
            raise UsageError(f"{tracker.name}: {name} must be {accepted}, got {_number(value)}")


def _number(value) -> str:
    """Whole numbers in full (up to 20 digits), others as ``%g``."""
    if isinstance(value, int):
        text = str(value)
        return text if len(text) <= 20 else f"a {len(text.lstrip('-'))}-digit number"
    return f"{value:g}"


_REGISTRY: dict[str, type[Tracker]] = {}


def register(cls):
    """Class decorator adding a tracker to the registry under ``cls.name``."""
    if not cls.name or cls.name in _REGISTRY:
        raise ValueError(f"tracker name {cls.name!r} missing or already registered")
    _REGISTRY[cls.name] = cls
    return cls


def tracker_names(*, include_unavailable: bool = False) -> list[str]:
    """Registered tracker names, in registration order (lptrack's own first)."""
    return [name for name, cls in _REGISTRY.items() if include_unavailable or cls.available()]


def tracker_class(name: str):
    """The registered class called ``name``."""
    try:
        return _REGISTRY[name]
    except KeyError:
        # Every registered name, those this install cannot run included: naming one of them then says what to
        # install (create_tracker), rather than that it does not exist.
        names = tracker_names(include_unavailable=True)
        raise UsageError(f"unknown tracker '{name}'{did_you_mean(name, names)}; choose one of: "
                         f"{', '.join(names)}") from None


def _onto_pixels(value: float, size: int) -> float:
    """A coordinate within half a pixel beyond the outermost pixel centres (0 and ``size - 1``) moved onto them;
    any other as it is."""
    if -0.5 <= value < 0.0:
        return 0.0
    if size - 1 < value <= size - 0.5:
        return float(size - 1)
    return value


def did_you_mean(name: str, choices: Iterable[str]) -> str:
    """`` (did you mean 'x'?)`` for the choice nearest a misspelt ``name`` (difflib's ratio at least 0.6), or ''
    if none is near."""
    near = difflib.get_close_matches(name, list(choices), n=1, cutoff=0.6)
    return f" (did you mean '{near[0]}'?)" if near else ""


def check_available(name: str) -> type:
    """The class of tracker ``name``, if it can run in this installation.

    Raises
    ------
    UsageError
        An unknown tracker, or one this installation cannot run (OpenCV's KCF and CSRT without the contrib wheel).
    """
    cls = tracker_class(name)
    if not cls.available():
        raise UsageError(f"tracker '{name}' is not available here: {cls.unavailable_reason()}")
    return cls


def create_tracker(name: str, **params) -> Tracker:
    """A new tracker of the registered kind ``name`` with keyword tuning ``params``.

    Raises
    ------
    UsageError
        An unknown or unavailable tracker, or ``params`` it does not take or accept.
    """
    cls = check_available(name)
    try:  # the parameters' kinds are checked by the construction itself (Tracker.__init_subclass__)
        return cls(**params)
    except LptrackError:
        raise
    except (TypeError, ValueError, OverflowError) as exc:  # an unknown keyword, or a check not in lptrack's terms
        unknown = re.search(r"unexpected keyword argument '(\w+)'", str(exc)) if isinstance(exc, TypeError) else None
        if unknown:  # said as the CLI's --param says it
            key, taken = unknown.group(1), tracker_parameters(name)
            raise UsageError(f"tracker '{name}' has no parameter '{key}'{did_you_mean(key, taken)}; it takes: "
                             f"{', '.join(taken) or 'none'}") from None
        raise UsageError(f"bad parameters for tracker '{name}': {exc}") from None


def tracker_parameters(name: str) -> dict[str, object]:
    """The keyword tuning parameters tracker ``name`` takes, with their defaults, in the order of its signature.

    Read from the keyword-only parameters of the class's ``__init__`` and of the ``__init__`` it hands
    ``**params`` on to (``lpcf-masked`` takes every parameter of ``lpcf``). Each default's type is the type a
    value given as text is converted to (:func:`tracker_params_from_text`).
    """
    found: dict[str, object] = {}
    for klass in inspect.getmro(tracker_class(name)):
        init = klass.__dict__.get("__init__")
        if init is None:
            continue
        passes_on = False
        for parameter in inspect.signature(init).parameters.values():
            if parameter.kind is parameter.VAR_KEYWORD:
                passes_on = True
            elif parameter.kind is parameter.KEYWORD_ONLY and parameter.default is not parameter.empty:
                found.setdefault(parameter.name, parameter.default)
        if not passes_on:
            break
    return found


_TRUE, _FALSE = ("true", "yes", "on", "1"), ("false", "no", "off", "0")


def _check_kind(tracker: str, key: str, value: object, default: object) -> None:
    """Refuse a value from Python that is not of the kind of the parameter's ``default``: a flag takes a bool (not
    the text 'false', which is true), a count a whole number (not 40.9, which was cut to 40), a number a number."""
    kind = type(default)
    if kind is bool:
        fits = isinstance(value, (bool, np.bool_))
    elif kind is int:
        fits = is_whole(value) or (isinstance(value, float) and value.is_integer())
    elif kind is float:
        fits = is_real(value)
    else:
        return
    if not fits:
        what = {bool: "True or False", int: "a whole number", float: "a number"}[kind]
        raise UsageError(f"{tracker}: parameter {key} takes {what} (default {default!r}), got {value!r}")


def _converted(tracker: str, key: str, text: str, default: object) -> object:
    """``text`` as a value of ``default``'s type, or a UsageError saying what the parameter takes."""
    kind = type(default)
    if kind not in (bool, int, float, str):
        raise UsageError(f"{tracker}: parameter {key} cannot be given as text (default {default!r}); set it from "
                         f"Python (create_tracker)")
    try:
        if kind is bool:
            if text.strip().lower() in _TRUE + _FALSE:
                return text.strip().lower() in _TRUE
            raise ValueError
        if kind is int:
            return int(text)
        if kind is float:
            value = float(text)
            if not math.isfinite(value):
                raise ValueError
            return value
    except ValueError:
        what = {bool: "true or false (or yes/no, on/off, 1/0)", int: "a whole number",
                float: "a finite number"}[kind]
        raise UsageError(f"{tracker}: parameter {key} takes {what} (default {default}), got '{text}'") from None
    return text


def tracker_params_from_text(trackers: Iterable[str], assignments: Iterable[tuple[str, str]], *,
                             skipped: Iterable[str] = ()) -> dict[str, dict[str, object]]:
    """Keyword tuning for each of ``trackers`` from ``(name, value text)`` pairs, as ``--param`` gives them.

    Each pair goes to the trackers that take a parameter of that name, its value converted to the type of
    the parameter's default (``true``/``false``, whole numbers, finite numbers, or text); a later pair of the
    same name replaces an earlier one. Each tracker given parameters is made once, which checks their ranges.

    ``skipped`` names trackers asked for that cannot run here: a name only they take is still an error, and
    its message says so.

    Returns
    -------
    dict
        ``{tracker: {parameter: value}}`` for every tracker in ``trackers`` (empty dicts where none applies).

    Raises
    ------
    UsageError
        An unknown or unavailable tracker given parameters, a name no tracker of ``trackers`` takes (the message
        lists the ones they take, with their defaults), a value that does not convert, or one out of range.
    """
    trackers = list(dict.fromkeys(trackers))
    taken = {tracker: tracker_parameters(tracker) for tracker in trackers}
    params: dict[str, dict[str, object]] = {tracker: {} for tracker in trackers}
    for key, text in assignments:
        takers = [tracker for tracker in trackers if key in taken[tracker]]
        if not takers:
            listing = "; ".join(f"{tracker} takes " + (", ".join(f"{k} ({v})" for k, v in taken[tracker].items())
                                                       or "none")
                                for tracker in trackers)
            who = trackers[0] if len(trackers) == 1 else f"any of {', '.join(trackers)}"
            absent = [name for name in skipped if key in tracker_parameters(name)]
            if absent:
                listing += f" ({', '.join(absent)} {'takes' if len(absent) == 1 else 'take'} it but cannot run here)"
            near = did_you_mean(key, {k for tracker in trackers for k in taken[tracker]})
            raise UsageError(f"no parameter '{key}' in {who}{near}: {listing}")
        for tracker in takers:
            params[tracker][key] = _converted(tracker, key, text, taken[tracker][key])
    for tracker, chosen in params.items():
        if chosen:
            create_tracker(tracker, **chosen)  # the tracker checks its ranges (one clear line) now, not per video
    return params
