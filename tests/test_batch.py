"""``lptrack run`` over many videos: folders, stdin, ROI files, combined streams, parallel workers, Dask, and
batches cut short by Ctrl-C or a killed worker (only complete outputs left; ``--skip-existing`` finishes)."""

from __future__ import annotations

import csv
import io
import json
import multiprocessing
import operator
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import cv2
import pytest

from conftest import CliRunner, _make_video, damage_middle
from logpolar_track import pipeline
from logpolar_track.batch import (BatchProgress, VideoInput, VideoOutcome, announced_job_frames, data_frame_span,
                                  find_videos, plan_batch, read_roi_file, run_batch)
from logpolar_track.cli import main
from logpolar_track.cli import run as cli_run
from logpolar_track.errors import LptrackError, UsageError
from logpolar_track.executor import DASK_HINT, opencv_threads
from logpolar_track.geometry import Ellipse
from logpolar_track.results import COLUMNS, header_line

LPTRACK = [sys.executable, "-m", "logpolar_track"]


def invoke(*args: str, stdin: str | None = None):
    return CliRunner().invoke(main, ["run", *map(str, args)], input=stdin, catch_exceptions=False)


def csv_rows(path_or_text) -> list[dict]:
    text = Path(path_or_text).read_text() if isinstance(path_or_text, Path) else path_or_text
    return list(csv.DictReader(io.StringIO(text)))


def files_under(folder: Path) -> list[str]:
    """Every file under ``folder`` (hidden temporary ones included), as sorted relative paths."""
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())


