"""The run CSV: exact schema, deterministic formatting, atomic writing."""

from __future__ import annotations

import io
import sys

import pytest

from logpolar_track.errors import OutputError, UsageError
from logpolar_track.geometry import Ellipse
from logpolar_track.results import COLUMNS, CsvWriter, FrameResult, format_row, header_line
from logpolar_track.trackers import TrackState

GOLDEN_HEADER = "frame,time_s,cx,cy,a,b,angle_deg,scale,rotation_deg,score,status\n"


def _result(frame=3, rotation=12.3456, status="tracked", angle=30.0, score=0.87654):
    ellipse = Ellipse(10.12345, 20.98765, 40.0, 20.0, angle)
    return FrameResult(frame, frame / 30.0, TrackState(ellipse, 1.234567, rotation, score), status)


def test_header_is_the_contract():
    assert header_line() == GOLDEN_HEADER
    assert ",".join(COLUMNS) + "\n" == GOLDEN_HEADER


def test_row_has_fixed_decimals():
    row = format_row(_result())
    assert dict(zip(COLUMNS, row)) == {
        "frame": "3", "time_s": "0.100000", "cx": "10.123", "cy": "20.988", "a": "40.000", "b": "20.000",
        "angle_deg": "30.000", "scale": "1.23457", "rotation_deg": "12.346", "score": "0.8765", "status": "tracked"}


def test_no_negative_zero():
    row = dict(zip(COLUMNS, format_row(_result(rotation=-0.0001, angle=-0.0002))))
    assert row["rotation_deg"] == "0.000" and row["angle_deg"] == "0.000"


@pytest.mark.parametrize("angle, text", [(30.0 + 720.0, "30.000"), (180.0, "180.000"), (-180.0, "180.000"),
                                         (-179.9996, "180.000"), (-190.0, "170.000"), (900.0, "180.000")])
def test_angle_is_wrapped_rotation_is_not(angle, text):
    row = dict(zip(COLUMNS, format_row(_result(rotation=angle - 30.0, angle=angle))))
    assert row["angle_deg"] == text
    assert row["rotation_deg"] == f"{angle - 30.0:.3f}"


def test_tracker_without_rotation_writes_empty_rotation_and_initial_angle():
    result = _result(rotation=None, angle=99.0)
    row = dict(zip(COLUMNS, format_row(result, initial_angle_deg=30.0)))
    assert row["rotation_deg"] == "" and row["angle_deg"] == "30.000"


def test_status_is_checked():
    with pytest.raises(ValueError, match="status"):
        _result(status="ok")


def test_csv_file_appears_only_when_closed(tmp_path):
    target = tmp_path / "run.csv"
    writer = CsvWriter(target)
    writer.write(_result(0, status="init"))
    writer.write(_result(1))
    assert not target.exists()
    assert [p.name for p in tmp_path.iterdir()] == [f".run.{__import__('os').getpid()}.part.csv"]
    writer.close()
    assert [p.name for p in tmp_path.iterdir()] == ["run.csv"]
    lines = target.read_text().splitlines(keepends=True)
    assert lines[0] == GOLDEN_HEADER and len(lines) == 3
    assert lines[1].split(",")[0] == "0" and lines[1].rstrip("\n").endswith(",init")


def test_csv_exception_leaves_nothing(tmp_path):
    with pytest.raises(RuntimeError):
        with CsvWriter(tmp_path / "run.csv") as writer:
            writer.write(_result())
            raise RuntimeError("tracker crashed")
    assert list(tmp_path.iterdir()) == []


def test_same_results_same_bytes(tmp_path):
    for name in ("a.csv", "b.csv"):
        with CsvWriter(tmp_path / name) as writer:
            for i in range(5):
                writer.write(_result(i, rotation=i * 7.1))
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()


def test_dash_writes_to_the_stream():
    stream = io.StringIO()
    with CsvWriter("-", stream=stream) as writer:
        writer.write(_result())
    assert writer.target == "-"
    assert stream.getvalue().startswith(GOLDEN_HEADER) and stream.getvalue().count("\n") == 2


