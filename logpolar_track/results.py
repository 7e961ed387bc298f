"""The per-frame results of a run and the CSV they are written as (the schema is a contract: append-only).

One row per frame, columns :data:`COLUMNS`:

=============  =======================================================================================
frame          frame index in the video file (0 = first frame of the file, not of the run)
time_s         nominal time of the frame in seconds, ``frame / fps``
cx, cy         centre in pixels (x right, y down, origin at the top-left corner of the frame)
a, b           semi-axes of the tracked ellipse in pixels (the initial ROI's times ``scale``)
angle_deg      direction of axis ``a`` in degrees counter-clockwise on screen: the initial ROI's angle plus
               ``rotation_deg``, wrapped into (-180, 180] as in the ``.gt.csv`` sidecars. For trackers that
               do not measure rotation it stays the initial angle.
scale          size relative to the first row (1 in the first row)
rotation_deg   cumulative (unwrapped) counter-clockwise rotation since the first row, in degrees; **empty**
               for trackers that do not measure rotation
score          match confidence in [0, 1]
status         ``init`` (first row), ``tracked`` or ``lost`` (not found: the geometry is the last good one)
=============  =======================================================================================

Numbers have fixed decimals (coordinates and angles 3, scale 5, score 4, time 6), so the same run always
writes the same bytes.

Batches (several videos in one stream) prepend a ``video`` column (:data:`VIDEO_COLUMN`). The same rows can be
written as JSON lines (:data:`FORMATS`): one object per frame with the same keys, numbers as JSON numbers and
empty fields as ``null``.
"""

from __future__ import annotations

import codecs
import contextlib
import csv
import errno
import io
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from .errors import OutputError, UsageError
from .geometry import wrap_degrees
from .trackers.base import TrackState
from .outputs import check_output_path, temporary_path, writes_in_place, written_into_place

#: The run CSV's columns, in order. A contract: never reorder or rename; only append.
COLUMNS: tuple[str, ...] = ("frame", "time_s", "cx", "cy", "a", "b", "angle_deg", "scale", "rotation_deg",
                            "score", "status")

#: Leading column added when several videos share one stream.
VIDEO_COLUMN = "video"

#: Data formats :class:`CsvWriter` writes, and the file extension of each.
FORMATS: dict[str, str] = {"csv": ".csv", "jsonl": ".jsonl"}

#: The values of the ``status`` column.
STATUSES: tuple[str, ...] = ("init", "tracked", "lost")


def off_contract(status: str | None, score: float) -> tuple[str, str] | None:
    """Where a row read back breaks the contract in its ``status`` or ``score``: ``(column, what it must be)``,
    or None. A NaN score is not judged here (a reader decides whether an empty field may stand), nor a ``status``
    of None (another tool's file without one)."""
    if status is not None and status not in STATUSES:
        return "status", f"one of {', '.join(STATUSES)}"
    if not 0.0 <= score <= 1.0 and not math.isnan(score):
        return "score", "in [0, 1]"
    return None


@dataclass(frozen=True)
class FrameResult:
    """What a run found in one frame.

    Attributes
    ----------
    frame : int
        Frame index in the video file (0 = its first frame).
    time_s : float
        Time of the frame in seconds: ``frame / fps``, or for a video whose frame rate varies its timestamp, from
        the first frame where they part (:attr:`VideoReader.timestamps_from
        <logpolar_track.video.VideoReader.timestamps_from>`).
    state : TrackState
        The tracker's state: ellipse (pixels), scale (1 at init), rotation (deg CCW, cumulative, or None),
        score in [0, 1]. For a lost frame, the last good geometry with this frame's score.
    status : str
        ``init``, ``tracked`` or ``lost``.
    """

    frame: int
    time_s: float
    state: TrackState
    status: str

    def __post_init__(self):
        if self.status not in STATUSES:
            raise ValueError(f"status must be one of {STATUSES}, got {self.status!r}")

    @property
    def lost(self) -> bool:
        return self.status == "lost"


