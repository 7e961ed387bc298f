"""The ``lptrack`` command line: parses, calls the library, reports.

This package is the only place that prints or exits. Library errors (:class:`LptrackError`) become one line
on stderr and an exit code: 0 success (lost frames are data), 1 runtime failure, 2 bad usage,
130 interrupted (Ctrl-C), 128 + N ended by signal N (143 SIGTERM, 129 SIGHUP), 141 the reader of stdout left
(``| head``). ``LPTRACK_DEBUG=1`` shows the traceback instead.
"""

from __future__ import annotations

import contextlib
import errno
import math
import os
import re
import signal
import sys
import threading

# FFmpeg's own messages ("moov atom not found") and OpenCV's warnings (one per frame when a disk fills up)
# would bury ours. FFmpeg reads its variable when a file is opened; OpenCV has read its own when the package
# imported cv2, so its level is set through the API unless the user chose one (and through the variable
# for worker processes).
os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")
_USER_LOG_LEVEL = "OPENCV_LOG_LEVEL" in os.environ
os.environ.setdefault("OPENCV_LOG_LEVEL", "ERROR")

import click  # noqa: E402

from .. import __version__, cv_compat  # noqa: E402
from ..errors import LptrackError, OutputError, RoiError, UsageError  # noqa: E402
from ..geometry import ROI_SYNTAX, Ellipse, parse_number, parse_roi  # noqa: E402
from ..results import stdout_errors  # noqa: E402
from ..video import keep_frames_off_the_heap  # noqa: E402

EXIT_OK, EXIT_FAILURE, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130
#: Exit code when the reader of stdout went away (128 + SIGPIPE, as a program killed by it).
EXIT_BROKEN_PIPE = 141

#: Signals that stop lptrack as Ctrl-C does (outputs cleaned up, workers stopped): ``timeout``, ``kill``,
#: systemd and ``docker stop`` send SIGTERM, a closing terminal SIGHUP.
STOP_SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))


