"""The ``lptrack`` console script and ``python -m logpolar_track``: the CLI, with Ctrl-C handled from the first
instant.

The CLI imports NumPy and OpenCV (about 0.3 s); a Ctrl-C during those imports would end in a KeyboardInterrupt
traceback before the CLI's own handling exists. The package imports them lazily (see ``logpolar_track.__init__``),
so this module can catch that and end as the CLI does on Ctrl-C.
"""

import os
import sys

#: :data:`logpolar_track.cli.EXIT_INTERRUPTED`, repeated: importing it is the heavy import guarded here.
EXIT_INTERRUPTED = 130


def main() -> int:
    """Run ``lptrack``; a Ctrl-C before the CLI can handle it ends with its one line and exit code 130."""
    if sys.stderr is None:
        # Started with stderr closed (``2>&-``): Python has no sys.stderr then. Messages and progress have nowhere
        # to go and are dropped, as ``-q`` would; the work itself goes on.
        sys.stderr = open(os.devnull, "w")
    try:
        from .cli import main as cli_main

        return cli_main()
    except (KeyboardInterrupt, RuntimeError) as exc:
        # Python wraps a Ctrl-C that lands in a class's creation during an import (a dataclass field's
        # __set_name__) in a RuntimeError: that one is a Ctrl-C too.
        if os.environ.get("LPTRACK_DEBUG") or not _from_ctrl_c(exc):
            raise
        sys.stderr.write("lptrack: interrupted\n")
        return EXIT_INTERRUPTED


def _from_ctrl_c(exc: BaseException) -> bool:
    """Whether ``exc`` is a KeyboardInterrupt, or the RuntimeError Python raises from one in a class's creation (a
    RuntimeError raised while merely handling a Ctrl-C, a bug in clean-up, keeps its traceback)."""
    return isinstance(exc, KeyboardInterrupt) or isinstance(exc.__cause__, KeyboardInterrupt)


if __name__ == "__main__":
    sys.exit(main())