def fixed_decimals(value: float | None, decimals: int) -> str:
    """``value`` with fixed ``decimals``; empty for None/NaN/inf; never ``-0.000``."""
    if value is None or not math.isfinite(value):
        return ""
    text = f"{value:.{decimals}f}"
    if text.startswith("-") and float(text) == 0.0:
        text = text[1:]
    return text


def format_row(result: FrameResult, *, initial_angle_deg: float | None = None) -> list[str]:
    """The CSV fields of ``result`` in :data:`COLUMNS` order, as strings.

    Parameters
    ----------
    result : FrameResult
    initial_angle_deg : float, optional
        The initial ROI's angle in degrees. When the tracker does not measure rotation
        (``state.rotation_deg is None``), ``angle_deg`` is written as this value and ``rotation_deg`` empty.
        Without it, ``angle_deg`` comes from the state's ellipse. Either way it is wrapped into (-180, 180].
    """
    state = result.state
    e = state.ellipse
    angle = e.angle_deg
    if state.rotation_deg is None and initial_angle_deg is not None:
        angle = initial_angle_deg
    angle = wrap_degrees(round(angle, 3))  # round first so 180.0004 and -179.9996 both print as 180.000
    return [str(int(result.frame)), fixed_decimals(result.time_s, 6),
            *(fixed_decimals(value, 3) for value in (e.cx, e.cy, e.a, e.b, angle)),
            fixed_decimals(state.scale, 5), fixed_decimals(state.rotation_deg, 3), fixed_decimals(state.score, 4),
            result.status]


def header_line(*, video: bool = False) -> str:
    """The CSV header line, newline included; with a leading ``video`` column if ``video``."""
    return ",".join(((VIDEO_COLUMN,) if video else ()) + COLUMNS) + "\n"


def _csv_field(text: str) -> str:
    """``text`` as one CSV field (quoted only when it holds a comma, quote or line break)."""
    buffer = io.StringIO()
    # The csv module quotes a field holding its line terminator: with none, a line break went out unquoted and split
    # the row (a path with a newline, as `find -print0 | lptrack run -` passes it).
    csv.writer(buffer, lineterminator="\n").writerow([text])
    return buffer.getvalue()[:-1]


def _json_value(column: str, text: str):
    if text == "":
        return None
    if column == "frame":
        return int(text)
    if column in ("status", VIDEO_COLUMN):
        return text
    return float(text)


def json_line(fields: list[str], *, video: str | None = None) -> str:
    """One JSON line (newline included) from a row's fields in :data:`COLUMNS` order.

    Keys are the column names (``video`` first when given); numbers keep the CSV's decimals; empty fields
    become ``null``.
    """
    record = {} if video is None else {VIDEO_COLUMN: video}
    record.update((c, _json_value(c, f)) for c, f in zip(COLUMNS, fields))
    return json.dumps(record, separators=(",", ":")) + "\n"


def decode_text(data: bytes) -> str:
    """``data`` as text: UTF-8 (with or without a byte-order mark), or UTF-16 with a byte-order mark (what Windows
    tools save as "Unicode text", PowerShell 5's ``>`` among them). Run CSVs, ground truth and ROI files are read so.

    Raises
    ------
    UnicodeDecodeError
        Neither, or text holding a NUL: a binary file that happens to decode, or UTF-16 without a byte-order mark
        (a NUL after each ASCII character).
    """
    encoding = "utf-16" if data[:2] in (codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE) else "utf-8-sig"
    text = data.decode(encoding)
    if "\0" in text:
        raise UnicodeDecodeError(encoding, data, 0, 1, "NUL")
    return text