class Terminated(KeyboardInterrupt):
    """A stop signal, unwinding like Ctrl-C so that every ``except KeyboardInterrupt`` cleanup runs."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


def _ignore(signum, frame):
    pass


def _stop(signum, frame):
    # Further signals are ignored from here on: a second one (two Ctrl-Cs, `kill` then `timeout`) would
    # interrupt the clean-up this one starts and leave temporary files behind.
    # (A handler that does nothing, not SIG_IGN: a signal already pending would then raise "ignored due to
    # race condition".)
    for other in (signal.SIGINT, *STOP_SIGNALS):
        signal.signal(other, _ignore)
    if signum == signal.SIGINT:
        raise KeyboardInterrupt
    raise Terminated(signum)


keep_frames_off_the_heap()  # the CLI owns its process; a library import does not tune malloc
if not _USER_LOG_LEVEL:
    cv_compat.set_log_level(cv_compat.LOG_LEVEL_ERROR)

# Plain `lptrack`: click >= 8.2 raises this UsageError to show the help (exit 2); click 8.1 has no such class and
# shows the help and exits 0 itself (`except ()` catches nothing).
_NO_ARGS_IS_HELP = getattr(click.exceptions, "NoArgsIsHelpError", ())


class LptrackGroup(click.Group):
    """Click group that turns lptrack's exceptions into one line on stderr and an exit code."""

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        # `lptrack --bogus`: parsed before invoke() below, so the one line is written here.
        try:
            with help_to_stdout():
                return super().parse_args(ctx, args)
        except _NO_ARGS_IS_HELP:
            raise  # plain `lptrack` shows the help
        except click.UsageError as exc:
            click.echo(f"lptrack: error: {exc.format_message()} (see 'lptrack --help')", err=True)
            ctx.exit(EXIT_USAGE)
        except OutputError as exc:  # `lptrack --help > /dev/full`: not yet inside invoke() below
            click.echo(f"lptrack: error: {exc}", err=True)
            ctx.exit(exc.exit_code)

    def make_context(self, *args, **kwargs) -> click.Context:
        # A Ctrl-C while the arguments are parsed, before invoke() below handles it: click would say "Aborted!".
        try:
            return super().make_context(*args, **kwargs)
        except KeyboardInterrupt:
            if os.environ.get("LPTRACK_DEBUG"):
                raise
            click.echo("lptrack: interrupted", err=True)
            sys.exit(EXIT_INTERRUPTED)

    def resolve_command(self, ctx: click.Context, args: list[str]):
        try:
            return super().resolve_command(ctx, args)
        except click.UsageError:
            raise UsageError(f"no command '{args[0]}'; the commands are {', '.join(self.list_commands(ctx))} "
                             f"(see 'lptrack --help')") from None

    def invoke(self, ctx: click.Context):
        # Handlers can only be set from the main thread (a test runner may invoke from another).
        main_thread = threading.current_thread() is threading.main_thread()
        previous = {signum: signal.signal(signum, _stop) for signum in (signal.SIGINT, *STOP_SIGNALS)
                    if main_thread and signal.getsignal(signum) is not signal.SIG_IGN}
        try:
            return super().invoke(ctx)
        except LptrackError as exc:
            if os.environ.get("LPTRACK_DEBUG"):
                raise
            click.echo(f"lptrack: error: {exc}", err=True)
            ctx.exit(exc.exit_code)
        except OSError as exc:
            # A path the system refuses before lptrack can judge it: pathlib's is_dir() and exists() raise for a
            # name over the file system's limit, where they return False for a missing file. Other OS errors are
            # caught and reported by the library, naming what failed.
            if exc.errno != errno.ENAMETOOLONG or os.environ.get("LPTRACK_DEBUG"):
                raise
            path = os.fsdecode(exc.filename) if exc.filename is not None else ""
            longest = max(path.split(os.sep), key=lambda part: len(os.fsencode(part)))
            size = len(os.fsencode(longest))
            if size > 255:
                shown = longest if len(longest) <= 60 else f"{longest[:30]}...{longest[-20:]}"
                click.echo(f"lptrack: error: cannot use the name '{shown}': it has {size} bytes; file systems allow "
                           f"at most 255 a name", err=True)
            else:
                click.echo(f"lptrack: error: cannot use '{path[:60]}...': {exc.strerror} "
                           f"({len(os.fsencode(path))} bytes; file systems allow paths of at most 4096)", err=True)
            ctx.exit(EXIT_FAILURE)
        except MemoryError:  # NumPy's allocation failures too; outputs were removed as on any failure
            if os.environ.get("LPTRACK_DEBUG"):
                raise
            click.echo("lptrack: error: out of memory; a smaller video, fewer --jobs or smaller tracker parameters "
                       "need less", err=True)
            ctx.exit(EXIT_FAILURE)
        except Terminated as exc:
            if os.environ.get("LPTRACK_DEBUG"):
                raise
            click.echo(f"lptrack: terminated ({signal.Signals(exc.signum).name})", err=True)
            ctx.exit(128 + exc.signum)
        except KeyboardInterrupt:
            if os.environ.get("LPTRACK_DEBUG"):
                raise
            click.echo("lptrack: interrupted", err=True)
            ctx.exit(EXIT_INTERRUPTED)
        finally:
            for signum, handler in previous.items():
                signal.signal(signum, handler)


@click.group(cls=LptrackGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, "--version", prog_name="lptrack")
def main() -> None:
    """Track a circle or ellipse through a video: centre, scale and rotation per frame.

    \b
    Quick start:
      lptrack run video.mp4 --roi 320,240,40      # circle: cx,cy,r (pixels)
      lptrack run video.mp4 --roi 320,240,60,30,15 # ellipse: cx,cy,a,b,angle (deg, CCW)
    """


class OneLineErrors(click.Command):
    """A command whose argument errors are one ``lptrack: error:`` line (exit 2), not click's usage block."""

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        given = list(args)  # click's parser takes them off the list
        try:
            with help_to_stdout():
                return super().parse_args(ctx, args)
        except click.UsageError as exc:
            message = exc.format_message()
            if isinstance(exc, click.NoSuchOption):
                # `lptrack run -clip.mp4`: a file whose name starts with '-' reads as options ("No such option
                # '-c'"); as for ls or rm, it is named ./-clip.mp4 or after --. The argument the unknown option was
                # read from, not another option's value ('--csv -old.csv').
                named = next((arg for arg in given if arg.startswith(exc.option_name) and os.path.exists(arg)), None)
                if named is not None:
                    message = message.rstrip(".") + f"; for the file '{named}' give ./{named} or -- {named}"
            raise UsageError(f"{message} (see 'lptrack {self.name} --help')") from None


