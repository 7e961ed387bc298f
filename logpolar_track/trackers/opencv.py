"""OpenCV's own trackers as peers of lptrack's, behind the same :class:`Tracker` interface.

Registered names:

``cv-mil``
    ``cv2.TrackerMIL`` (Babenko et al., CVPR 2009); ships with opencv-python-headless.
``cv-kcf``
    ``cv2.TrackerKCF`` (Henriques et al., TPAMI 2015); needs opencv-contrib-python-headless.
``cv-csrt``
    ``cv2.TrackerCSRT`` (Lukezic et al., CVPR 2017); needs opencv-contrib-python-headless.

The contrib wheel replaces the plain one (they must not be installed together: uninstall
``opencv-python-headless`` first, then install ``opencv-contrib-python-headless`` of the same version).

OpenCV's trackers follow an axis-aligned box and measure no rotation. The adapters start them on the ROI's
axis-aligned bounding box (rounded to whole pixels, as OpenCV takes integer boxes) and report, per frame, the
ROI's own ellipse (its angle kept) moved by as much as the box's centre moved and scaled by
``scale = sqrt(w*h) / sqrt(w0*h0)`` against the initial box, so the first state is the ROI itself (a centre beyond
the frame's outermost pixel centres is reported on them, as lpcf reports an object leaving the view);
``rotation_deg = None``; and ``score`` 1.0 when OpenCV says ok, else 0.0 (OpenCV gives no confidence). MIL says
ok even when the target is gone; KCF and CSRT can report a loss. ``init`` seeds OpenCV's random number
generator and the C library's ``rand()`` (keyword ``seed``, default 0): MIL draws its samples with the first and its
features with the second, so its runs repeat, within a process as from process to process. (Seeded with OpenCV's
alone, a MIL run depended on how many had run before it in the process, and ended up to 5 px away.) On Linux and
macOS ``rand()`` is one per process, so MIL runs in several threads of a process at once still vary; on Windows
(the UCRT keeps it per thread) the seeding is not verified. A ROI hanging over the frame's edge starts them on its
box cut to the frame.
"""

from __future__ import annotations

import ctypes
import math
import sys

import numpy as np

from ..errors import NotStartedError, RoiError
from ..geometry import Ellipse
from ..images import check_frame, frame_layout, to_bgr
from .base import Tracker, TrackState, check_ranges, check_start, register

_CONTRIB_HINT = ("needs opencv-contrib-python-headless instead of opencv-python-headless "
                 "(swap them: pip uninstall opencv-python-headless && pip install opencv-contrib-python-headless)")
#: Where both wheels are installed (reinstalling lptrack after the swap brings the plain one back), they share
#: the cv2 module, and whichever was installed last wins; uninstalling only the plain one leaves it broken.
_BOTH_WHEELS_HINT = ("both opencv-python-headless and opencv-contrib-python-headless are installed and share the "
                     "cv2 module; reinstall the contrib one alone: pip uninstall -y opencv-python-headless "
                     "opencv-contrib-python-headless && pip install opencv-contrib-python-headless")