def read_data_rows(path) -> tuple[list[str], list[tuple[int, list[str]]]]:
    """The header and the rows of a run's data file, as :class:`CsvWriter` writes it in either format.

    A CSV file gives its header line and fields as written. A file of JSON lines (its first non-blank character is
    ``{``) gives the first object's keys as the header and each line's values in that order as text: ``null`` or a
    missing key as an empty field, numbers as Python prints them. Blank lines are skipped. ``'-'`` reads stdin.

    Returns
    -------
    header : list of str
        Column names, stripped; empty for an empty file.
    rows : list of (int, list of str)
        The file's line number (1-based) and the fields of each non-blank row after the header.

    Raises
    ------
    OSError, UnicodeDecodeError
        The file cannot be read as UTF-8 text (or UTF-16 with a byte-order mark).
    ValueError
        A JSON line is not an object; the message gives its line number.
    """
    if str(path) == "-":  # a pipe: lptrack run clip.mp4 --csv - | lptrack eval - clip.gt.csv
        if sys.stdin is None:
            raise OSError(errno.EBADF, "stdin is closed")
        data = sys.stdin.buffer.read()
    else:
        with open(path, "rb") as fh:
            data = fh.read()
    text = decode_text(data)
    if not text.lstrip().startswith("{"):
        rows = [(n, r) for n, r in enumerate(csv.reader(io.StringIO(text)), start=1) if any(f.strip() for f in r)]
        if not rows:
            return [], []
        return [h.strip() for h in rows[0][1]], rows[1:]
    header: list[str] = []
    rows = []
    for n, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            record = None
        if not isinstance(record, dict):
            raise ValueError(f"line {n} is not a JSON object")
        if not header:
            header = [str(k).strip() for k in record]
        rows.append((n, ["" if record.get(k) is None else str(record[k]) for k in header]))
    return header, rows


@contextlib.contextmanager
def stdout_errors(what: str | None = "the rows"):
    """Turn a failed write of ``what`` (None: anything) to stdout (a full disk behind it, a character its
    encoding lacks) into an :class:`OutputError`; a closed pipe (``| head``: BrokenPipeError; see
    :func:`reader_left`) passes through as BrokenPipeError for the caller to end quietly."""
    failed = f"cannot write {what} to stdout" if what else "cannot write to stdout"
    try:
        yield
    except BrokenPipeError:
        raise
    except OSError as exc:
        if reader_left(exc):
            raise BrokenPipeError(errno.EPIPE, "Broken pipe") from exc
        raise OutputError(f"{failed}: {exc.strerror or exc}") from None
    except UnicodeEncodeError as exc:  # a path in a batch's 'video' column or eval's table, stdout set to latin-1
        text = exc.object[exc.start:exc.end].encode("ascii", "backslashreplace").decode()
        raise OutputError(f"{failed}: its encoding ({exc.encoding}) has no '{text}'; "
                          f"set PYTHONIOENCODING=utf-8") from None


def reader_left(exc: OSError) -> bool:
    """Whether a failed write to stdout means its reader went away (``| head``): a BrokenPipeError, or on
    Windows the EINVAL a write to a pipe whose reader closed it gives there."""
    return isinstance(exc, BrokenPipeError) or (sys.platform == "win32" and exc.errno == errno.EINVAL)