def _to_devnull(stream) -> None:
    """Point ``stream``'s file descriptor at the null device, so that Python's flush of it at exit, which would fail
    again (and print "Exception ignored ..."), succeeds; nothing where it is not a file (a test runner's)."""
    try:
        fd = stream.fileno()
    except (AttributeError, OSError, ValueError):
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)


def echo_progress(line: str) -> None:
    """A progress line on stderr (where it is not a terminal: a batch's videos, a long run's 30 s lines, bench's
    tenths). A reader of stderr that went away (``2>&1 | grep -m1 failed``) ends the lines, not the work: the
    outputs are files, and before these lines such a batch wrote nothing to stderr until its summary."""
    if sys.stderr is None:
        return
    try:
        click.echo(line, err=True)
    except BrokenPipeError:
        _to_devnull(sys.stderr)  # later writes (the summary) and Python's flush at exit go nowhere, as stdout's do


def stdout_reader_left() -> None:
    """The reader of stdout went away (``| head``): stop quietly with :data:`EXIT_BROKEN_PIPE`, as a program
    killed by SIGPIPE would."""
    _to_devnull(sys.stdout)
    sys.exit(EXIT_BROKEN_PIPE)


@contextlib.contextmanager
def stdout_failures():
    """Writes to stdout within: a reader that left ends lptrack quietly (:func:`stdout_reader_left`); any other
    failed write (a full disk behind it, a character the encoding of stdout lacks) is an :class:`OutputError`
    (one line, exit 1), as :func:`~logpolar_track.results.stdout_errors` words it for the rows of a run."""
    try:
        with stdout_errors(None):
            yield
    except BrokenPipeError:
        stdout_reader_left()
    except OutputError:
        _to_devnull(sys.stdout)
        raise


def require_stdout() -> None:
    """A closed stdout (``>&-``) is an :class:`OutputError`, not data lost in silence. Commands whose data goes
    to stdout call this before any work too, so that they do not fail after writing their files."""
    if sys.stdout is None:
        raise OutputError("cannot write to stdout: it is closed")


@contextlib.contextmanager
def help_to_stdout():
    """Parsing the arguments, which may print the help or the version to stdout and exit 0: its failures are
    those of :func:`stdout_failures`, and a closed stdout, where click prints nothing, is an error too."""
    with stdout_failures():
        try:
            yield
        except click.exceptions.Exit as exc:
            if exc.exit_code == 0:
                require_stdout()
            raise


def write_stdout(text: str) -> None:
    """Data on stdout (a table, JSON, written paths), flushed at once so that a failure shows here:
    see :func:`stdout_failures` and :func:`require_stdout`."""
    require_stdout()
    with stdout_failures():
        sys.stdout.write(text)
        sys.stdout.flush()


def parse_roi_option(spec: str) -> Ellipse:
    """``--roi`` text as an :class:`Ellipse`; a malformed one raises a RoiError that shows the syntax."""
    try:
        return parse_roi(spec)
    except RoiError as exc:
        message = str(exc)
        raise RoiError(message if ROI_SYNTAX in message else f"{message}; expected {ROI_SYNTAX}") from None


class FrameRate(click.ParamType):
    """A frame rate as a number or a fraction, as FFmpeg writes NTSC's: ``25``, ``29.97``, ``30000/1001``."""

    name = "rate"

    def convert(self, value, param, ctx):
        if isinstance(value, (int, float)):
            return float(value)
        text = str(value).strip()
        numerator, slash, denominator = text.partition("/")
        try:
            rate = float(numerator) / float(denominator) if slash else float(text)
        except (ValueError, ZeroDivisionError):
            self.fail(f"'{value}' is not a frame rate; give frames per second as a number (25, 29.97) or a "
                      f"fraction (30000/1001)", param, ctx)
        return rate


