"""Output files: written under a temporary name and moved into place only when complete."""

import errno
import os

import pytest

from logpolar_track.errors import OutputError
from logpolar_track.outputs import check_output_path, run_in_output_folders, temporary_path, written_into_place


def test_a_finished_output_is_moved_into_place_and_its_temporary_name_is_gone(tmp_path):
    target = tmp_path / "run.csv"
    with written_into_place(target, what="output CSV") as temp:
        assert temp == temporary_path(target) and temp.parent == tmp_path
        temp.write_text("frame\n")
        assert not target.exists()
    assert target.read_text() == "frame\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.csv"]


def test_a_failed_or_stopped_output_leaves_nothing_and_its_error_goes_through(tmp_path):
    target = tmp_path / "run.csv"
    for error in (ValueError("bad row"), KeyboardInterrupt()):
        with pytest.raises(type(error)):
            with written_into_place(target) as temp:
                temp.write_text("half")
                raise error
        assert list(tmp_path.iterdir()) == []


def test_an_os_error_while_writing_is_one_output_error_naming_the_output(tmp_path):
    target = tmp_path / "plot.png"
    with pytest.raises(OutputError) as info:
        with written_into_place(target, what="plot") as temp:
            temp.write_text("half")
            raise OSError(errno.ENOSPC, "No space left on device")
    assert str(info.value) == f"cannot write plot '{target}': No space left on device"
    assert list(tmp_path.iterdir()) == []


def test_a_temporary_that_cannot_even_be_removed_leaves_the_output_error(tmp_path, monkeypatch):
    # In a read-only folder the temporary was never made, and removing it fails too (EROFS, not ENOENT): that
    # OSError replaced the OutputError, and `lptrack samples <read-only folder>` ended in a traceback.
    from pathlib import Path

    target = tmp_path / "spin.mp4"

    def read_only(self, missing_ok=False):
        raise OSError(errno.EROFS, "Read-only file system", str(self))

    monkeypatch.setattr(Path, "unlink", read_only)
    with pytest.raises(OutputError) as info:
        with written_into_place(target, what="sample video"):
            raise OSError(errno.EROFS, "Read-only file system")
    assert str(info.value) == f"cannot write sample video '{target}': Read-only file system"
    with pytest.raises(ValueError, match="bad frame"):  # any other failure goes through as it is
        with written_into_place(target, what="sample video"):
            raise ValueError("bad frame")


def test_a_name_taken_meanwhile_is_kept_unless_overwriting(tmp_path):
    target = tmp_path / "out.json"
    with pytest.raises(OutputError, match="already exists .written while this run went on.; use --overwrite"):
        with written_into_place(target, what="JSON output") as temp:
            temp.write_text("new")
            target.write_text("theirs")  # another run finished first
    assert target.read_text() == "theirs" and sorted(p.name for p in tmp_path.iterdir()) == ["out.json"]
    with written_into_place(target, overwrite=True, what="JSON output") as temp:
        temp.write_text("new")
    assert target.read_text() == "new" and sorted(p.name for p in tmp_path.iterdir()) == ["out.json"]


def test_the_temporary_name_of_a_long_name_fits_the_file_system(tmp_path):
    """A 248-byte name is legal; its temporary name, 13 bytes longer, failed ("File name too long")."""
    for stem in ("v" * 236, "视" * 78):
        target = tmp_path / f"{stem}.lptrack.csv"
        temp = temporary_path(target)
        assert len(temp.name.encode()) <= 255 and temp.name.startswith(".") and temp.name.endswith(".part.csv")
        assert temporary_path(target.with_name("w" + target.name)) != temp  # cut alike, kept apart
        with written_into_place(target) as temp:
            temp.write_text("frame\n")
        assert target.read_text() == "frame\n" and sorted(p.name for p in tmp_path.iterdir()) == [target.name]
        target.unlink()
    assert temporary_path(tmp_path / "run.csv").name == f".run.{os.getpid()}.part.csv"  # short names as before


def test_work_whose_folder_was_removed_meanwhile_is_started_again_in_it(tmp_path):
    folder = tmp_path / "out" / "day1"
    starts = []

    def work():
        starts.append(folder.is_dir())
        if len(starts) == 1:  # a parallel run that failed removes the folders it made, left empty
            folder.rmdir()
        check_output_path(folder / "a.csv", what="output CSV")
        return "done"

    assert run_in_output_folders([folder], work) == "done" and starts == [True, True]
    assert not (tmp_path / "out").exists()  # made here and left empty: removed again


def test_a_failure_with_its_folders_in_place_is_not_started_again(tmp_path):
    starts = []

    def work():
        starts.append(1)
        raise OutputError("cannot write output CSV: No space left on device")

    with pytest.raises(OutputError, match="No space left"):
        run_in_output_folders([tmp_path / "out"], work)
    assert starts == [1] and list(tmp_path.iterdir()) == []
    folder = tmp_path / "kept"

    def removed_each_time():
        starts.append(1)
        folder.rmdir()
        raise OutputError("folder does not exist")

    starts.clear()
    with pytest.raises(OutputError):
        run_in_output_folders([folder], removed_each_time, retry=False, remove_made=False)
    assert starts == [1]


def test_a_folder_made_again_by_a_third_run_before_the_failure_is_seen_is_started_again(tmp_path):
    # Run A failed and removed the folder; run C, starting, made it again before this run looked at its failure.
    folder = tmp_path / "out"
    starts = []

    def work():
        starts.append(1)
        if len(starts) == 1:
            folder.rmdir()
            keep = tmp_path / "keep"  # holds the inode just freed, as a busy file system's other files do
            keep.mkdir()
            try:
                check_output_path(folder / "a.csv", what="output CSV")
            finally:
                folder.mkdir()  # run C
                keep.rmdir()
        return "done"

    assert run_in_output_folders([folder], work, remove_made=False) == "done" and starts == [1, 1]


def test_a_folder_made_again_for_a_start_that_then_fails_is_removed(tmp_path):
    # A batch's video (remove_made=False: the batch removes the folders it made) whose folder, found in place, a
    # run that failed removed; made again here and the start made again failing, it was left behind, empty.
    folder = tmp_path / "out"
    folder.mkdir()
    starts = []

    def work():
        starts.append(1)
        if len(starts) == 1:
            folder.rmdir()
            check_output_path(folder / "a.csv", what="output CSV")
        raise OutputError("cannot write output CSV: No space left on device")

    with pytest.raises(OutputError, match="No space left"):
        run_in_output_folders([folder], work, remove_made=False)
    assert starts == [1, 1] and list(tmp_path.iterdir()) == []