class CsvWriter:
    """Writes run results as CSV to a file (atomically) or to stdout.

    Parameters
    ----------
    target : str or Path
        ``'-'`` for standard output, otherwise a file path.
    overwrite : bool, optional
        Replace an existing file; otherwise an existing file raises :class:`OutputError`.
    stream : text stream, optional
        Where ``'-'`` writes (default: ``sys.stdout`` at construction time).
    data_format : {'csv', 'jsonl'}
        CSV (default), or JSON lines (:func:`json_line`; no header).
    video : str, optional
        Label written in a leading ``video`` column (key, in JSON lines) of every row, for streams that hold
        several videos.
    header : bool
        Write the CSV header line (default). A batch writing several videos into one stream writes it once.

    Raises
    ------
    OutputError
        If the folder is missing or unwritable, the file exists (without ``overwrite``), or writing fails.

    Notes
    -----
    For a file, rows go to a hidden temporary file in the same folder (``.name.<pid>.part.csv``) that
    :meth:`close` renames to ``target``; :meth:`abort`, or leaving a ``with`` block by an exception, deletes
    it. A device or pipe (``/dev/null``, ``>(gzip > t.csv.gz)``) is written directly. The header is written
    at once. The ``angle_deg`` of trackers that do not measure rotation is the first row's angle (see
    :func:`format_row`).
    """

    def __init__(self, target, *, overwrite: bool = False, stream: IO[str] | None = None,
                 data_format: str = "csv", video: str | None = None, header: bool = True):
        if data_format not in FORMATS:
            raise UsageError(f"data_format must be one of {tuple(FORMATS)}, got {data_format!r}")
        self.data_format = data_format
        self.video = video
        self._prefix = "" if video is None else _csv_field(video) + ","
        self.to_stdout = str(target) == "-"
        self.overwrite = overwrite
        self.path: Path | None = None
        self._temp: Path | None = None
        self._initial_angle: float | None = None
        self.rows = 0
        self._closed = False
        if self.to_stdout:
            self._file = stream if stream is not None else sys.stdout
            if self._file is None:  # started with stdout closed (`>&-`)
                raise OutputError("cannot write the rows to stdout: it is closed")
        else:
            self.path = check_output_path(target, overwrite=overwrite, what="output CSV", special_ok=True)
            # A device or pipe (/dev/null, a named pipe, a process substitution) is written directly.
            self._temp = None if writes_in_place(self.path) else temporary_path(self.path)
            try:
                self._file = open(self._temp or self.path, "w", encoding="utf-8", newline="")
            except OSError as exc:
                raise OutputError(f"cannot write output CSV '{self.path}': {exc.strerror or exc}") from None
            except BaseException:  # a stop signal just as the file was made
                if self._temp is not None:
                    self._temp.unlink(missing_ok=True)
                raise
        try:
            if header and data_format == "csv":
                self._emit(header_line(video=video is not None))
        except BaseException:
            # A failure or a stop signal here would otherwise leave the temporary file: the caller never got
            # the writer to abort (seen once in 40 SIGTERMs sent as the file appeared).
            self.abort()
            raise

    @property
    def target(self) -> str:
        """``'-'`` or the final file path as text."""
        return "-" if self.to_stdout else str(self.path)

    def __enter__(self) -> "CsvWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()

    def _emit(self, text: str) -> None:
        if self.to_stdout:
            with stdout_errors():
                self._file.write(text)
            return
        try:
            self._file.write(text)
        except OSError as exc:
            self.abort()
            raise OutputError(f"cannot write output CSV '{self.path}': {exc.strerror or exc}") from None

    def write(self, result: FrameResult) -> None:
        """Append the row of one frame."""
        if self._closed:
            raise RuntimeError("CsvWriter is closed")
        if self.rows == 0:
            self._initial_angle = result.state.ellipse.angle_deg
        fields = format_row(result, initial_angle_deg=self._initial_angle)
        if self.data_format == "jsonl":
            self._emit(json_line(fields, video=self.video))
        else:
            self._emit(self._prefix + ",".join(fields) + "\n")
        self.rows += 1

    def close(self) -> None:
        """Finish: flush stdout, or close the temporary file and rename it to the target path."""
        if self._closed:
            return
        self._closed = True
        if self.to_stdout:
            with stdout_errors():
                self._file.flush()
            return
        if self._temp is None:  # a device or pipe, written directly
            try:
                self._file.close()
            except OSError as exc:
                raise OutputError(f"cannot write output CSV '{self.path}': {exc.strerror or exc}") from None
            return
        with written_into_place(self.path, overwrite=self.overwrite, what="output CSV", temp=self._temp):
            self._file.close()

    def abort(self) -> None:
        """Stop and delete the temporary file (stdout is only flushed). Safe to call more than once."""
        if self.to_stdout:
            self._closed = True
            try:
                self._file.flush()
            except (OSError, ValueError):
                pass
            return
        self._closed = True
        try:
            self._file.close()
        except OSError:
            pass  # the file is deleted next anyway
        if self._temp is not None:
            self._temp.unlink(missing_ok=True)