class TimeParam(click.ParamType):
    """A time in a video: seconds (``83.5``) or, as FFmpeg's ``-ss`` takes it, ``MM:SS`` or ``HH:MM:SS`` with
    decimals (``1:23.5``, ``00:01:23.500``); never negative."""

    name = "time"

    def convert(self, value, param, ctx):
        if isinstance(value, (int, float)):
            seconds = float(value)
        else:
            parts = str(value).strip().split(":")
            numbers = [parse_number(p) for p in parts]
            # Hours and minutes are whole numbers; minutes and seconds after a colon are under 60.
            clock_like = (len(parts) <= 3 and all(p.strip().isdigit() for p in parts[:-1])
                          and all(n is not None and 0 <= n < 60 for n in numbers[1:]))
            if None in numbers or not clock_like:
                self.fail(f"'{value}' is not a time; give seconds (83.5) or HH:MM:SS (00:01:23.5, 1:23.5)", param,
                          ctx)
            seconds = 0.0
            for number in numbers:
                seconds = seconds * 60 + number
        if not (math.isfinite(seconds) and seconds >= 0):
            self.fail(f"'{value}' is not a time; give seconds >= 0 (83.5) or HH:MM:SS (00:01:23.5)", param, ctx)
        return seconds


class PathParam(click.Path):
    """A file or folder name, as :class:`click.Path`, that is never empty: ``Path('')`` is the current folder, so
    ``lptrack run "$VIDEO"`` with an unset variable tracked every video below it."""

    def convert(self, value, param, ctx):
        if isinstance(value, str) and not value:
            self.fail("an empty name was given (an unset shell variable?); give a file or folder name", param, ctx)
        if isinstance(value, str) and _URL.match(value):
            # Read as a path, 'http://host/x.mp4' was reported as "video 'http:/host/x.mp4' not found".
            hint = (f" (a video online: download it first, e.g. ffmpeg -i '{value}' -c copy clip.mp4)"
                    if param is not None and param.param_type_name == "argument" else "")
            self.fail(f"'{value}' is a URL; lptrack reads and writes local files only{hint}", param, ctx)
        return super().convert(value, param, ctx)


#: A URL's scheme (http://, rtsp://, file://): no file name starts so.
_URL = re.compile(r"[A-Za-z][A-Za-z0-9+.-]*://")


class WholeNumber(click.IntRange):
    """A whole number within bounds, as :class:`click.IntRange`, whose message for text that is not one says so
    (click's says "'abc' is not a valid integer range")."""

    def convert(self, value, param, ctx):
        if isinstance(value, str):
            try:
                int(value.strip())
            except ValueError:
                low, high = self.min, self.max
                bounds = (f" from {low} to {high}" if low is not None and high is not None
                          else f" >= {low}" if low is not None else f" <= {high}" if high is not None else "")
                self.fail(f"'{value}' is not a whole number; give one{bounds}", param, ctx)
        return super().convert(value, param, ctx)


def check_jobs_or_scheduler(jobs_given: bool, scheduler: str | None) -> None:
    """``--jobs`` and ``--scheduler`` contradict each other: the cluster's workers, not local processes, run the
    work (``run`` and ``bench`` take one or the other)."""
    if jobs_given and scheduler is not None:
        raise UsageError("--jobs and --scheduler contradict each other: with --scheduler the cluster's workers "
                         "run the work; give one of them")


#: Help of ``--param``, shared by ``lptrack run`` and ``lptrack bench``.
PARAM_HELP = ("Tracker tuning, e.g. --param learning_rate=0.03 (repeatable): goes to the trackers that take NAME; "
              "an unknown NAME gets the list of those they take, with their defaults.")


def parse_param_options(assignments: tuple[str, ...], trackers, skipped=()) -> dict[str, dict]:
    """``--param NAME=VALUE`` texts as ``{tracker: {NAME: value}}`` for ``trackers``
    (:func:`~logpolar_track.trackers.tracker_params_from_text`; ``skipped``: trackers that cannot run here)."""
    from ..trackers import tracker_params_from_text

    pairs = []
    for text in assignments:
        key, sep, value = text.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise UsageError(f"--param takes NAME=VALUE (e.g. --param learning_rate=0.03), got '{text}'")
        pairs.append((key.strip(), value.strip()))
    return tracker_params_from_text(trackers, pairs, skipped=skipped)


# Sub-commands register themselves on `main` when imported; one import line per command module.
# --- command modules ---
from . import run  # noqa: E402,F401
from . import bench  # noqa: E402,F401
from . import samples  # noqa: E402,F401
from . import look  # noqa: E402,F401