def _contrib_hint() -> str:
    """What to do for the contrib trackers, as the installed OpenCV wheels say."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        version("opencv-contrib-python-headless")
        version("opencv-python-headless")
    except PackageNotFoundError:
        return _CONTRIB_HINT
    return _BOTH_WHEELS_HINT


class _OpenCVTracker(Tracker):
    """Shared adapter: subclasses name the ``cv2`` class in ``_cv_class``."""

    measures_rotation = False
    _cv_class = ""
    #: Least side in pixels of the box the OpenCV tracker is started on.
    _min_box_px = 1

    def __init__(self, *, seed: int = 0):
        self.seed = int(seed)
        check_ranges(self, {"seed": (0, 2 ** 31 - 1)})  # cv2.setRNGSeed takes a C int
        self._tracker = None
        self._size0 = 1.0
        self._last: TrackState | None = None
        self._roi: Ellipse | None = None
        self._box0 = (0, 0, 1, 1)

    @classmethod
    def available(cls) -> bool:
        """Whether this OpenCV build has the tracker class."""
        try:
            import cv2
        except ImportError:  # pragma: no cover - cv2 is a dependency
            return False
        return hasattr(cv2, cls._cv_class)

    @classmethod
    def unavailable_reason(cls) -> str:
        """Why the tracker cannot be created here, in one line ('' when it can)."""
        return "" if cls.available() else f"cv2.{cls._cv_class} is not in this OpenCV build; {_contrib_hint()}"

    def _create(self):
        import cv2

        return getattr(cv2, self._cv_class).create()

    def init(self, frame: np.ndarray, roi: Ellipse) -> TrackState:
        frame = np.asarray(frame)
        roi = check_start(frame, roi)
        x, y, w, h = roi.bounding_box()
        # OpenCV takes an integer box; round the corners so the box stays centred on the ROI. A ROI may hang
        # over the frame's edge (half of it inside is enough): the box is cut to the frame, which MIL needs (a box
        # beyond the edge ended it with std::bad_alloc, or an assertion near a corner).
        width, height = frame.shape[1], frame.shape[0]
        x0, y0 = min(max(int(round(x)), 0), width - 1), min(max(int(round(y)), 0), height - 1)
        x1, y1 = min(int(round(x + w)), width), min(int(round(y + h)), height)
        box = (x0, y0, max(x1 - x0, 1), max(y1 - y0, 1))
        if min(box[2], box[3]) < self._min_box_px:
            raise RoiError(f"{self.name} cannot start on a box under {self._min_box_px} px a side (the ROI's is "
                           f"{box[2]}x{box[3]} px): OpenCV's {self._cv_class} may never return on one; give a larger "
                           "ROI or another tracker")
        import cv2

        # Fixed seeds of the random numbers MIL draws (see the module's notes), so that its runs repeat.
        cv2.setRNGSeed(self.seed)
        _seed_c_rand(self.seed)
        # Made aside and kept only once it has started: a refused start leaves the tracker as it was (MIL's object
        # after its failed init crashed the process on the next update).
        tracker = self._create()
        try:
            tracker.init(to_bgr(frame), box)
        except cv2.error as exc:
            # MIL samples its negatives around the box: a box spanning the frame leaves none (an assertion).
            reason = str(exc).strip().splitlines()[-1].strip().rpartition("error: ")[2]
            raise RoiError(f"{self.name} cannot start on the ROI's box ({box[2]}x{box[3]} px at {box[0]},{box[1]}) "
                           f"in a {width}x{height} frame: OpenCV says {reason}; give a smaller ROI, with room "
                           "around it inside the frame") from None
        self._tracker = tracker
        self._frame_size, self._frame_layout = (frame.shape[1], frame.shape[0]), frame_layout(frame)
        self._roi, self._box0 = roi, box
        self._size0 = math.sqrt(box[2] * box[3])
        self._last = TrackState(roi, 1.0, None, 1.0)
        return self._last

    def update(self, frame: np.ndarray) -> tuple[bool, TrackState]:
        if self._tracker is None:
            raise NotStartedError("update() called before init(); start the tracker on a frame and a ROI first")
        frame = np.asarray(frame)
        check_frame(frame, self._frame_size, self._frame_layout)
        import cv2

        try:
            ok, box = self._tracker.update(to_bgr(frame))
        except cv2.error:
            # CSRT's box can leave a frame a few pixels high or wide, and its next crop is then empty (an assertion in
            # copyMakeBorder): not found in this frame.
            ok, box = False, (0, 0, 0, 0)
        box = tuple(float(v) for v in box)
        if not ok or box[2] <= 0 or box[3] <= 0 or not all(math.isfinite(v) for v in box):
            return False, TrackState(self._last.ellipse, self._last.scale, None, 0.0)
        self._last = self._state(box, 1.0)
        return True, self._last

    def _state(self, box, score: float) -> TrackState:
        # Moved by the box's displacement, not centred on the box: the initial box was rounded to whole pixels.
        x, y, w, h = box
        x0, y0, w0, h0 = self._box0
        scale = math.sqrt(w * h) / self._size0
        cx = self._roi.cx + (x + w / 2.0) - (x0 + w0 / 2.0)
        cy = self._roi.cy + (y + h / 2.0) - (y0 + h0 / 2.0)
        # A centre beyond the frame is reported on its edge, as lpcf reports an object leaving the view: KCF's and
        # CSRT's boxes may move part-way out of the frame (a tracked centre 5.5 px beyond the right edge of a 531 px
        # frame), and the centre of a ROI cut by the edge is off its box's by up to half the box.
        width, height = self._frame_size
        cx, cy = min(max(cx, 0.0), width - 1.0), min(max(cy, 0.0), height - 1.0)
        return TrackState(self._roi.moved(cx, cy, scale), scale, None, score)


def _seed_c_rand(seed: int) -> None:
    """Seed the C library's ``rand()``, which OpenCV's MIL draws its features with (``generateRandomFeature``);
    nothing where the library cannot be reached."""
    try:
        library = ctypes.CDLL("ucrtbase") if sys.platform == "win32" else ctypes.CDLL(None)
        library.srand(ctypes.c_uint(seed))
    except (OSError, AttributeError):
        pass


@register
class MILTracker(_OpenCVTracker):
    """OpenCV's MIL tracker (multiple-instance learning; Babenko, Yang, Belongie, CVPR 2009)."""

    name = "cv-mil"
    summary = "OpenCV MIL (peer; box only, no rotation)"
    _cv_class = "TrackerMIL"
    # OpenCV 5.1's MIL loops for ever (at full CPU, deaf to signals inside the native call) on small boxes: on
    # noise, 4x4, 3x5, 3x3, 2x9, 1x20 px never returned; 4x5, 3x6, 20x3 and every box of 5 px a side or more did.
    _min_box_px = 5


@register
class KCFTracker(_OpenCVTracker):
    """OpenCV's KCF tracker (kernelized correlation filters; Henriques et al., TPAMI 2015). Contrib only."""

    name = "cv-kcf"
    summary = "OpenCV KCF (peer, contrib wheel; box only, no rotation)"
    _cv_class = "TrackerKCF"


@register
class CSRTTracker(_OpenCVTracker):
    """OpenCV's CSRT tracker (discriminative correlation filter with channel and spatial reliability;
    Lukezic et al., CVPR 2017). Contrib only."""

    name = "cv-csrt"
    summary = "OpenCV CSRT (peer, contrib wheel; box only, no rotation)"
    _cv_class = "TrackerCSRT"
