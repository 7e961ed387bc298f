"""The ``lptrack`` command line: parses, calls the library, reports.

This package is the only place that prints or exits. Library errors (:class:`LptrackError`) become one line
on stderr and an exit code: 0 success (lost frames are data), 1 runtime failure, 2 bad usage,
130 interrupted. ``LPTRACK_DEBUG=1`` shows the traceback instead.
"""

from __future__ import annotations

import os

# FFmpeg's own messages ("moov atom not found") would bury ours; must be set before cv2 is imported.
os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")
os.environ.setdefault("OPENCV_LOG_LEVEL", "ERROR")

import click  # noqa: E402

from .. import __version__  # noqa: E402
from ..errors import LptrackError, RoiError, UsageError  # noqa: E402
from ..geometry import ROI_SYNTAX, Ellipse, parse_roi  # noqa: E402
from ..video import keep_frames_off_the_heap  # noqa: E402

EXIT_OK, EXIT_FAILURE, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130


keep_frames_off_the_heap()  # the CLI owns its process; a library import does not tune malloc


class LptrackGroup(click.Group):
    """Click group that turns lptrack's exceptions into one line on stderr and an exit code."""

    def invoke(self, ctx: click.Context):
        try:
            return super().invoke(ctx)
        except LptrackError as exc:
            if os.environ.get("LPTRACK_DEBUG"):
                raise
            click.echo(f"lptrack: error: {exc}", err=True)
            ctx.exit(exc.exit_code)
        except KeyboardInterrupt:
            if os.environ.get("LPTRACK_DEBUG"):
                raise
            click.echo("lptrack: interrupted", err=True)
            ctx.exit(EXIT_INTERRUPTED)


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
        try:
            return super().parse_args(ctx, args)
        except click.UsageError as exc:
            raise UsageError(f"{exc.format_message()} (see 'lptrack {self.name} --help')") from None


def parse_roi_option(spec: str) -> Ellipse:
    """``--roi`` text as an :class:`Ellipse`; a malformed one raises a RoiError that shows the syntax."""
    try:
        return parse_roi(spec)
    except RoiError as exc:
        message = str(exc)
        raise RoiError(message if ROI_SYNTAX in message else f"{message}; expected {ROI_SYNTAX}") from None


# Sub-commands register themselves on `main` when imported; one import line per command module.
# --- command modules ---
from . import run  # noqa: E402,F401
from . import bench  # noqa: E402,F401
from . import samples  # noqa: E402,F401
from . import look  # noqa: E402,F401
