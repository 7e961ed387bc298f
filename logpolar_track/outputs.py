"""Output files: checked before any work, written under a temporary name, moved into place when complete.

Every file lptrack writes (CSV, video, PNG, JSON, plots, sample videos) goes through here, so that a run that
fails or is stopped never leaves a file that looks finished, and an existing output is replaced only when asked
(``--overwrite``). Devices, pipes and ``/dev/stdout`` are written directly (:func:`writes_in_place`). Images:
:func:`check_image_suffix` checks an image's file name before any work, :func:`write_png` writes a PNG.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
from pathlib import Path
from typing import Callable, Iterator, TypeVar

import cv2
import numpy as np

from .errors import OutputError, UsageError

#: Bytes in a file name most file systems take (ext4, XFS, APFS, NTFS's 255 UTF-16 units are more).
_NAME_MAX = 255

_Result = TypeVar("_Result")


def temporary_path(path: Path, *, pid: int | None = None) -> Path:
    """A hidden temporary name next to ``path`` that keeps its extension last (so OpenCV picks the container).

    ``out/run.mp4`` -> ``out/.run.<pid>.part.mp4``. The process id (this process's unless ``pid`` is given)
    keeps concurrent runs apart, and lets a parent find what a killed worker left.
    """
    tail = f".{os.getpid() if pid is None else pid}.part{path.suffix}"
    name = f".{path.stem}{tail}"
    if len(os.fsencode(name)) > _NAME_MAX:
        # A name the file system takes (up to 255 bytes) would fail here for its 15 or so bytes more: the stem is cut
        # short, a hash of it kept so that two long names cut alike stay apart.
        digest = hashlib.sha1(os.fsencode(path.name)).hexdigest()[:8]
        room = _NAME_MAX - len(os.fsencode(f".~{digest}{tail}"))
        stem = os.fsencode(path.stem)[:room].decode(errors="ignore")  # not through a multi-byte character
        name = f".{stem}~{digest}{tail}"
    return path.with_name(name)


def check_output_path(path, *, overwrite: bool = False, what: str = "output", special_ok: bool = False,
                      keep_hint: str = "") -> Path:
    """Check that ``path`` can be written; return it as a :class:`Path`.

    ``special_ok`` accepts what :func:`writes_in_place` -- ``/dev/null``, ``/dev/stdout``, a named pipe, a
    process substitution's ``/dev/fd/N`` -- which is then written directly, never replaced. ``keep_hint`` is
    added to the message about an existing file (another way to go on than ``--overwrite``).

    Raises
    ------
    OutputError
        If its folder does not exist, is not a folder or is not writable, if ``path`` is a folder, if ``path``
        exists and ``overwrite`` is False, or if it is written in place and ``special_ok`` is False.
    """
    if str(path).endswith(("/", os.sep)):  # Path() drops the slash: 'out/' would be written as a file 'out'
        raise OutputError(f"cannot write {what} '{path}': it names a folder; give a file name")
    path = Path(path)
    if writes_in_place(path):
        if special_ok:
            return path
        raise OutputError(f"cannot write {what} '{path}': it is a device or stream, not a file; give a file name")
    folder = path.parent
    if not folder.exists():
        raise OutputError(f"cannot write {what} '{path}': folder '{folder}' does not exist")
    if not folder.is_dir():
        raise OutputError(f"cannot write {what} '{path}': '{folder}' is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OutputError(f"cannot write {what} '{path}': folder '{folder}' is not writable")
    if path.is_dir():
        raise OutputError(f"cannot write {what} '{path}': it is a folder")
    if os.path.lexists(path) and not overwrite:  # a dangling link is a name taken too
        raise OutputError(f"{what} '{path}' already exists; use --overwrite to replace it{keep_hint}")
    return path


def move_into_place(temp: Path, path: Path, *, overwrite: bool = False, what: str = "output") -> None:
    """Rename the finished temporary file ``temp`` to ``path`` (same folder).

    With ``overwrite`` an existing ``path`` is replaced. Without it the name is claimed only if still free: another
    run writing the same name at the same time (``xargs -P`` over videos of one name in different folders, both
    with ``--out-dir tracks``) passed :func:`check_output_path` too, and a plain rename would silently replace the
    output of whichever finished first. The file is linked to its name, which fails if the name exists, and the
    temporary name removed; on a file system without hard links the name is checked once more and renamed over.

    Raises
    ------
    OutputError
        If ``path`` exists and ``overwrite`` is False (``temp`` is left for the caller to delete).
    OSError
        If the rename fails otherwise.
    """
    if overwrite:
        os.replace(temp, path)
        return
    taken = OutputError(f"{what} '{path}' already exists (written while this run went on); use --overwrite to "
                        f"replace it")
    try:
        os.link(temp, path)
    except FileExistsError:
        raise taken from None
    except OSError:
        # No hard links here (FAT, exFAT, many network shares, which report it under several error numbers): the
        # name is checked once more and renamed over, so that a finished output is never lost for want of a link.
        if os.path.lexists(path):
            raise taken from None
        os.replace(temp, path)
        return
    with contextlib.suppress(OSError):  # the output is in place; a temporary name left behind is only clutter
        temp.unlink()


def writes_in_place(path) -> bool:
    """Whether output to ``path`` goes straight into it, never through a temporary file renamed over it: a
    device, pipe or socket, or any path under ``/dev`` or ``/proc`` (``/dev/stdout`` and ``/proc/self/fd/1``
    are streams even when they lead to a regular file, and renaming over them would replace the link)."""
    path = Path(path)
    if str(path.absolute()).startswith(("/dev/", "/proc/")):
        return True
    return path.exists() and not path.is_file() and not path.is_dir()


def make_output_folder(folder) -> list[Path]:
    """Create ``folder`` and its missing parents; return the folders created, outermost first.

    Raises
    ------
    OutputError
        If a part of the path is a file, or the folder cannot be created (permissions, read-only file system).
    """
    folder = Path(folder)
    missing = [p for p in [folder, *folder.parents] if not p.exists()][::-1]
    blocking = next((p for p in [folder, *folder.parents] if p.exists() and not p.is_dir()), None)
    if blocking is not None:
        raise OutputError(f"cannot create output folder '{folder}': '{blocking}' is a file, not a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create output folder '{folder}': {exc.strerror or exc}") from None
    return missing


#: How many times :func:`run_in_output_folders` starts its work, making its folders again when another process
#: removed one of them meanwhile.
_FOLDER_ATTEMPTS = 3


def run_in_output_folders(folders, work: Callable[[], _Result], *, retry: bool = True,
                          remove_made: bool = True) -> _Result:
    """Make ``folders`` (:func:`make_output_folder`) and return ``work()``, which writes its outputs into them.

    Parallel runs into one folder (``xargs -P``, several ``lptrack run`` at once) each make it if it is missing,
    and one that fails removes the folder it made if it is empty. If that lands after this process made or found
    the folder and before it opened its outputs there (an output's temporary file, once open, keeps the folder from
    being removed), ``work`` raises :class:`OutputError` with a folder gone, or made again by a third run: the
    folders are made again and ``work`` is started again (``_FOLDER_ATTEMPTS`` times in all). Nothing is written
    by then if every output goes into ``folders`` (they are opened before the first frame is written); rows sent
    to a stream or a file written in place before the video's first frame (``--csv -``, ``/dev/stdout``) would be
    sent again: give ``retry=False`` there. With ``remove_made``, the folders made here are removed again if
    ``work`` leaves them empty (it failed, or wrote nothing there); else whoever runs several works into them does
    that once they are all done, and only those made for a start made again that failed are removed here.
    """
    folders = [Path(folder) for folder in folders]
    attempts = _FOLDER_ATTEMPTS if retry else 1
    made: list[Path] = []
    made_again: list[Path] = []  # on a start made again: the batch's own clean-up does not know them
    done = False
    try:
        for attempt in range(1, attempts + 1):
            for folder in folders:
                (made if attempt == 1 else made_again).extend(make_output_folder(folder))
            found = [_identity(folder) for folder in folders]
            try:
                result = work()
                done = True
                return result
            except OutputError:
                # A folder gone, or made again by a third run before this one looks: either way not the one found.
                if attempt >= attempts or [_identity(folder) for folder in folders] == found:
                    raise
    finally:
        if remove_made:
            remove_empty_folders(made + made_again)
        elif not done:
            remove_empty_folders(made_again)


def _identity(folder: Path) -> tuple[int, int] | None:
    """Which folder ``folder`` is (None if it is missing): a folder removed and made again is another, unless the
    file system gives it the inode just freed. Not its times: a failure's own temporary file changes them, and a
    real error (a full disk) would be started again."""
    try:
        info = os.stat(folder)
    except OSError:
        return None
    return info.st_dev, info.st_ino


def remove_empty_folders(folders) -> None:
    """Remove those of ``folders`` that are empty, innermost first (undoing :func:`make_output_folder`)."""
    for folder in sorted(map(Path, folders), key=lambda p: len(p.parts), reverse=True):
        try:
            folder.rmdir()
        except OSError:  # not empty (another output went there), or already gone
            pass


@contextlib.contextmanager
def written_into_place(path: Path, *, overwrite: bool = False, what: str = "output",
                       temp: Path | None = None) -> Iterator[Path]:
    """Yield a temporary name next to ``path`` to write; when the block ends normally, move it to ``path``.

    ``temp`` (default :func:`temporary_path`) is deleted however the block ends: once moved into place it is
    gone already, and after a failure or a stop signal nothing is left behind. ``what`` names the output in
    messages ("output CSV", "plot").

    Raises
    ------
    OutputError
        If writing or moving fails with an :class:`OSError` ("cannot write output CSV 'x.csv': No space left
        on device"), or ``path`` was taken meanwhile and ``overwrite`` is False (:func:`move_into_place`).
    """
    path = Path(path)
    temp = temporary_path(path) if temp is None else temp
    try:
        yield temp
        move_into_place(temp, path, overwrite=overwrite, what=what)
    except OSError as exc:
        raise OutputError(f"cannot write {what} '{path}': {exc.strerror or exc}") from None
    finally:
        try:
            temp.unlink(missing_ok=True)
        except OSError:  # a read-only folder refuses even the removal of a file it does not hold (EROFS)
            pass


def write_text_atomic(path, text: str, *, overwrite: bool = True, what: str = "JSON output") -> None:
    """Write ``text`` (UTF-8) to ``path`` via a temporary file in the same folder, renamed when complete (over an
    existing file only with ``overwrite``: see :func:`move_into_place`); ``what`` the file is, for messages.

    Raises
    ------
    OutputError
        If the folder does not exist or is not writable, or ``path`` exists and ``overwrite`` is False.
    """
    path = Path(path)
    if writes_in_place(path):  # /dev/stdout, a pipe: no temporary file to rename over it
        try:
            with open(path, "w", encoding="utf-8") as stream:
                stream.write(text)
        except OSError as exc:
            raise OutputError(f"cannot write {what} '{path}': {exc.strerror or exc}") from None
        return
    if not path.parent.is_dir():
        raise OutputError(f"cannot write {what} '{path}': folder '{path.parent}' does not exist")
    with written_into_place(path, overwrite=overwrite, what=what) as temp:
        temp.write_text(text, encoding="utf-8")


def check_image_suffix(path, suffixes: tuple[str, ...], what: str) -> None:
    """Raise :class:`UsageError` unless ``path`` ends in one of ``suffixes`` (checked before any work)."""
    if Path(path).suffix.lower() not in suffixes:
        names = " or ".join(suffixes)
        raise UsageError(f"cannot write {what} '{path}': give a file name ending in {names}")


def write_png(path, image: np.ndarray, *, overwrite: bool = False, what: str = "output image") -> Path:
    """Write ``image`` as PNG atomically (temporary name in the same folder, then rename); return the path.

    Raises
    ------
    UsageError
        ``path`` does not end in .png.
    OutputError
        Folder missing or unwritable, file exists without ``overwrite``, or encoding failed.
    """
    check_image_suffix(path, (".png",), what)
    path = check_output_path(path, overwrite=overwrite, what=what)
    # Encoded in memory and written by Python: a full disk is then one OSError ("No space left on device"),
    # where cv2.imwrite let libpng print its own line first, and any name the file system takes will do.
    ok, encoded = cv2.imencode(".png", image)
    if not ok:
        raise OutputError(f"cannot write {what} '{path}': PNG encoding failed")
    with written_into_place(path, overwrite=overwrite, what=what) as temp:
        temp.write_bytes(encoded.tobytes())
    return path