def test_no_rotation_tracker_keeps_first_rows_angle(tmp_path):
    stream = io.StringIO()
    with CsvWriter("-", stream=stream) as writer:
        writer.write(_result(0, rotation=None, angle=15.0, status="init"))
        writer.write(_result(1, rotation=None, angle=40.0))
    rows = [line.split(",") for line in stream.getvalue().splitlines()[1:]]
    assert [r[COLUMNS.index("angle_deg")] for r in rows] == ["15.000", "15.000"]
    assert [r[COLUMNS.index("rotation_deg")] for r in rows] == ["", ""]


def test_existing_csv_refused_unless_overwrite(tmp_path):
    target = tmp_path / "run.csv"
    target.write_text("keep me")
    with pytest.raises(OutputError, match=r"'.*run.csv' already exists.*--overwrite"):
        CsvWriter(target)
    assert target.read_text() == "keep me"
    with CsvWriter(target, overwrite=True):
        pass
    assert target.read_text() == GOLDEN_HEADER


@pytest.mark.parametrize("overwrite", [False, True])
def test_a_csv_written_meanwhile_by_another_run_is_kept_unless_overwrite(tmp_path, overwrite):
    # Two runs writing one name at once (xargs -P over two folders' cam.mp4 into one --out-dir) both pass the check
    # at the start; the second to finish must not replace the first's rows without --overwrite.
    target = tmp_path / "run.csv"
    writer = CsvWriter(target, overwrite=overwrite)
    writer.write(_result(0, status="init"))
    target.write_text("the other run's rows")
    if overwrite:
        writer.close()
        assert target.read_text().startswith(GOLDEN_HEADER)
    else:
        with pytest.raises(OutputError, match=r"'.*run.csv' already exists \(written while this run went on\); "
                                              r"use --overwrite"):
            writer.close()
        assert target.read_text() == "the other run's rows"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.csv"]  # no temporary file left


def test_a_dangling_link_at_the_csv_name_is_refused_unless_overwrite(tmp_path):
    target = tmp_path / "run.csv"
    target.symlink_to(tmp_path / "gone.csv")
    with pytest.raises(OutputError, match="already exists"):
        CsvWriter(target)
    assert target.is_symlink()


def test_a_name_ending_in_a_slash_is_a_folder_not_a_file(tmp_path):
    # Path() drops the slash: 'out/' was written as a file named 'out'.
    with pytest.raises(OutputError, match=r"out/': it names a folder; give a file name"):
        CsvWriter(f"{tmp_path}/out/")
    assert list(tmp_path.iterdir()) == []


def test_missing_folder(tmp_path):
    with pytest.raises(OutputError, match="does not exist"):
        CsvWriter(tmp_path / "nowhere" / "run.csv")


@pytest.mark.parametrize("platform, ends_quietly", [("win32", True), ("linux", False)])
def test_a_gone_reader_on_windows_ends_quietly_as_a_broken_pipe(monkeypatch, capsys, platform, ends_quietly):
    """On Windows a write to a pipe whose reader left fails with EINVAL, not BrokenPipeError: it ends lptrack as
    quietly (exit 141), both for rows (``run --csv -``) and for the other commands' stdout; elsewhere EINVAL is an
    error like any other failed write."""
    import errno

    from logpolar_track.cli import EXIT_BROKEN_PIPE, stdout_failures
    from logpolar_track.results import stdout_errors

    monkeypatch.setattr(sys, "platform", platform)
    invalid = OSError(errno.EINVAL, "Invalid argument")
    with pytest.raises(BrokenPipeError if ends_quietly else OutputError):
        with stdout_errors():
            raise invalid
    with pytest.raises(SystemExit if ends_quietly else OutputError) as raised:
        with stdout_failures():
            raise invalid
    if ends_quietly:
        assert raised.value.code == EXIT_BROKEN_PIPE


def test_an_unknown_data_format_is_a_usage_error(tmp_path):
    """It was a bare ValueError, where every other bad argument is an LptrackError the CLI words as one line."""
    with pytest.raises(UsageError, match=r"data_format must be one of \('csv', 'jsonl'\), got 'xml'"):
        CsvWriter(tmp_path / "t.csv", data_format="xml")
    assert list(tmp_path.iterdir()) == []


def test_the_package_exports_every_error_it_raises():
    import logpolar_track
    from logpolar_track import errors
    raised = {name for name, value in vars(errors).items() if isinstance(value, type) and issubclass(value, Exception)}
    assert raised <= set(logpolar_track.__all__) and all(hasattr(logpolar_track, name) for name in raised)