@pytest.fixture(scope="module")
def footage(tmp_path_factory) -> Path:
    """footage/day1/{a.mp4 (20 frames), b.mp4 (24)}, footage/day2/{c.avi (16), cut.avi (truncated),
    notes.mp4 (not a video)}, each with a .roi sidecar."""
    root = tmp_path_factory.mktemp("batch") / "footage"
    (root / "day1").mkdir(parents=True)
    (root / "day2").mkdir()
    _make_video(root / "day1", "a.mp4", n_frames=20, seed=1)
    _make_video(root / "day1", "b.mp4", n_frames=24, seed=2)
    _make_video(root / "day2", "c.avi", n_frames=16, seed=3)
    whole = _make_video(root / "day2", "cut.avi", n_frames=30, seed=4).path
    data = whole.read_bytes()
    whole.write_bytes(data[: len(data) // 2])  # MJPG AVI cut in half: FFmpeg reads the frames before the cut
    (root / "day2" / "notes.mp4").write_text("not a video\n")
    (root / "day2" / "notes.roi").write_text("80,60,20\n")
    return root


@pytest.fixture
def work(tmp_path, monkeypatch, footage) -> Path:
    """A fresh current folder holding a copy of ``footage``."""
    shutil.copytree(footage, tmp_path / "footage")
    monkeypatch.chdir(tmp_path)
    return tmp_path


GOOD = {"day1/a": 20, "day1/b": 24, "day2/c": 16}


def test_folder_with_bad_videos_completes_the_good_ones(work):
    result = invoke("footage", "--out-dir", "out", "--no-video", "--jobs", "1")
    assert result.exit_code == 1
    outputs = files_under(work / "out")
    assert outputs == ["day1/a.lptrack.csv", "day1/b.lptrack.csv", "day2/c.lptrack.csv", "day2/cut.lptrack.csv"]
    for name, n in GOOD.items():
        rows = csv_rows(work / "out" / f"{name}.lptrack.csv")
        assert len(rows) == n and rows[0]["status"] == "init"
    cut_rows = len(csv_rows(work / "out" / "day2/cut.lptrack.csv"))
    assert 0 < cut_rows < 30
    err = result.stderr
    assert "lptrack: 5 videos: 4 ok, 1 failed;" in err
    # The video named as given (the batch's paths are absolute), as a single run names it.
    assert "lptrack: failed: footage/day2/notes.mp4: cannot read 'footage/day2/notes.mp4' as a video" in err
    assert f"footage/day2/cut.avi: ended after {cut_rows} of the 30 frames" in err
    assert "Traceback" not in err


class RecordingBar:
    """Stands in for tqdm: keeps what the batch's progress bar was told."""

    made: list["RecordingBar"] = []

    def __init__(self, total=None, unit="it", file=None, **options):
        self.total, self.unit, self.file, self.n, self.steps, self.postfix = total, unit, file, 0, [], None
        RecordingBar.made.append(self)

    def update(self, n=1):
        self.steps.append(n)
        self.n += n

    def set_postfix_str(self, text, refresh=True):
        self.postfix = text

    def refresh(self):
        pass

    def close(self):
        pass


@pytest.fixture
def recorded_bars(monkeypatch) -> list[RecordingBar]:
    """Progress bars of ``lptrack run`` as if stderr were a terminal, recorded instead of drawn."""
    RecordingBar.made = []
    monkeypatch.setattr(cli_run, "_stderr_is_terminal", lambda: True)
    monkeypatch.setattr("tqdm.tqdm", RecordingBar)
    return RecordingBar.made


def _name_not_utf8(folder: Path, name: bytes) -> Path:
    """``folder / name`` for a name of bytes that are not UTF-8 (a Linux file system allows them; Python keeps them
    as surrogate escapes), or a skip where the file system or Python's file name encoding does not."""
    if sys.getfilesystemencoding().lower() not in ("utf-8", "utf8"):
        pytest.skip("file names are not UTF-8 here")
    return Path(os.fsdecode(os.fsencode(str(folder)) + b"/" + name))


def test_a_video_whose_name_is_not_utf8_fails_alone(work):
    """OpenCV crashed (a segmentation fault) on such a name, and with --jobs 1 took the whole batch with it: the
    videos after it were not run and no summary was given. It fails alone, saying why."""
    day1 = work / "footage" / "day1"
    bad = _name_not_utf8(day1, b"caf\xe9.mp4")
    try:
        shutil.copy(day1 / "a.mp4", bad)
        shutil.copy(day1 / "a.roi", bad.with_suffix(".roi"))
    except OSError:
        pytest.skip("the file system refuses names that are not UTF-8")
    result = invoke("footage/day1", "--out-dir", "out", "--no-video", "--jobs", "1")
    assert result.exit_code == 1
    assert files_under(work / "out") == ["a.lptrack.csv", "b.lptrack.csv"]
    assert "its name is not valid UTF-8, which OpenCV cannot open; rename it" in result.stderr
    assert "lptrack: 3 videos: 2 ok, 1 failed;" in result.stderr


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_batch_progress_bar_counts_frames_of_every_video(work, recorded_bars, jobs):
    result = invoke("footage", "--out-dir", "out", "--no-video", "--jobs", jobs)
    assert result.exit_code == 1
    cut_rows = len(csv_rows(work / "out" / "day2/cut.lptrack.csv"))
    [bar] = recorded_bars
    assert bar.unit == "frame" and bar.file.name == "<stderr>"
    # It ends full, in frames (the video that is not one tracked none), never having gone back.
    assert bar.n == bar.total == 20 + 24 + 16 + cut_rows
    assert min(bar.steps) >= 0
    assert bar.postfix == "5/5 videos, 1 failed"


def test_batch_progress_bar_stays_off_under_quiet(work, recorded_bars):
    result = invoke("footage/day1", "--out-dir", "out", "--no-video", "--jobs", "1", "-q")
    assert result.exit_code == 0 and result.stderr == ""
    assert recorded_bars == []


def test_batch_on_a_stderr_that_is_not_a_terminal_says_each_video_as_it_settles(work):
    # A log file or a CI job: no bar (its carriage returns), a line per video instead; skipped ones are counted, not
    # listed (a resumed batch of thousands would list every video done before).
    invoke("footage/day1/a.mp4", "--out-dir", "out/day1", "--no-video")
    result = invoke("footage", "--out-dir", "out", "--no-video", "--jobs", "1", "--skip-existing")
    assert result.exit_code == 1
    cut_rows = len(csv_rows(work / "out" / "day2/cut.lptrack.csv"))
    lines = result.stderr.splitlines()
    assert [line.split()[1] for line in lines[:4]] == ["2/5", "3/5", "4/5", "5/5"]  # the skipped one settled first
    described = sorted(re.sub(r"^lptrack: \d/5 ", "", line) for line in lines[:4])
    assert [re.sub(r" in [0-9.]+ s$", " in T s", line) for line in described] == sorted([
        "footage/day1/b.mp4: 24 frames in T s",
        "footage/day2/c.avi: 16 frames in T s",
        f"footage/day2/cut.avi: {cut_rows} frames in T s",
        "footage/day2/notes.mp4: failed: cannot read 'footage/day2/notes.mp4' as a video: OpenCV cannot decode it "
        "(not a video, a damaged or truncated file, or a format this OpenCV build does not support)"])
    assert lines[4].startswith("lptrack: 5 videos: 3 ok, 1 skipped (outputs exist), 1 failed;")  # then the summary
    quiet = invoke("footage/day1", "--out-dir", "out2", "--no-video", "--jobs", "1", "-q")
    assert quiet.exit_code == 0 and quiet.stderr == ""


def test_a_long_batch_logs_its_frames_where_stderr_is_not_a_terminal(work, monkeypatch):
    monkeypatch.setattr(cli_run, "_LOG_PROGRESS_SECONDS", 0.0)  # a line at every report, as after each 30 s
    result = invoke("footage/day1", "--out-dir", "out", "--no-video", "--jobs", "1")
    assert result.exit_code == 0, result.stderr
    lines = [line for line in result.stderr.splitlines() if " videos done: " in line]
    done = [int(line.split()[4]) for line in lines]
    assert done == sorted(done) and done[-1] == 44 and len(done) > 2
    assert lines[0].startswith("lptrack: 0/2 videos done: ")  # how many videos have settled, beside the frames
    assert re.fullmatch(r"lptrack: 2/2 videos done: 44 of 44 frames \(100 %\), [0-9]+ frames/s", lines[-1]), lines[-1]


def test_a_settled_video_line_says_its_lost_frames():
    line = cli_run._settled_line(VideoOutcome("clip.mp4", "ok", frames=148, lost=2, seconds=0.61))
    assert line == "clip.mp4: 148 frames (2 lost) in 0.6 s"


def test_batch_progress_totals_frames_and_estimates_unknown_counts():
    progress = BatchProgress(3, [VideoOutcome("old.mp4", "skipped", "outputs exist")])
    assert (progress.videos, progress.videos_done, progress.skipped) == (4, 1, 1)
    assert progress.frames_total is None  # no count known yet
    progress.expect(0, 100)
    progress.expect(1, None)  # its container does not say: counted as the mean of the known ones
    assert progress.frames_total == 100 + 100 + 100
    progress.expect(2, 40)
    assert progress.frames_total == 100 + 70 + 40
    progress.advance(0, 30)
    assert progress.frames_done == 30
    progress.finish(0, VideoOutcome("a.mp4", "ok", frames=90))  # ended early: its own count replaces the container's
    assert (progress.frames_done, progress.frames_total) == (90, 90 + 70 + 40)
    progress.advance(1, 25)
    progress.finish(1, VideoOutcome("b.mp4", "failed", "broken"))  # keeps the frames it had: the bar never goes back
    assert (progress.frames_done, progress.frames_total) == (115, 90 + 25 + 40)
    progress.advance(2, 50)  # more frames than its container announced
    assert progress.frames_total == progress.frames_done == 165
    progress.finish(2, VideoOutcome("c.mp4", "ok", frames=50))
    assert (progress.frames_done, progress.frames_total) == (140 + 25, 165)
    assert (progress.ok, progress.failed, progress.skipped, progress.videos_done) == (2, 1, 1, 4)


def test_a_batch_waits_for_its_frame_counting_thread(work, monkeypatch):
    # The thread reading the containers' frame counts was left running when a batch ended; one still inside OpenCV
    # as the interpreter exits aborts the process ('terminate called without an active exception', exit 134 instead
    # of 1): 'lptrack run a.mp4 b.mp4' with both missing, stderr to a log, did so more often than not.
    import threading

    from logpolar_track import batch

    counted = []

    def slow_count(job):
        time.sleep(0.5)  # a container slow to open, while the videos fail at once
        counted.append(job.label)
        return None

    monkeypatch.setattr(batch, "announced_job_frames", slow_count)
    result = invoke("missing1.mp4", "missing2.mp4", "--roi", "10,10,5", "--no-video", "--jobs", "1")
    assert result.exit_code == 1
    assert "lptrack: 2 videos: 0 ok, 2 failed;" in result.stderr
    assert not [t for t in threading.enumerate() if t.name == "lptrack-frame-counts"]
    assert counted  # it was stopped after the container it was reading, not abandoned inside it


def test_announced_job_frames_follow_start_frame_and_frames(work):
    def job(path, **options):
        [one] = plan_batch(find_videos([path]), roi=Ellipse.circle(80, 60, 20), out_dir="out", **options).jobs
        return one

    assert announced_job_frames(job("footage/day1/b.mp4")) == 24
    assert announced_job_frames(job("footage/day1/b.mp4", start_frame=10)) == 14
    assert announced_job_frames(job("footage/day1/b.mp4", start_frame=10, max_frames=5)) == 5
    assert announced_job_frames(job("footage/day1/b.mp4", start_frame=30)) == 0
    assert announced_job_frames(job("footage/day2/notes.mp4")) is None  # not a video: not known
    assert announced_job_frames(job("footage/day2/notes.mp4", max_frames=7)) == 7


def test_failed_video_leaves_no_folder_made_for_it(work):
    (work / "footage" / "day3").mkdir()
    (work / "footage" / "day3" / "bad.mp4").write_text("not a video\n")
    (work / "footage" / "day3" / "bad.roi").write_text("80,60,20\n")
    (work / "out" / "day1").mkdir(parents=True)  # folders that were there stay, even empty
    result = invoke("footage/day3", "footage/day1/a.mp4", "footage/day2/notes.mp4", "--out-dir", "out",
                    "--no-video", "--frames", "7")
    assert result.exit_code == 1
    assert "lptrack: 3 videos: 1 ok, 2 failed;" in result.stderr
    assert files_under(work / "out") == ["day1/a.lptrack.csv"]
    assert sorted(p.name for p in (work / "out").iterdir()) == ["day1"]
    assert len(csv_rows(work / "out" / "day1/a.lptrack.csv")) == 7  # --frames applies to every video


@pytest.mark.parametrize("stream", [False, True])
def test_a_folder_removed_by_a_parallel_run_is_made_again(work, monkeypatch, stream):
    # Another lptrack run into the same folder that failed removes the folder it made if it is empty, which can
    # land between this batch's making it and opening a video's outputs there (xargs -P). The checks are counted
    # in a file: the videos may be tracked in worker processes.
    checks = work / "checks"
    real_check = pipeline.check_outputs

    def check_outputs(*args, **kwargs):
        with open(checks, "a") as count:
            count.write("check\n")
        if len(checks.read_text().splitlines()) == 1:
            (work / "out").rmdir()
        return real_check(*args, **kwargs)

    monkeypatch.setattr(pipeline, "check_outputs", check_outputs)
    result = invoke("footage/day1", "--out-dir", "out", "--jobs", "1", *(["--csv", "-"] if stream else []))
    assert result.exit_code == 0, result.stderr
    assert len(checks.read_text().splitlines()) == 3
    if stream:  # each video's rows once
        videos = [r["video"] for r in csv_rows(result.stdout)]
        assert videos == ["footage/day1/a.mp4"] * 20 + ["footage/day1/b.mp4"] * 24
        assert files_under(work / "out") == ["a.lptrack.mp4", "b.lptrack.mp4"]
    else:
        assert files_under(work / "out") == ["a.lptrack.csv", "a.lptrack.mp4", "b.lptrack.csv", "b.lptrack.mp4"]


def test_one_video_is_counted_in_the_singular(work):
    result = invoke("-", "--no-video", "--out-dir", "out2", stdin="footage/day1/a.mp4\n")
    assert result.exit_code == 0 and "lptrack: 1 video: 1 ok, 0 failed;" in result.stderr


def test_stdin_paths_and_one_combined_csv_stream(work):
    paths = "\n".join(["footage/day1/b.mp4", "", "# a comment", "footage/day1/a.mp4", "footage/missing.mp4"])
    result = invoke("-", "--csv", "-", "--no-video", "--jobs", "1", stdin=paths + "\n")
    assert result.exit_code == 1
    assert result.stdout.count("video,frame,") == 1
    rows = csv_rows(result.stdout)
    assert list(rows[0]) == ["video", *COLUMNS]
    # Rows of each video together, in input order.
    assert [r["video"] for r in rows] == ["footage/day1/b.mp4"] * 24 + ["footage/day1/a.mp4"] * 20
    assert "lptrack: failed: footage/missing.mp4: video" in result.stderr and "not found" in result.stderr
    assert sorted(os.listdir(work)) == ["footage"]  # no files: the data went to stdout


def test_jsonl_stream_holds_the_same_rows(work):
    as_csv = invoke("footage/day1", "--csv", "-", "--no-video", "--jobs", "1")
    as_json = invoke("footage/day1", "--csv", "-", "--no-video", "--jobs", "1", "--format", "jsonl")
    assert as_csv.exit_code == as_json.exit_code == 0
    records = [json.loads(line) for line in as_json.stdout.splitlines()]
    rows = csv_rows(as_csv.stdout)
    assert len(records) == len(rows) == 44
    for record, row in zip(records, rows):
        assert list(record) == ["video", *COLUMNS]
        assert record["video"] == row["video"] and record["status"] == row["status"]
        assert record["frame"] == int(row["frame"]) and record["cx"] == float(row["cx"])


def test_roi_file_on_standard_input(work):
    # `make_rois | lptrack run --roi-file - ...`, as VIDEO '-' and --csv - take '-': it was read as a file named '-'
    # ("cannot read ROI file '-': No such file or directory", exit 1). Its relative paths: from the current folder.
    result = invoke("--roi-file", "-", "--no-video", "--csv", "-", "--jobs", "1", "--frames", "3",
                    stdin='footage/day1/a.mp4,"80,60,20",2\nfootage/day1/b.mp4,80,60,20\n')
    assert result.exit_code == 0, result.stderr
    rows = csv_rows(result.stdout)
    assert [(r["video"], r["frame"]) for r in rows] == [("footage/day1/a.mp4", f) for f in "234"] + [
        ("footage/day1/b.mp4", f) for f in "012"]
    bad = invoke("--roi-file", "-", "--no-video", "--csv", "-", stdin="footage/day1/a.mp4,80,60\n")
    assert bad.exit_code == 2
    assert bad.stderr.startswith("lptrack: error: ROI file (standard input) line 1: expected video,roi")
    both = invoke("-", "--roi-file", "-", "--no-video", "--csv", "-", stdin="footage/day1/a.mp4,80,60,20\n")
    assert both.exit_code == 2
    assert both.stderr == ("lptrack: error: '-' (standard input) can give the videos' paths or the ROI file, not "
                           "both: give the ROI file's path, or list the videos in it and leave VIDEO out\n")
    binary = invoke("--roi-file", "-", "--no-video", "--csv", "-", stdin=b"\xc3\x28\x00\x01")
    assert binary.exit_code == 1
    assert binary.stderr == ("lptrack: error: cannot read the ROI file from standard input: it is not text in UTF-8 "
                             "(nor UTF-16 with a byte-order mark); save it as UTF-8\n")


def test_roi_file_relative_paths_start_frame_and_tracker(work):
    lists = work / "lists"
    lists.mkdir()
    (lists / "rois.csv").write_text(
        "video,roi,start_frame,tracker\n"
        "../footage/day1/a.mp4,\"80,60,20\",0,fixed\n"
        "# b starts later, with the default tracker; its ROI is unquoted\n"
        "../footage/day1/b.mp4,80,60,20,5\n")
    result = invoke("--roi-file", lists / "rois.csv", "--out-dir", "out", "--no-video", "--jobs", "1")
    assert result.exit_code == 0, result.stderr
    assert files_under(work / "out") == ["a.lptrack.csv", "b.lptrack.csv"]
    a_rows, b_rows = csv_rows(work / "out/a.lptrack.csv"), csv_rows(work / "out/b.lptrack.csv")
    assert len(a_rows) == 20 and len(b_rows) == 24 - 5 and b_rows[0]["frame"] == "5"
    # The ROI file wins over the sidecar, and --roi is the fallback for videos it does not list.
    (work / "footage/day1/a.roi").write_text("10,10,5\n")
    result = invoke("footage/day1", "--roi-file", lists / "rois.csv", "--roi", "81,61,20", "--csv", "-",
                    "--no-video", "--jobs", "1")
    firsts = {r["video"]: r for r in csv_rows(result.stdout) if r["status"] == "init"}
    assert firsts["footage/day1/a.mp4"]["cx"] == "80.000"
    assert firsts["footage/day1/b.mp4"]["frame"] == "5"


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_param_reaches_every_video_of_a_batch(work, jobs):
    # With lost_threshold=1 every frame after the first is reported lost (a match never reaches 1). The ROI file
    # gives a.mp4 the thesis tracker, which takes both parameters, and b.mp4 lpcf, which takes no 'window'.
    (work / "rois.csv").write_text("footage/day1/a.mp4,80,60,20,0,fixed\nfootage/day1/b.mp4,80,60,20,0,lpcf\n")
    result = invoke("--roi-file", "rois.csv", "--out-dir", "out", "--no-video", "--jobs", jobs,
                    "--param", "lost_threshold=1", "--param", "window=9")
    assert result.exit_code == 0, result.stderr
    a_rows, b_rows = csv_rows(work / "out/a.lptrack.csv"), csv_rows(work / "out/b.lptrack.csv")
    assert [r["status"] for r in a_rows] == ["init"] + ["lost"] * 19
    assert [r["status"] for r in b_rows] == ["init"] + ["lost"] * 23
    plain = invoke("footage/day1", "--out-dir", "plain", "--no-video", "--jobs", jobs, "--tracker", "fixed")
    assert plain.exit_code == 0 and {r["status"] for r in csv_rows(work / "plain/a.lptrack.csv")[1:]} == \
        {"tracked"}


def test_a_tracker_this_installation_lacks_stops_a_batch_before_any_video(work, monkeypatch):
    # As one video's run refuses it (exit 2, one line); a batch ran every video to fail each with it (a line per
    # video, exit 1), a ROI file's tracker column too.
    from logpolar_track.trackers import tracker_class

    monkeypatch.setattr(tracker_class("fixed"), "available", classmethod(lambda cls: False))
    monkeypatch.setattr(tracker_class("fixed"), "unavailable_reason", classmethod(lambda cls: "not in this build"))
    one = invoke("footage/day1/a.mp4", "--tracker", "fixed", "--no-video", "--out-dir", "out")
    assert (one.exit_code, one.stderr) == (2, "lptrack: error: tracker 'fixed' is not available here: not in this "
                                              "build\n")
    many = invoke("footage/day1", "--tracker", "fixed", "--no-video", "--out-dir", "out", "--jobs", "1")
    assert (many.exit_code, many.stderr) == (one.exit_code, one.stderr)
    (work / "rois.csv").write_text('footage/day1/a.mp4,"80,60,20",,lpcf\nfootage/day1/b.mp4,"80,60,20",,fixed\n')
    listed = invoke("--roi-file", "rois.csv", "--no-video", "--out-dir", "out", "--jobs", "1")
    assert (listed.exit_code, listed.stderr) == (one.exit_code, one.stderr)
    assert not (work / "out").exists()


def test_bad_param_stops_a_batch_before_any_video(work):
    result = invoke("footage/day1", "--out-dir", "out", "--no-video", "--param", "window=9")
    assert result.exit_code == 2 and not (work / "out").exists()
    assert result.stderr.startswith("lptrack: error: no parameter 'window' in lpcf (did you mean 'window_power'?): "
                                    "lpcf takes padding (1.0), ")
    assert len(result.stderr.strip().splitlines()) == 1
    # Checked against the trackers of the videos that run: here the ROI file gives every one the thesis tracker,
    # so an lpcf parameter is used by none (the default tracker, lpcf, tracks nothing) and is refused.
    (work / "rois.csv").write_text("footage/day1/a.mp4,80,60,20,0,fixed\n")
    result = invoke("--roi-file", "rois.csv", "--out-dir", "out", "--no-video", "--param", "learning_rate=0.5")
    assert result.exit_code == 2 and not (work / "out").exists()
    assert result.stderr.startswith("lptrack: error: no parameter 'learning_rate' in fixed: fixed takes window (11)")


def test_tracker_params_in_run_videos_form_are_refused_not_dropped(work):
    """plan_batch takes ``{tracker: {keyword: value}}``; run_video's ``{keyword: value}`` was read as tuning for a
    tracker named 'padding' and dropped in silence."""
    with pytest.raises(UsageError, match=r"tracker_params maps tracker names to their tuning, e\.g\. "
                                         r"\{'lpcf': \{'padding': 1\.5\}\}; got \{'padding': 1\.5\}"):
        plan_batch(find_videos(["footage/day1"]), tracker_params={"padding": 1.5})


def test_video_jobs_stay_hashable_with_tracker_params(work):
    plan = plan_batch(find_videos(["footage/day1"]), roi=Ellipse.circle(80, 60, 20), out_dir="out",
                      tracker_params={"lpcf": {"learning_rate": 0.05}})
    assert len({hash(job) for job in plan.jobs}) == 2
    assert [job.tracker_params for job in plan.jobs] == [{"learning_rate": 0.05}] * 2


def test_roi_file_parsing(tmp_path):
    (tmp_path / "v.mp4").touch()
    text = ("clip.mp4,\"320,240,60,30,15\"\n"
            "/abs/other.mp4,1,2,3,,lpcf\n"
            "third.mp4,1,2,3,4,5,7\n")
    (tmp_path / "r.csv").write_text(text)
    entries = read_roi_file(tmp_path / "r.csv")
    assert [e.video for e in entries] == [tmp_path / "clip.mp4", Path("/abs/other.mp4"), tmp_path / "third.mp4"]
    assert entries[0].roi == Ellipse(320, 240, 60, 30, 15) and entries[0].start_frame is None
    assert entries[1].tracker == "lpcf" and entries[1].roi == Ellipse.circle(1, 2, 3)
    assert entries[2].start_frame == 7 and entries[2].roi == Ellipse(1, 2, 3, 4, 5)
    # A header may follow comments and blank lines, but not an entry.
    (tmp_path / "h.csv").write_text("# made by hand\n\nVideo,roi,start_frame,tracker\n" + text)
    assert read_roi_file(tmp_path / "h.csv") == entries
    for bad, fragment in (("a.mp4,1,2\n", "line 1: expected video,roi"),
                          ("a.mp4,1,2,3\nvideo,roi\n", "line 2: expected video,roi"),
                          ("a.mp4,1,2,3\nb.mp4,1,2,3,x,y\n", "line 2"),
                          ("a.mp4,1,2,3,nosuch\n", ("bad.csv' line 1: in the tracker column, unknown tracker "
                                                    "'nosuch'; choose one of: ")),
                          # Quoted, the ROI is one column: the next one is start_frame, whatever it holds.
                          ("a.mp4,\"1,2,3\",abc\n", ("bad.csv' line 1: the start_frame column holds 'abc'; it "
                                                     "takes a frame index >= 0")),
                          ("a.mp4,\"1,2,3\",0,fixed,x\n", "line 1: expected video,roi"),
                          ("a.mp4,1,2,3\na.mp4,4,5,6\n", "already listed on line 1"),
                          # A spreadsheet's CSV in a locale with decimal commas.
                          ("video;roi\na.mp4;1;2;3\n", "line 1: expected video,roi[,start_frame][,tracker]")):
        (tmp_path / "bad.csv").write_text(bad)
        with pytest.raises(UsageError, match=re.escape(fragment)) as refused:
            read_roi_file(tmp_path / "bad.csv")
        assert ("separated by ';', not commas" in str(refused.value)) == bad.startswith("video;")


def test_a_roi_files_numbers_are_read_by_the_rule_of_parse_roi(tmp_path):
    """Whether the last column is a tracker's name was decided by float(), which takes nan, inf and 1_0 (a start
    frame 'nan' was asked for) and not the typeset minus sign that parse_roi takes (an angle of \u221230 was read
    as a tracker)."""
    roi_file = tmp_path / "r.csv"
    roi_file.write_text("a.mp4,320,240,60,30,\u221230\n")
    assert read_roi_file(roi_file)[0].roi == Ellipse(320, 240, 60, 30, -30)
    for last in ("nan", "inf", "1_0"):
        roi_file.write_text(f"a.mp4,320,240,40,{last}\n")
        with pytest.raises(UsageError, match=re.escape(f"(the last column, '{last}', is not a number (plain decimals "
                                                       f"such as 12, -3.5 or 1e3; no '_', nan or inf), so it is read "
                                                       f"as a tracker's name)")):
            read_roi_file(roi_file)
    roi_file.write_text("a.mp4,320,240,4_0\n")
    with pytest.raises(UsageError, match=re.escape("got 'a.mp4,320,240,4_0' (the last column, '4_0', is not a "
                                                   "number")):
        read_roi_file(roi_file)


def test_bad_roi_file_is_a_usage_error(work):
    (work / "rois.csv").write_text("footage/day1/a.mp4,80,60\n")
    result = invoke("--roi-file", "rois.csv", "--no-video")
    assert result.exit_code == 2
    assert result.stderr.startswith("lptrack: error: ROI file 'rois.csv' line 1: expected video,roi")


def test_roi_file_listing_no_videos_is_a_usage_error_as_empty_stdin_is(work):
    (work / "empty.csv").write_text("")
    (work / "header.csv").write_text("video,roi,start_frame,tracker\n# none yet\n")
    for args, stdin, message in (
            (("--roi-file", "empty.csv"), None, ("no videos found in ROI file 'empty.csv': write one line per "
                                                 "video, video,roi[,start_frame][,tracker]")),
            (("--roi-file", "header.csv"), None, "no videos found in ROI file 'header.csv': "),
            (("-",), "", "no videos found in stdin")):
        result = invoke(*args, "--no-video", stdin=stdin)
        assert result.exit_code == 2, result.stderr
        lines = result.stderr.splitlines()
        assert len(lines) == 1 and lines[0].startswith(f"lptrack: error: {message}"), result.stderr
    assert sorted(os.listdir(work)) == ["empty.csv", "footage", "header.csv"]


@pytest.mark.parametrize("make", ["missing", "folder"])
def test_unreadable_roi_file_is_an_input_failure(work, make):
    # Exit 1 as for any input file that cannot be read (README: errors), not 2.
    if make == "folder":
        (work / "rois.csv").mkdir()
    result = invoke("footage/day1", "--roi-file", "rois.csv", "--no-video")
    assert result.exit_code == 1, result.stderr
    assert result.stderr.startswith("lptrack: error: cannot read ROI file 'rois.csv': ")
    assert len(result.stderr.splitlines()) == 1


def test_find_videos_sorts_and_skips_outputs_and_hidden_files(tmp_path):
    for name in ("b/x.mp4", "a.MOV", "a.txt", ".hidden.mp4", "b/x.lptrack.mp4", ".cache/y.mp4", "b/.x.1.part.mp4"):
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).touch()
    found = find_videos([str(tmp_path), str(tmp_path / "a.MOV"), "-"], stdin=io.StringIO("\n"))
    assert found == [VideoInput(tmp_path / "a.MOV", tmp_path), VideoInput(tmp_path / "b/x.mp4", tmp_path)]


def test_find_videos_reads_find_print0_from_stdin():
    """``find . -print0 | lptrack run -``: paths between NULs, exactly as written (a space, a '#', a newline
    inside a name are its own); it gave a traceback (embedded null byte)."""
    listing = "./a b.mp4\0#c.mp4\0./new\nline.mp4\0"
    found = find_videos(["-"], stdin=io.StringIO(listing))
    assert found == [VideoInput(Path("./a b.mp4")), VideoInput(Path("#c.mp4")), VideoInput(Path("./new\nline.mp4"))]
    # printf '%s\0%s\n' a b: the line end after the last name is not part of it
    found = find_videos(["-"], stdin=io.StringIO("a.mp4\0b.mp4\n"))
    assert found == [VideoInput(Path("a.mp4")), VideoInput(Path("b.mp4"))]


def test_standard_input_closed_or_holding_a_video_is_said_so(monkeypatch):
    """``lptrack run - <&-`` gave a traceback, and ``cat clip.mp4 | lptrack run -`` dozens of notes about file names
    of binary junk: both are one usage error saying what '-' reads."""
    monkeypatch.setattr(sys, "stdin", None)
    with pytest.raises(UsageError, match="standard input, which is closed"):
        find_videos(["-"])
    # A video's bytes as the text layer gives them: not UTF-8 (lone surrogates) and control characters.
    header = "\0\0\0\x20ftypisom\0\0\x02\0isomiso2mp41\0\0\x08\x1e" + "\udcb3\udcf6q\x05" * 200
    with pytest.raises(UsageError, match=r"what it holds is not text \(a video piped in\?\); give the video's path"):
        find_videos(["-"], stdin=io.StringIO(header))
    # As bytes under a locale that decodes strictly (it raised UnicodeDecodeError): the same.
    video = io.TextIOWrapper(io.BytesIO(b"\0\0\0\x20ftypisom" + bytes(range(256)) * 40), errors="strict")
    with pytest.raises(UsageError, match="what it holds is not text"):
        find_videos(["-"], stdin=video)
    names = io.TextIOWrapper(io.BytesIO(b"a.mp4\ncaf\xe9.mp4\r\n"), errors="strict")  # one name not UTF-8
    assert [v.path.name for v in find_videos(["-"], stdin=names)] == ["a.mp4", "caf\udce9.mp4"]
    # A list of paths with one name that is not UTF-8 is still a list of paths.
    listing = "a.mp4\n" * 30 + "caf\udce9.mp4\n"
    assert len(find_videos(["-"], stdin=io.StringIO(listing))) == 2


def test_a_shell_glob_over_an_image_sequence_is_refused_not_tracked_image_by_image(work):
    # 'lptrack run shots/*.png' (the pattern unquoted, or a glob for it): every image became a video of one frame,
    # one CSV of a single row each, exit 0.
    shots = work / "shots"
    shots.mkdir()
    capture = cv2.VideoCapture(str(work / "footage/day1/a.mp4"))
    for number in range(1, 5):
        ok, frame = capture.read()
        assert ok
        cv2.imwrite(str(shots / f"frame_{number:04d}.png"), frame)
    capture.release()
    images = sorted(f"shots/{p.name}" for p in shots.iterdir())
    result = invoke(*images, "--roi", "80,60,20", "--no-video", "--out-dir", "out")
    assert result.exit_code == 2
    assert result.stderr == ("lptrack: error: 'shots/frame_0001.png' and 3 other inputs are still images, each of "
                             "which would be tracked as a video of one frame; give an image sequence as its images' "
                             "pattern, quoted so that the shell leaves it alone, e.g. 'shots/frame_%04d.png'\n")
    assert not (work / "out").exists()
    listed = invoke("-", "--roi", "80,60,20", "--no-video", "--out-dir", "out", stdin="\n".join(images) + "\n")
    assert listed.exit_code == 2 and "are still images" in listed.stderr
    # The pattern itself runs, beside a video too.
    result = invoke("shots/frame_%04d.png", "footage/day1/a.mp4", "--roi", "80,60,20", "--no-video", "--out-dir",
                    "out", "-q")
    assert result.exit_code == 0, result.stderr
    assert len(csv_rows(work / "out/shots/frame.lptrack.csv")) == 4
    # Images among videos (a list from find -type f) do not stop the others, as any input that is no video.
    mixed = invoke(*images[:2], "footage/day1/a.mp4", "--roi", "80,60,20", "--no-video", "--out-dir", "out2", "-q")
    assert mixed.exit_code == 0, mixed.stderr


def test_a_shell_glob_does_not_track_lptracks_own_videos_beside_their_sources(tmp_path):
    """``lptrack run *.mp4`` in a folder already run named clip.lptrack.mp4 too: tracked again, it wrote
    clip.lptrack.lptrack.mp4, one more each run. Named beside its source it is skipped, with a note; alone, or
    beside other videos but not its source, it is tracked."""
    for name in ("clip.mp4", "clip.lptrack.mp4", "other.lptrack.mp4"):
        (tmp_path / name).touch()
    dropped = []
    found = find_videos([str(tmp_path / n) for n in ("clip.lptrack.mp4", "clip.mp4", "other.lptrack.mp4")],
                        on_own_output=lambda out, source: dropped.append((out.name, source.name)))
    assert [v.path.name for v in found] == ["clip.mp4", "other.lptrack.mp4"]
    assert dropped == [("clip.lptrack.mp4", "clip.mp4")]
    assert [v.path.name for v in find_videos([str(tmp_path / "clip.lptrack.mp4")])] == ["clip.lptrack.mp4"]


def test_a_shell_glob_skips_the_annotated_videos_named_after_their_sources_file_name(tmp_path):
    """a.mp4 beside a.avi gives a.mp4.lptrack.mp4 and a.avi.lptrack.mp4: ``*.mp4`` named them and they were tracked
    again (a.mp4.lptrack.lptrack.csv), the second whose source a.avi the glob does not name, but which is beside it."""
    for name in ("a.mp4", "a.avi", "a.mp4.lptrack.mp4", "a.avi.lptrack.mp4", "b.avi.lptrack.mp4"):
        (tmp_path / name).touch()
    dropped = []
    found = find_videos([str(tmp_path / n) for n in ("a.mp4", "a.mp4.lptrack.mp4", "a.avi.lptrack.mp4",
                                                      "b.avi.lptrack.mp4")],
                        on_own_output=lambda out, source: dropped.append((out.name, source.name)))
    assert [v.path.name for v in found] == ["a.mp4", "b.avi.lptrack.mp4"]  # b.avi is nowhere: tracked
    assert dropped == [("a.mp4.lptrack.mp4", "a.mp4"), ("a.avi.lptrack.mp4", "a.avi")]


def test_a_folder_search_says_which_links_it_passes_by(tmp_path):
    """A link to a folder is not followed (as find does not) and a link to nothing is no video: both were passed
    by without a word."""
    (tmp_path / "real").mkdir()
    (tmp_path / "real/a.mp4").touch()
    (tmp_path / "links").mkdir()
    (tmp_path / "links/b.mp4").touch()
    (tmp_path / "links/sub").symlink_to(tmp_path / "real")
    (tmp_path / "links/gone.mp4").symlink_to(tmp_path / "nothing.mp4")
    (tmp_path / "links/notes.txt").symlink_to(tmp_path / "nothing.txt")  # not named as a video: not said
    passed = []
    found = find_videos([str(tmp_path / "links")], on_link_passed=lambda link, folder: passed.append((link.name,
                                                                                                        folder)))
    assert [v.path.name for v in found] == ["b.mp4"]
    assert passed == [("gone.mp4", False), ("sub", True)]
    assert [v.path.name for v in find_videos([str(tmp_path / "links/sub")])] == ["a.mp4"]  # named, it is searched


def test_folders_of_one_name_are_told_apart_by_the_folders_above_them(work):
    """``run d4/day1/cams d4/day2/cams``: both were named 'cams', the second video failed on the first's outputs and
    the first took a name with its extension; each is now mirrored under as many folders as tell them apart."""
    for day in ("day1", "day2"):
        (work / "d4" / day / "cams").mkdir(parents=True)
        shutil.copy(work / "footage/day1/a.mp4", work / "d4" / day / "cams/cam.mp4")
        shutil.copy(work / "footage/day1/a.roi", work / "d4" / day / "cams/cam.roi")
    result = invoke("d4/day1/cams", "d4/day2/cams", "footage/day2", "--out-dir", "out", "--no-video", "--frames", "2")
    assert "2 failed" not in result.stderr
    assert files_under(work / "out") == ["day1/cams/cam.lptrack.csv", "day2/cams/cam.lptrack.csv",
                                         "footage/day2/c.lptrack.csv", "footage/day2/cut.lptrack.csv"]
    one = invoke("d4/day1/cams", "footage/day1", "--out-dir", "one", "--no-video", "--frames", "2")
    assert one.exit_code == 0 and files_under(work / "one") == ["cams/cam.lptrack.csv", "day1/a.lptrack.csv",
                                                                 "day1/b.lptrack.csv"]


def test_outputs_never_collide(work):
    shutil.copy(work / "footage/day2/c.avi", work / "footage/day2/a.avi")
    (work / "footage/day2/a.roi").write_text("80,60,20\n")
    plan = plan_batch(find_videos(["footage/day1/a.mp4", "footage/day2/a.avi", "footage/day1/b.mp4"]),
                      video=True, out_dir="out")
    names = [(j.video_out.relative_to(work / "out"), j.csv_out.relative_to(work / "out")) for j in plan.jobs]
    assert names == [(Path("day1/a.lptrack.mp4"), Path("day1/a.lptrack.csv")),
                     (Path("day2/a.lptrack.mp4"), Path("day2/a.lptrack.csv")),
                     (Path("day1/b.lptrack.mp4"), Path("day1/b.lptrack.csv"))]
    plan = plan_batch([VideoInput(Path("footage/day2/a.avi")), VideoInput(Path("footage/day2/c.avi"))] +
                      [VideoInput(Path("footage/day2/a.mp4"))], out_dir="out")
    assert [j.csv_out.name for j in plan.jobs] == ["a.avi.lptrack.csv", "c.lptrack.csv", "a.mp4.lptrack.csv"]
    # Two folders holding the same relative name: their inputs go under the folders' names, as cp -r would put
    # them (the second failed, as it would overwrite the first's outputs, and the first's names were spoilt).
    (work / "again/day1").mkdir(parents=True)
    shutil.copy(work / "footage/day1/a.mp4", work / "again/day1/a.mp4")
    plan = plan_batch(find_videos(["footage", "again"]), roi=Ellipse.circle(80, 60, 20), out_dir="out")
    assert not plan.settled
    outputs = {j.label: str(j.csv_out.relative_to(work / "out")) for j in plan.jobs}
    assert outputs["footage/day1/a.mp4"] == "footage/day1/a.lptrack.csv"
    assert outputs["footage/day1/b.mp4"] == "footage/day1/b.lptrack.csv"
    assert outputs["again/day1/a.mp4"] == "again/day1/a.lptrack.csv"
    # ... and folders of one name too, under as many folders above them as tell them apart (the second failed, as
    # it would overwrite the first's outputs).
    (work / "more/footage/day1").mkdir(parents=True)
    shutil.copy(work / "footage/day1/a.mp4", work / "more/footage/day1/a.mp4")
    plan = plan_batch(find_videos(["footage", "more/footage"]), roi=Ellipse.circle(80, 60, 20), out_dir="out")
    assert not plan.settled
    outputs = {j.label: str(j.csv_out.relative_to(work / "out")) for j in plan.jobs}
    assert outputs["footage/day1/a.mp4"] == f"{work.name}/footage/day1/a.lptrack.csv"
    assert outputs["more/footage/day1/a.mp4"] == "more/footage/day1/a.lptrack.csv"


def test_parents_names_outputs_alike_however_the_videos_are_split_between_runs(work):
    """Without --parents a run's layout depends on the other videos given with it: split between runs (``xargs
    -n 1``) day1's and day2's cam.mp4 both become out/cam.lptrack.csv. With it, each video's own path decides."""
    shutil.copy(work / "footage/day1/a.mp4", work / "footage/day2/a.mp4")
    (work / "footage/day2/a.roi").write_text("80,60,20\n")
    videos = ["footage/day1/a.mp4", "./footage/day2/a.mp4", "footage/day1/b.mp4"]
    expected = ["footage/day1/a.lptrack.csv", "footage/day1/b.lptrack.csv", "footage/day2/a.lptrack.csv"]
    for out, groups in ("one", [videos]), ("pairs", [videos[:2], videos[2:]]), ("each", [[v] for v in videos]):
        for group in groups:
            result = invoke(*group, "--no-video", "--frames", "3", "--out-dir", out, "--parents", "-q")
            assert result.exit_code == 0, result.output
        assert files_under(work / out) == expected, out
    # Next to the videos without --out-dir; from the filesystem's root for paths going up or absolute.
    assert invoke("footage/day2/a.mp4", "--no-video", "--frames", "3", "--parents", "-q").exit_code == 0
    assert (work / "footage/day2/a.lptrack.csv").is_file()
    from logpolar_track.pipeline import mirrored_path

    assert mirrored_path("../x/clip.mp4") == Path(os.path.abspath("../x/clip.mp4")).relative_to("/")
    assert mirrored_path("./footage/day1/../day2/a.mp4") == Path("footage/day2/a.mp4")  # lexically, as cp
    assert mirrored_path(work / "footage/day1/a.mp4") == (work / "footage/day1/a.mp4").relative_to("/")
    plan = plan_batch(find_videos([str(work / "footage/day1/a.mp4"), "footage/day1/b.mp4"]), out_dir="out",
                      parents=True)
    assert [j.csv_out.relative_to(work / "out") for j in plan.jobs] == [
        (work / "footage/day1/a.lptrack.csv").relative_to("/"), Path("footage/day1/b.lptrack.csv")]
    # Two videos of one stem side by side keep their extensions, given together or apart: the folder decides.
    shutil.copy(work / "footage/day2/c.avi", work / "footage/day2/a.avi")
    for out, groups in ("twins", [["footage/day2/a.mp4", "footage/day2/a.avi"]]), \
                       ("twins apart", [["footage/day2/a.mp4"], ["footage/day2/a.avi"]]):
        for group in groups:
            result = invoke(*group, "--no-video", "--frames", "3", "--out-dir", out, "--parents", "-q")
            assert result.exit_code == 0, result.output
        assert files_under(work / out) == ["footage/day2/a.avi.lptrack.csv", "footage/day2/a.mp4.lptrack.csv"]
    # Where lptrack names no output, --parents has nothing to do: said, as for --out-dir.
    for args in (("footage/day2/c.avi", "--csv", "-", "--no-video"), ("footage/day1", "--csv", "-", "--no-video")):
        result = CliRunner().invoke(main, ["run", *args, "--parents"])
        assert result.exit_code == 2
        assert "--parents would name nothing: it names the outputs lptrack names, and --csv - and --no-video leave " \
               "it none; drop --parents" in result.stderr


@pytest.mark.parametrize("args, fragment", [
    (("footage/day1", "--out", "x.mp4"), "--out names one video's output"),
    (("footage/day1", "--csv", "all.csv"), "--csv names one video's output in this process; with a folder give"),
    (("footage/day1/a.mp4", "footage/day1/b.mp4", "--csv", "all.csv"), "; with several videos give --out-dir"),
    (("--roi-file", "one.csv", "--csv", "o.csv"), "--csv names one video's output in this process; with --roi-file"),
    # The ROI file's own error comes first.
    (("--roi-file", "bad.csv", "--csv", "o.csv"), "ROI file 'bad.csv'"),
    (("footage/day1", "--csv", "-", "--skip-existing"), "--skip-existing needs outputs in files"),
    (("footage/day1", "--overwrite", "--skip-existing"), "contradict each other"),
    ((), "give a VIDEO"),
    (("footage/day1", "--jobs", "0"), "--jobs"),
])
def test_bad_batch_arguments(work, args, fragment):
    (work / "one.csv").write_text("footage/day1/a.mp4,80,60,20\n")
    (work / "bad.csv").write_text("footage/day1/a.mp4;80;60;20\n")
    result = invoke(*args)
    assert result.exit_code == 2
    assert result.stderr.startswith("lptrack: error:") and fragment in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_folder_without_videos_is_a_usage_error(work):
    # A folder given as the video is a folder of videos: with none in it, nothing can run (exit 2, as README).
    (work / "empty").mkdir()
    (work / "rois.csv").write_text("footage/day1/a.mp4,80,60,20\n")
    for args in (("empty",), ("empty", "--roi-file", "rois.csv")):
        result = invoke(*args, "--roi", "80,60,20")
        assert result.exit_code == 2
        assert result.stderr == ("lptrack: error: no videos found in 'empty' (folders are searched for .mp4, "
                                 ".m4v, .mov, .avi, .mkv, ... files)\n")


def _links(folder: Path, target: Path, names) -> None:
    folder.mkdir()
    for name in names:
        try:
            (folder / name).symlink_to(target)
        except (OSError, NotImplementedError):
            pytest.skip("cannot make symbolic links here")


def test_links_to_one_video_are_videos_of_their_own(work):
    _links(work / "links", work / "footage/day1/a.mp4", ["l1.mp4", "l2.mp4", "l3.mp4"])
    result = invoke("links", "--roi", "80,60,20", "--out-dir", "out", "--no-video", "--jobs", "1")
    assert result.exit_code == 0, result.stderr
    assert "lptrack: 3 videos: 3 ok, 0 failed;" in result.stderr
    assert files_under(work / "out") == ["l1.lptrack.csv", "l2.lptrack.csv", "l3.lptrack.csv"]
    # Named directly too, each link keeps its own name (not its target's).
    result = invoke("links/l1.mp4", "links/l2.mp4", "--roi", "80,60,20", "--csv", "-", "--no-video", "--jobs", "1")
    assert result.exit_code == 0, result.stderr
    assert [r["video"] for r in csv_rows(result.stdout) if r["status"] == "init"] == ["links/l1.mp4", "links/l2.mp4"]


def test_the_same_video_named_twice_runs_once_and_says_so(work):
    result = invoke("footage/day1", "footage/day1/a.mp4", "./footage/day1/b.mp4", "--out-dir", "out", "--no-video",
                    "--jobs", "1")
    assert result.exit_code == 0, result.stderr
    assert "lptrack: 2 videos: 2 ok, 0 failed;" in result.stderr
    notes = [line for line in result.stderr.splitlines() if "named more than once" in line]
    assert notes == ["lptrack: note: 'footage/day1/a.mp4' is named more than once; tracked once",
                     "lptrack: note: 'footage/day1/b.mp4' is named more than once; tracked once"]
    assert files_under(work / "out") == ["a.lptrack.csv", "b.lptrack.csv"]


def test_video_without_roi_and_roi_outside_frame_fail_alone(work):
    (work / "footage/day1/a.roi").unlink()
    (work / "footage/day1/b.roi").write_text("500,500,20\n")
    (work / "footage/day2").rename(work / "elsewhere")
    result = invoke("footage", "--no-video", "--out-dir", "out", "--jobs", "1")
    assert result.exit_code == 1
    assert "footage/day1/a.mp4: no ROI given" in result.stderr
    assert "footage/day1/b.mp4: ROI centre" in result.stderr or "footage/day1/b.mp4: " in result.stderr
    # No rates where nothing was tracked (a batch failing at once once claimed thousands of videos/s).
    assert re.search(r"2 videos: 0 ok, 2 failed; 0 frames in \d+\.\d s\n", result.stderr)
    assert not (work / "out").exists() or files_under(work / "out") == []


def test_jobs_2_writes_the_same_bytes_as_jobs_1(work):
    one = invoke("footage/day1", "footage/day2/c.avi", "--out-dir", "one", "--jobs", "1")
    two = invoke("footage/day1", "footage/day2/c.avi", "--out-dir", "two", "--jobs", "2")
    assert one.exit_code == two.exit_code == 0, two.stderr
    # Videos found in a folder mirror their path below it; files named directly go to the top.
    assert files_under(work / "one") == files_under(work / "two") == [
        "a.lptrack.csv", "a.lptrack.mp4", "b.lptrack.csv", "b.lptrack.mp4", "c.lptrack.csv", "c.lptrack.mp4"]
    for name in files_under(work / "one"):
        if name.endswith(".csv"):
            assert (work / "one" / name).read_bytes() == (work / "two" / name).read_bytes(), name


def test_dask_local_cluster_gives_the_same_csvs(work):
    distributed = pytest.importorskip("dask.distributed")
    local = invoke("footage/day1", "--out-dir", "local", "--no-video", "--jobs", "1")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, protocol="tcp",
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        on_dask = invoke("footage/day1", "--out-dir", "dask", "--no-video", "--scheduler",
                         cluster.scheduler_address)
        with distributed.Client(cluster) as client:  # the library takes a connected client too
            plan = plan_batch(find_videos(["footage/day2"]), out_dir="api", video=False)
            seen = []
            summary = run_batch(plan, scheduler=client, on_progress=lambda p: seen.append(
                (p.frames_done, p.frames_total, p.videos_done)))
    assert local.exit_code == on_dask.exit_code == 0, on_dask.stderr
    for name in ("a.lptrack.csv", "b.lptrack.csv"):
        assert (work / "local" / name).read_bytes() == (work / "dask" / name).read_bytes()
    assert [o.status for o in summary.outcomes] == ["ok", "ok", "failed"]
    # Dask workers report no frames while they run: the progress moves a finished video at a time.
    assert seen[-1] == (summary.frames, summary.frames, 3)


def _double(item, report):
    return 2 * item


def test_a_dask_cluster_without_workers_is_said_to_wait_for_one():
    # The tasks waited in silence for a worker: lptrack looked hung.
    distributed = pytest.importorskip("dask.distributed")
    from logpolar_track.executor import run_tasks

    with distributed.LocalCluster(n_workers=0, processes=False, protocol="tcp", host="127.0.0.1",
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        notes, results = [], []
        waiting = threading.Thread(target=lambda: results.extend(
            run_tasks(_double, [21], scheduler=client, on_note=notes.append)))
        waiting.start()
        for _ in range(200):  # the note comes before the task is submitted
            if notes:
                break
            time.sleep(0.05)
        assert notes == [f"the Dask scheduler '{cluster.scheduler_address}' has no workers yet; nothing runs until "
                         "one connects (Ctrl-C to stop)"]
        assert results == []
        cluster.scale(1)
        waiting.join(60)
        assert [(r.index, r.value) for r in results] == [(0, 42)]
        notes.clear()
        assert [r.value for r in run_tasks(_double, [1], scheduler=client, on_note=notes.append)] == [2]
        assert notes == []  # a worker is there now


def test_malformed_scheduler_address_is_one_line_and_ends_at_once(work):
    # In a process of its own: the 30 s hang was in a half-made Dask Client's __del__ at interpreter exit.
    pytest.importorskip("dask.distributed")
    proc = subprocess.run([*LPTRACK, "run", "footage/day1/a.mp4", "--roi", "80,60,20", "--no-video",
                           "--scheduler", "nonsense"], capture_output=True, text=True, timeout=20)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr == ("lptrack: error: --scheduler 'nonsense' is not a Dask scheduler address (missing port "
                           "number in address 'nonsense'); give one like tcp://10.0.0.5:8786\n")


def test_a_scheduler_address_that_is_not_a_dask_scheduler_is_one_line(work, monkeypatch):
    """Nothing listening there is said at once (Dask retried for its whole timeout, 15 s); something listening
    that never answers as Dask does (an HTTP server) is given up on (Dask waited for its handshake for ever, and
    Ctrl-C then took 30 s and printed a traceback); a tls:// address without Dask's TLS settings is one line (it
    was a traceback of Dask's TypeError)."""
    pytest.importorskip("dask.distributed")
    from logpolar_track import executor

    silent = socket.socket()
    silent.bind(("127.0.0.1", 0))
    silent.listen()  # accepts connections (the kernel's backlog) and never says a word
    closed = socket.socket()
    closed.bind(("127.0.0.1", 0))
    refused = closed.getsockname()[1]
    closed.close()
    monkeypatch.setattr(executor, "SCHEDULER_ANSWER_S", 0.5)
    try:
        cases = {f"tcp://127.0.0.1:{refused}": "cannot reach the Dask scheduler",
                 f"tcp://127.0.0.1:{silent.getsockname()[1]}": "did not answer within 0.75 s (is it a Dask "
                                                               "scheduler's address?)",
                 "tls://127.0.0.1:8786": "the Dask scheduler 'tls://127.0.0.1:8786'"}
        for address, fragment in cases.items():
            result = invoke("footage/day1", "--no-video", "--out-dir", "out", "--scheduler", address)
            assert result.exit_code == 1, (address, result.stderr)
            lines = result.stderr.splitlines()
            assert len(lines) == 1 and lines[0].startswith("lptrack: error: ") and fragment in lines[0], lines
        # Rows to stdout: not even the header goes out before the cluster is reached.
        result = invoke("footage/day1", "--no-video", "--csv", "-", "--scheduler", f"tcp://127.0.0.1:{refused}")
        assert result.exit_code == 1 and result.stdout == ""
    finally:
        silent.close()
    assert not (work / "out").exists()


def test_an_interrupted_dask_batch_says_that_started_videos_go_on(work, monkeypatch):
    # lptrack cannot stop Dask's workers; "lptrack: interrupted" alone left their outputs appearing afterwards unsaid.
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli_run, "run_batch", interrupted)
    result = invoke("footage/day1", "--no-video", "--scheduler", "tcp://127.0.0.1:8786")
    assert result.exit_code == 130
    assert result.stderr.splitlines() == [
        "lptrack: note: videos a Dask worker had started go on there and leave their outputs when done (wait for "
        "them before a --skip-existing rerun); the others were cancelled", "lptrack: interrupted"]
    local = invoke("footage/day1", "--no-video", "--jobs", "2")
    assert (local.exit_code, local.stderr) == (130, "lptrack: interrupted\n")


def test_scheduler_without_dask_gives_a_hint(work, monkeypatch):
    monkeypatch.setitem(sys.modules, "dask.distributed", None)  # import fails as if the extra were missing
    result = invoke("footage/day1", "--no-video", "--scheduler", "tcp://127.0.0.1:8786")
    assert result.exit_code == 2
    assert result.stderr == f"lptrack: error: {DASK_HINT}\n"


def _stamp(path: Path) -> tuple[int, int]:
    """What tells a file rewritten: its inode (outputs are renamed into place) and its modification time."""
    status = path.stat()
    return status.st_ino, status.st_mtime_ns


def test_skip_existing_resumes(work):
    first = invoke("footage/day1", "--out-dir", "out", "--no-video", "--jobs", "1")
    assert first.exit_code == 0
    (work / "out/b.lptrack.csv").unlink()
    stamp = _stamp(work / "out/a.lptrack.csv")
    again = invoke("footage/day1", "--out-dir", "out", "--no-video", "--jobs", "1", "--skip-existing")
    assert again.exit_code == 0
    assert "2 videos: 1 ok, 1 skipped (outputs exist), 0 failed" in again.stderr
    assert _stamp(work / "out/a.lptrack.csv") == stamp
    assert len(csv_rows(work / "out/b.lptrack.csv")) == 24
    # Partial sets of outputs (here: a's video without its CSV, b's CSV without its video) are redone whole.
    (work / "out/a.lptrack.csv").unlink()
    (work / "out/a.lptrack.mp4").write_bytes(b"earlier")
    redone = invoke("footage/day1", "--out-dir", "out", "--jobs", "1", "--skip-existing")
    assert redone.exit_code == 0 and "2 ok" in redone.stderr
    assert (work / "out/a.lptrack.mp4").read_bytes() != b"earlier"
    refused = invoke("footage/day1", "--out-dir", "out", "--no-video", "--jobs", "1")
    assert refused.exit_code == 1
    # Named from the current folder, as a single run names it (the batch's paths are absolute).
    assert ("failed: footage/day1/a.mp4: output CSV 'out/a.lptrack.csv' already exists; use --overwrite"
            in refused.stderr)


def test_skip_existing_redoes_the_videos_whose_roi_changed(work):
    """A ROI corrected in the sidecar (or the ROI file) since the run: that video is tracked again, the others
    are left alone."""
    assert invoke("footage/day1", "--out-dir", "out", "--no-video", "--jobs", "1").exit_code == 0
    stamp = _stamp(work / "out/a.lptrack.csv")
    (work / "footage/day1/b.roi").write_text("82,60,20\n")
    again = invoke("footage/day1", "--out-dir", "out", "--no-video", "--jobs", "1", "--skip-existing")
    assert again.exit_code == 0 and "2 videos: 1 ok, 1 skipped (outputs exist), 0 failed" in again.stderr
    assert _stamp(work / "out/a.lptrack.csv") == stamp
    assert csv_rows(work / "out/b.lptrack.csv")[0]["cx"] == "82.000"
    (work / "rois.csv").write_text("footage/day1/a.mp4,80,60,20\nfootage/day1/b.mp4,82,61,20\n")
    from_file = invoke("--roi-file", "rois.csv", "--out-dir", "out", "--no-video", "--jobs", "1",
                       "--skip-existing")
    assert from_file.exit_code == 0 and "2 videos: 1 ok, 1 skipped (outputs exist), 0 failed" in from_file.stderr
    assert csv_rows(work / "out/b.lptrack.csv")[0]["cy"] == "61.000"


def test_skip_existing_redoes_a_trial_run_over_fewer_frames(work):
    """Outputs of ``--frames 5`` (or another start frame) are complete files, but not this run's results."""
    trial = invoke("footage/day1", "--out-dir", "out", "--no-video", "--jobs", "1", "--frames", "5")
    assert trial.exit_code == 0 and len(csv_rows(work / "out/b.lptrack.csv")) == 5
    full = invoke("footage/day1", "--out-dir", "out", "--no-video", "--jobs", "1", "--skip-existing")
    assert full.exit_code == 0 and "2 videos: 2 ok, 0 failed" in full.stderr, full.stderr
    assert len(csv_rows(work / "out/b.lptrack.csv")) == 24
    # The same trial again is complete; the full run too; another start frame is not.
    assert "2 skipped" in invoke("footage/day1", "--out-dir", "out", "--no-video", "--jobs", "1",
                                 "--skip-existing").stderr
    again = invoke("footage/day1", "--out-dir", "out", "--no-video", "--jobs", "1", "--frames", "24",
                   "--skip-existing")
    assert "2 skipped" in again.stderr
    moved = invoke("footage/day1", "--out-dir", "out", "--no-video", "--jobs", "1", "--start-frame", "2",
                   "--skip-existing")
    assert moved.exit_code == 0 and "2 ok" in moved.stderr
    assert csv_rows(work / "out/b.lptrack.csv")[0]["frame"] == "2"


def test_skip_existing_skips_a_video_cut_short_whose_run_went_to_its_end(work):
    """cut.avi announces 30 frames and ends after fewer: its run's outputs end there, and every resumed batch
    tracked it again; a trial over fewer frames than it has is still redone."""
    first = invoke("footage/day2/cut.avi", "--out-dir", "out", "--no-video", "--skip-existing")
    rows = len(csv_rows(work / "out/cut.lptrack.csv"))
    assert first.exit_code == 0 and 0 < rows < 30, first.stderr
    again = invoke("footage/day2/cut.avi", "--out-dir", "out", "--no-video", "--skip-existing")
    assert again.exit_code == 0 and again.stderr == "lptrack: cut.avi: outputs exist; skipped (--skip-existing)\n"
    trial = invoke("footage/day2/cut.avi", "--out-dir", "out", "--no-video", "--overwrite", "--frames", "3")
    assert trial.exit_code == 0 and len(csv_rows(work / "out/cut.lptrack.csv")) == 3
    redone = invoke("footage/day2/cut.avi", "--out-dir", "out", "--no-video", "--skip-existing")
    assert redone.exit_code == 0 and len(csv_rows(work / "out/cut.lptrack.csv")) == rows, redone.stderr


def test_skip_existing_is_refused_with_rows_on_stdout_for_one_video_too(work):
    """With one video, ``--csv - --skip-existing`` replaced the annotated video the hint said it would keep."""
    assert invoke("footage/day1/a.mp4", "--csv", "out.csv", "--frames", "3").exit_code == 0
    stamp = _stamp(work / "a.lptrack.mp4")
    refused = invoke("footage/day1/a.mp4", "--csv", "-", "--frames", "3")
    assert refused.exit_code == 1 and "(or --skip-existing" not in refused.stderr
    for videos in (["footage/day1/a.mp4"], ["footage/day1/a.mp4", "footage/day1/b.mp4"]):
        result = invoke(*videos, "--csv", "-", "--skip-existing")
        assert result.exit_code == 2 and result.stdout == ""
        assert result.stderr == "lptrack: error: --skip-existing needs outputs in files; it cannot apply to --csv -\n"
    assert _stamp(work / "a.lptrack.mp4") == stamp


def test_an_empty_name_is_refused_not_read_as_the_current_folder(work):
    """``lptrack run "$VIDEO"`` with VIDEO unset tracked every video below the current folder."""
    for args in ([""], ["footage/day1/a.mp4", "--csv", ""], ["footage/day1/a.mp4", "--out-dir", ""],
                 ["footage/day1/a.mp4", "-o", ""]):
        result = invoke(*args, "--no-video" if "-o" not in args else "--frames=2")
        assert result.exit_code == 2, args
        assert "an empty name was given (an unset shell variable?); give a file or folder name" in result.stderr
        assert result.stderr.count("\n") == 1
    assert sorted(p.name for p in work.iterdir()) == ["footage"]


def test_a_path_with_a_line_break_is_one_quoted_field_of_the_stream(work):
    """``find -print0 | lptrack run - --csv -``: a name holding a newline went out unquoted and split each row."""
    odd = work / "footage/day1/new\nline.mp4"
    shutil.copy(work / "footage/day1/a.mp4", odd)
    (work / "footage/day1/new\nline.roi").write_text((work / "footage/day1/a.roi").read_text())
    listing = f"{odd}\0{work / 'footage/day1/b.mp4'}\0"
    result = invoke("-", "--no-video", "--csv", "-", "--frames", "3", stdin=listing)
    assert result.exit_code == 0, result.stderr
    rows = csv_rows(result.stdout)
    assert [r["video"] for r in rows] == [str(odd)] * 3 + [str(work / "footage/day1/b.mp4")] * 3
    assert [r["frame"] for r in rows] == ["0", "1", "2"] * 2


def test_a_stream_stdout_cannot_encode_is_one_error_line(work, monkeypatch):
    shutil.copy(work / "footage/day1/a.mp4", work / "footage/day1/视频.mp4")
    shutil.copy(work / "footage/day1/a.roi", work / "footage/day1/视频.roi")
    env = dict(os.environ, PYTHONIOENCODING="latin-1")
    proc = subprocess.run([sys.executable, "-m", "logpolar_track", "run", "footage/day1", "--no-video", "--csv", "-",
                           "--frames", "2", "-q"], capture_output=True, env=env, cwd=work)
    assert proc.returncode == 1
    assert proc.stderr.decode() == ("lptrack: error: cannot write the rows to stdout: its encoding (latin-1) has no "
                                    "'\\u89c6\\u9891'; set PYTHONIOENCODING=utf-8\n")


def test_data_frame_span_reads_csv_and_json_lines(tmp_path):
    csv_file, jsonl_file, empty = tmp_path / "a.csv", tmp_path / "a.jsonl", tmp_path / "e.csv"
    csv_file.write_text(header_line() + "\n" + "".join(f"{i},0,1,1,1,1,0,1,0,1,tracked\n" for i in range(3, 900)))
    jsonl_file.write_text("".join(f'{{"frame": {i}, "status": "tracked"}}\n' for i in range(7, 12)))
    empty.write_text(header_line() + "\n")
    assert data_frame_span(csv_file) == (3, 899)
    assert data_frame_span(jsonl_file) == (7, 11)
    assert data_frame_span(empty) is None and data_frame_span(tmp_path / "missing.csv") is None


# -- batches cut short --------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def long_footage(tmp_path_factory) -> Path:
    """Four 320x240 clips of 120 frames: long enough to interrupt a batch while it writes."""
    root = tmp_path_factory.mktemp("long") / "in"
    root.mkdir()
    for i in range(4):
        _make_video(root, f"v{i}.mp4", n_frames=120, size=(320, 240), radius=30, seed=i)
    return root


def _start_and_wait_for_a_temporary_file(long_footage, out: Path, *extra: str):
    """Start a 2-job batch with video output; return (process, pid of the worker writing the first temp file)."""
    # A shell's background job inherits SIGINT ignored, and `nohup` SIGHUP, and Python keeps them so (lptrack
    # then leaves them ignored, as it should): restore the defaults, or the signals would not reach the batch when
    # the tests themselves run in the background or under nohup (done in the child's Python, since preexec_fn is
    # unsafe in a parent with threads).
    restore_signals = ("import runpy, signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
                       "[signal.signal(getattr(signal, s), signal.SIG_DFL) for s in ('SIGTERM', 'SIGHUP') "
                       "if hasattr(signal, s)]; "
                       "sys.argv[0] = 'lptrack'; runpy.run_module('logpolar_track', run_name='__main__')")
    process = subprocess.Popen([sys.executable, "-c", restore_signals, "run", str(long_footage), "--out-dir",
                                str(out), "--jobs", "2", "--tracker", "spatial", *extra],
                               stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        temporary = list(out.glob(".*.part.*")) if out.exists() else []
        if temporary:
            return process, int(re.search(r"\.(\d+)\.part\.", temporary[0].name).group(1))
        if process.poll() is not None:
            break
        time.sleep(0.02)
    process.kill()
    pytest.fail("the batch never wrote a temporary output")


def _complete(out: Path) -> list[str]:
    """Output files; every CSV among them holds all 120 rows (nothing half-written under a final name)."""
    names = files_under(out)
    for name in names:
        assert not name.startswith(".") and ".part." not in name, f"temporary file left: {name}"
        if name.endswith(".csv"):
            assert len(csv_rows(out / name)) == 120, name
    return names


ALL_OUTPUTS = sorted(f"v{i}.lptrack.{ext}" for i in range(4) for ext in ("csv", "mp4"))


@pytest.mark.parametrize("how, code, message", [("SIGINT", 130, "lptrack: interrupted"),
                                                 ("SIGTERM", 143, "lptrack: terminated (SIGTERM)"),
                                                 ("SIGHUP", 129, "lptrack: terminated (SIGHUP)")])
def test_interrupted_batch_leaves_only_complete_outputs_and_resumes(long_footage, tmp_path, how, code, message):
    out = tmp_path / "out"
    process, _ = _start_and_wait_for_a_temporary_file(long_footage, out)
    process.send_signal(getattr(signal, how))
    _, err = process.communicate(timeout=30)
    assert process.returncode == code, err
    assert err.strip() == message  # one line: no worker's traceback either
    assert len(_complete(out)) < len(ALL_OUTPUTS)
    resumed = subprocess.run([*LPTRACK, "run", str(long_footage), "--out-dir", str(out), "--jobs", "2",
                              "--tracker", "spatial", "--skip-existing"], capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    assert _complete(out) == ALL_OUTPUTS


@pytest.mark.parametrize("how, code", [("SIGTERM", 143), ("SIGHUP", 129)])
def test_stopped_single_video_leaves_nothing(long_footage, tmp_path, how, code):
    # `timeout`, `kill`, systemd and `docker stop` send SIGTERM; a closing terminal SIGHUP.
    out = tmp_path / "out"
    process, _ = _start_and_wait_for_a_temporary_file(long_footage / "v0.mp4", out)
    process.send_signal(getattr(signal, how))
    _, err = process.communicate(timeout=30)
    assert process.returncode == code, err
    assert err.strip() == f"lptrack: terminated ({how})"
    assert files_under(out) == []


def test_reader_of_stdout_leaving_stops_the_run_quietly(long_footage, tmp_path):
    # `lptrack run ... --csv - | head -3`: exit as a program killed by SIGPIPE, no message, nothing left.
    process = subprocess.Popen([*LPTRACK, "run", str(long_footage / "v0.mp4"), "--tracker", "spatial", "--csv", "-"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    assert process.stdout.readline().startswith("frame,time_s,")
    process.stdout.close()
    err = process.stderr.read()
    assert process.wait(timeout=60) == 141, err
    assert err == ""
    assert files_under(tmp_path) == []


def test_reader_of_a_batch_stream_leaving_stops_the_batch_quietly(long_footage, tmp_path):
    # `lptrack run folder --csv - | head -2`: 141 and no message, as with one video; and no more work once the
    # reader is gone: the second video is not finished for rows no one reads, and leaves nothing half-written.
    out = tmp_path / "out"
    process = subprocess.Popen([*LPTRACK, "run", str(long_footage), "--tracker", "spatial", "--csv", "-",
                                "--out-dir", str(out), "--jobs", "1"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    assert process.stdout.readline().startswith("video,frame,time_s,")
    assert process.stdout.readline().startswith(f"{long_footage / 'v0.mp4'},0,")
    process.stdout.close()
    err = process.stderr.read()
    assert process.wait(timeout=60) == 141, err
    # stderr is not a terminal: the first video's line as it settled (before its rows were streamed), and nothing
    # more: no second video, no summary, no message.
    assert re.fullmatch(rf"lptrack: 1/4 {re.escape(str(long_footage / 'v0.mp4'))}: 120 frames in [0-9.]+ s\n", err), err
    assert files_under(out) == ["v0.lptrack.mp4"]


def test_reader_of_a_batchs_stderr_leaving_stops_the_lines_not_the_batch(long_footage, tmp_path):
    # `lptrack run folder 2>&1 >/dev/null | grep -m1 failed`: the per-video lines (stderr not a terminal) made the
    # batch stop with 141 after its second video once the reader had gone; before them it wrote nothing there
    # until its summary, and the outputs are files.
    out = tmp_path / "out"
    process = subprocess.Popen([*LPTRACK, "run", str(long_footage), "--tracker", "spatial", "--no-video",
                                "--out-dir", str(out), "--jobs", "1"],
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    assert process.stderr.readline().startswith("lptrack: 1/4 ")
    process.stderr.close()
    assert process.wait(timeout=120) == 0
    assert files_under(out) == [f"v{i}.lptrack.csv" for i in range(4)]


def test_a_worker_stopped_as_it_starts_reports_interrupted(monkeypatch):
    # The parent's SIGTERM (Ctrl-C, the reader of --csv - gone) can land in a worker's set-up, before its task:
    # reported as interrupted, not a traceback from multiprocessing.
    from logpolar_track import executor

    def interrupted() -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(executor, "keep_frames_off_the_heap", interrupted)
    receiver, sender = multiprocessing.Pipe(duplex=False)
    handlers = {signum: signal.getsignal(signum) for signum in (signal.SIGINT, signal.SIGTERM)}
    try:
        executor._worker_main(sender, len, "abc")
    finally:
        for signum, handler in handlers.items():  # the worker's own, set in this process
            signal.signal(signum, handler)
    assert receiver.recv() == ("error", "interrupted")


def _sleeping_task(seconds, report):
    time.sleep(seconds)


def test_a_ctrl_c_while_a_worker_starts_stops_that_worker_too(monkeypatch):
    # A Ctrl-C landing inside Process.start() (after the fork, before start() returned) left that worker out of
    # those stopped: it went on after 'lptrack: interrupted', made its output folder, and stopped only at its first
    # progress report once the parent had exited (an empty folder left behind the run).
    from logpolar_track import executor

    process_class = executor._context().Process
    real_start = process_class.start
    started = []

    def start_then_ctrl_c(process):
        real_start(process)
        started.append(process)
        os.kill(os.getpid(), signal.SIGINT)  # the Ctrl-C, as start() returns

    monkeypatch.setattr(process_class, "start", start_then_ctrl_c)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            for _ in executor.run_tasks(_sleeping_task, [60, 60], jobs=2):
                pass
    finally:
        signal.signal(signal.SIGINT, previous)
    assert started
    for process in started:
        process.join(10)
        assert not process.is_alive()  # stopped with the others, not left to run its task


@pytest.mark.parametrize("failures", [1, 2])
def test_a_worker_server_that_died_is_asked_again_then_reported(monkeypatch, failures):
    # Workers fork from multiprocessing's forkserver; killed while asked for one, it makes start() raise EOFError,
    # which reached click as "Aborted!". A new server is made on the next request: one more try, then one
    # error naming the cause.
    from logpolar_track import executor

    process_class = executor._context().Process
    real_popen = process_class._Popen
    left = {"failures": failures}

    def flaky_popen(process):
        if left["failures"]:
            left["failures"] -= 1
            raise EOFError
        return real_popen(process)

    monkeypatch.setattr(process_class, "_Popen", staticmethod(flaky_popen))
    tasks = executor.run_tasks(operator.is_, ["a", "b"], jobs=2)
    if failures == 1:
        assert sorted((o.index, o.value, o.error) for o in tasks) == [(0, False, None), (1, False, None)]
    else:
        with pytest.raises(LptrackError, match="^cannot start a worker process: multiprocessing's process server "
                                               "ended \\(EOFError\\); what had not finished was not done$"):
            list(tasks)


def test_killed_worker_costs_only_its_video(long_footage, tmp_path):
    out = tmp_path / "out"
    process, worker = _start_and_wait_for_a_temporary_file(long_footage, out)
    os.kill(worker, signal.SIGKILL)
    _, err = process.communicate(timeout=120)
    assert process.returncode == 1, err
    assert "4 videos: 3 ok, 1 failed" in err
    assert re.search(r"lptrack: failed: .*v\d\.mp4: worker process was killed \(SIGKILL\)", err)
    assert len(_complete(out)) == len(ALL_OUTPUTS) - 2
    resumed = subprocess.run([*LPTRACK, "run", str(long_footage), "--out-dir", str(out), "--tracker", "spatial",
                              "--skip-existing", "--jobs", "2"], capture_output=True, text=True)
    assert resumed.returncode == 0 and "3 skipped (outputs exist)" in resumed.stderr
    assert _complete(out) == ALL_OUTPUTS


# -- OpenCV's threads while tracking ------------------------------------------------------------------------

def test_opencv_threads_sets_and_restores_after_the_last_overlapping_block(two_opencv_threads):
    before = two_opencv_threads
    assert cv2.getNumThreads() == before
    with opencv_threads(1):
        assert cv2.getNumThreads() == 1
        with opencv_threads(1):  # a second run in another thread of the process, overlapping
            pass
        assert cv2.getNumThreads() == 1  # the first run still holds its setting
    assert cv2.getNumThreads() == before
    with opencv_threads(None):
        assert cv2.getNumThreads() == before
    with pytest.raises(UsageError, match="at least 1"):
        with opencv_threads(0):
            pass
    with pytest.raises(KeyError):
        with opencv_threads(1):
            raise KeyError("a failed run restores the setting too")
    assert cv2.getNumThreads() == before


def test_a_batch_says_which_frames_of_a_damaged_video_have_no_row(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "cams").mkdir()
    _make_video(tmp_path / "cams", "ok.mp4", n_frames=20, seed=1)
    damage_middle(_make_video(tmp_path / "cams", "hit.mp4", n_frames=60, seed=1).path)
    result = invoke("cams", "--out-dir", "out", "--no-video", "--jobs", "1")
    assert result.exit_code == 0, result.stderr
    rows = csv_rows(tmp_path / "out" / "hit.lptrack.csv")
    frames = [int(r["frame"]) for r in rows]
    gap = sorted(set(range(60)) - set(frames))
    assert frames[-1] == 59 and 1 <= len(gap) <= 10 and gap == list(range(gap[0], gap[-1] + 1))
    assert (f"lptrack: warning: cams/hit.mp4: {len(gap)} frames could not be decoded (the file is damaged there) and "
            f"have no row: {gap[0]}-{gap[-1]}; tracking went on after them") in result.stderr.splitlines()
    assert "ended after" not in result.stderr


def test_a_failed_video_given_by_its_absolute_path_is_named_so(work):
    # The line names the video as given: its absolute path below the current folder was made relative.
    bad = work / "footage/day2/notes.mp4"
    result = invoke(str(bad), "footage/day1/a.mp4", "--out-dir", "out", "--no-video", "--jobs", "1")
    assert result.exit_code == 1
    assert f"lptrack: failed: {bad}: cannot read '{bad}' as a video" in result.stderr, result.stderr
