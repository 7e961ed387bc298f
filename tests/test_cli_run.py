"""``lptrack run`` end to end on tiny generated videos: outputs, stdout cleanliness, and every kind of bad input.

In-process with click's CliRunner (conftest's, which keeps stderr apart on click 8.1 too: ``result.stdout`` /
``result.stderr``), plus one real subprocess of the installed ``lptrack`` console script.
"""

from __future__ import annotations

import csv
import io
import json
import os
import re
import shutil
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import cv2
import pytest

from conftest import CliRunner, count_frames, damage_middle
from logpolar_track import outputs, pipeline
from logpolar_track.cli import main
from logpolar_track.draw import LOST_COLOUR, TRACKED_COLOUR
from logpolar_track.errors import LptrackError, RoiError
from logpolar_track.geometry import Ellipse
from logpolar_track.pipeline import read_roi_sidecar, run_video, track_video
from logpolar_track.results import COLUMNS
from logpolar_track.trackers import Tracker, TrackState, tracker_names
from logpolar_track.video import VideoReader

HEADER = "frame,time_s,cx,cy,a,b,angle_deg,scale,rotation_deg,score,status"


@pytest.fixture
def workdir(tmp_path, monkeypatch) -> Path:
    """An empty current folder, apart from the input video's folder, so default outputs can be listed."""
    folder = tmp_path / "work"
    folder.mkdir()
    monkeypatch.chdir(folder)
    return folder


def invoke(*args: str):
    return CliRunner().invoke(main, ["run", *map(str, args)], catch_exceptions=False)


def listing(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def read_rows(text: str) -> list[dict]:
    return list(csv.DictReader(io.StringIO(text)))


def centre_errors(rows, poses) -> np.ndarray:
    return np.array([np.hypot(float(r["cx"]) - p.cx, float(r["cy"]) - p.cy) for r, p in zip(rows, poses)])


def decoded_frame(path: Path, index: int) -> np.ndarray:
    """Frame ``index`` of the video at ``path``, decoded by reading up to it."""
    cap = cv2.VideoCapture(str(path))
    try:
        for _ in range(index + 1):
            ok, frame = cap.read()
            assert ok, f"{path} has no frame {index}"
    finally:
        cap.release()
    return frame


def outline_share(frame: np.ndarray, row: dict, colour) -> float:
    """Share of 64 points on ``row``'s ellipse outline with a pixel of about ``colour`` (BGR) within 1 px.

    mp4v is lossy and anti-aliasing blends the line into the frame: a channel may be off by up to 90.
    """
    ellipse = Ellipse(*(float(row[k]) for k in ("cx", "cy", "a", "b", "angle_deg")))
    painted = np.abs(frame.astype(int) - np.array(colour)).max(axis=2) < 90
    hits = [painted[max(y - 1, 0):y + 2, max(x - 1, 0):x + 2].any()
            for x, y in np.rint(ellipse.boundary_points(64)).astype(int)]
    return float(np.mean(hits))


# -- what a user gets ----------------------------------------------------------------------------------------

def test_run_writes_csv_and_annotated_video(tiny_video, workdir):
    result = invoke(tiny_video.path, "--roi", "80,60,20")
    assert result.exit_code == 0, result.stderr
    assert result.stdout == ""  # data only on stdout when asked for
    assert listing(workdir) == ["tiny.lptrack.csv", "tiny.lptrack.mp4"]
    text = (workdir / "tiny.lptrack.csv").read_text()
    assert text.splitlines()[0] == HEADER
    rows = read_rows(text)
    assert [int(r["frame"]) for r in rows] == list(range(tiny_video.n_frames))
    assert [r["status"] for r in rows][0] == "init" and {r["status"] for r in rows[1:]} <= {"tracked", "lost"}
    assert float(rows[-1]["time_s"]) == pytest.approx(19 / 30.0, abs=1e-6)
    assert float(rows[0]["scale"]) == 1.0 and float(rows[0]["rotation_deg"]) == 0.0
    # The pipeline is wired right: the CSV follows the moving disc (tracker accuracy is tested elsewhere).
    assert np.median(centre_errors(rows, tiny_video.poses)) < 1.5
    n, size, fps = count_frames(workdir / "tiny.lptrack.mp4")
    assert (n, size) == (tiny_video.n_frames, tiny_video.size)
    assert fps == pytest.approx(30.0, abs=0.01)
    summary = result.stderr.strip().splitlines()[-1]
    assert "20 frames (0 lost)" in summary and "mp4v" in summary and "tiny.lptrack.csv" in summary
    # The video is annotated: frame k shows row k's ellipse in the tracked colour (not the bare frame, nor lost).
    k = 10
    assert rows[k]["status"] == "tracked"
    frame = decoded_frame(workdir / "tiny.lptrack.mp4", k)
    assert outline_share(frame, rows[k], TRACKED_COLOUR) > 0.9
    assert outline_share(frame, rows[k], LOST_COLOUR) < 0.1
    assert outline_share(tiny_video.frames[k], rows[k], TRACKED_COLOUR) < 0.1  # the bare frame has no such outline


def test_roi_from_sidecar_and_explicit_outputs(tiny_video, workdir):
    result = invoke(tiny_video.path, "--out", "annotated.avi", "--csv", "track.csv", "-q")
    assert result.exit_code == 0, result.stderr
    assert result.stderr == "" and result.stdout == ""  # --quiet
    assert listing(workdir) == ["annotated.avi", "track.csv"]
    rows = read_rows((workdir / "track.csv").read_text())
    assert (float(rows[0]["cx"]), float(rows[0]["cy"]), float(rows[0]["a"])) == (80.0, 60.0, 20.0)
    assert count_frames(workdir / "annotated.avi")[:2] == (tiny_video.n_frames, tiny_video.size)


def test_csv_dash_gives_clean_csv_on_stdout_and_no_video(tiny_video, workdir):
    result = invoke(tiny_video.path, "--roi", "80,60,20", "--csv", "-", "--no-video")
    assert result.exit_code == 0, result.stderr
    assert result.stdout.splitlines()[0] == HEADER
    rows = list(csv.reader(io.StringIO(result.stdout)))
    assert len(rows) == 1 + tiny_video.n_frames and all(len(r) == len(COLUMNS) for r in rows)
    assert "frames" in result.stderr  # the summary went to stderr
    assert listing(workdir) == []  # --no-video: no video; CSV on stdout: no file


def test_no_video_writes_only_the_csv(tiny_video, workdir):
    result = invoke(tiny_video.path, "--no-video", "-q")
    assert result.exit_code == 0, result.stderr
    assert listing(workdir) == ["tiny.lptrack.csv"]


def test_ellipse_roi_and_start_frame(tiny_video, workdir):
    result = invoke(tiny_video.path, "--roi", "80,60,24,16,30", "--start-frame", "5", "--csv", "-", "--no-video")
    assert result.exit_code == 0, result.stderr
    rows = read_rows(result.stdout)
    assert [int(r["frame"]) for r in rows] == list(range(5, tiny_video.n_frames))
    assert float(rows[0]["time_s"]) == pytest.approx(5 / 30.0, abs=1e-6)
    assert rows[0]["status"] == "init" and float(rows[0]["angle_deg"]) == 30.0
    assert all(float(r["a"]) / float(r["b"]) == pytest.approx(1.5, rel=1e-3) for r in rows)


def test_frames_limits_the_run_and_o_names_the_video(tiny_video, workdir):
    result = invoke(tiny_video.path, "--start-frame", "3", "--frames", "5", "-o", "short.mp4")
    assert result.exit_code == 0, result.stderr
    rows = read_rows(Path("tiny.lptrack.csv").read_text())
    assert [int(r["frame"]) for r in rows] == [3, 4, 5, 6, 7]
    assert count_frames(workdir / "short.mp4")[0] == 5
    assert "5 frames" in result.stderr and "warning" not in result.stderr
    # A sidecar ROI is for frame 0 in lptrack's own samples: say that it was applied elsewhere.
    assert "tiny.mp4's .roi file" in result.stderr and "start frame 3" in result.stderr
    # Asking for more frames than there are is not an error: the run ends with the video.
    result = invoke(tiny_video.path, "--frames", "500", "--no-video", "--csv", "-")
    assert result.exit_code == 0 and len(read_rows(result.stdout)) == tiny_video.n_frames


def test_skip_existing_redoes_a_trial_run_and_skips_a_finished_one(tiny_video, workdir):
    trial = invoke(tiny_video.path, "--frames", "4", "--no-video")
    assert trial.exit_code == 0 and len(read_rows(Path("tiny.lptrack.csv").read_text())) == 4
    full = invoke(tiny_video.path, "--no-video", "--skip-existing")
    assert full.exit_code == 0 and "skipped" not in full.stderr
    assert len(read_rows(Path("tiny.lptrack.csv").read_text())) == tiny_video.n_frames
    again = invoke(tiny_video.path, "--no-video", "--skip-existing")
    assert again.exit_code == 0 and "outputs exist; skipped (--skip-existing)" in again.stderr


def test_skip_existing_redoes_a_run_from_another_roi(tiny_video, workdir):
    """The first row holds the ROI a run started from: a corrected ROI is tracked again; the same outline written
    another way (axes swapped, angle a quarter turn on) is the same run."""
    assert invoke(tiny_video.path, "--no-video", "--roi", "80,60,20,12,10").exit_code == 0
    same = invoke(tiny_video.path, "--no-video", "--skip-existing", "--roi", "80,60,12,20,100")
    assert same.exit_code == 0 and "outputs exist; skipped" in same.stderr
    moved = invoke(tiny_video.path, "--no-video", "--skip-existing", "--roi", "81,60,20,12,10")
    assert moved.exit_code == 0 and "skipped" not in moved.stderr
    first = read_rows(Path("tiny.lptrack.csv").read_text())[0]
    assert [first[k] for k in ("cx", "cy", "a", "b", "angle_deg")] == ["81.000", "60.000", "20.000", "12.000",
                                                                        "10.000"]
    # Without --roi the run starts from tiny.roi (80,60,20), which the file's first row is not.
    from_sidecar = invoke(tiny_video.path, "--no-video", "--skip-existing")
    assert from_sidecar.exit_code == 0 and "skipped" not in from_sidecar.stderr
    assert "outputs exist; skipped" in invoke(tiny_video.path, "--no-video", "--skip-existing").stderr


def test_data_format_follows_the_csv_extension_unless_given(tiny_video, workdir):
    assert invoke(tiny_video.path, "--no-video", "--csv", "t.jsonl").exit_code == 0
    first = json.loads(Path("t.jsonl").read_text().splitlines()[0])
    assert first["frame"] == 0 and first["status"] == "init"
    assert invoke(tiny_video.path, "--no-video", "--csv", "t.txt").exit_code == 0
    assert Path("t.txt").read_text().splitlines()[0] == HEADER
    assert invoke(tiny_video.path, "--no-video", "--csv", "u.txt", "--format", "jsonl").exit_code == 0
    assert json.loads(Path("u.txt").read_text().splitlines()[0])["frame"] == 0
    # --format wins over a name that says the other format, with a note saying so.
    against = invoke(tiny_video.path, "--no-video", "--csv", "v.csv", "--format", "jsonl")
    assert against.exit_code == 0 and json.loads(Path("v.csv").read_text().splitlines()[0])["frame"] == 0
    assert "note: writing JSON lines to 'v.csv' (--format jsonl), whose name says CSV" in against.stderr
    # A name another reader takes for another format (pandas decompresses .gz by the name).
    gz = invoke(tiny_video.path, "--no-video", "--csv", "w.csv.gz")
    assert gz.exit_code == 0 and Path("w.csv.gz").read_text().splitlines()[0] == HEADER
    assert "note: writing CSV to 'w.csv.gz', whose name says gzip; lptrack does not compress" in gz.stderr


@pytest.mark.skipif(not os.path.exists("/dev/null"), reason="needs /dev/null")
def test_csv_to_a_device_or_pipe_is_written_directly(tiny_video, workdir):
    result = invoke(tiny_video.path, "--no-video", "--csv", "/dev/null")
    assert result.exit_code == 0, result.stderr
    assert listing(workdir) == []
    if hasattr(os, "mkfifo"):  # a named pipe, as a process substitution >(gzip > t.csv.gz) gives
        fifo = workdir / "rows"
        os.mkfifo(fifo)
        received = []
        reader = threading.Thread(target=lambda: received.append(fifo.read_text()))
        reader.start()
        result = invoke(tiny_video.path, "--no-video", "--csv", fifo)
        reader.join(timeout=60)
        assert result.exit_code == 0, result.stderr
        assert len(read_rows(received[0])) == tiny_video.n_frames
        assert listing(workdir) == ["rows"]
    result = invoke(tiny_video.path, "--out", "/dev/null")  # a video is renamed into place: not onto a device
    assert result.exit_code == 1 and listing(workdir) in ([], ["rows"])
    assert result.stderr == ("lptrack: error: cannot write output video '/dev/null': it is a device or stream, "
                             "not a file; give a file name\n")


def test_existing_output_is_not_overwritten_without_flag(tiny_video, workdir):
    (workdir / "tiny.lptrack.csv").write_text("precious\n")
    result = invoke(tiny_video.path)
    assert result.exit_code == 1
    assert result.stderr.count("\n") == 1 and "tiny.lptrack.csv" in result.stderr
    assert "use --overwrite to replace it (or --skip-existing to keep" in result.stderr
    assert listing(workdir) == ["tiny.lptrack.csv"]
    assert (workdir / "tiny.lptrack.csv").read_text() == "precious\n"
    assert invoke(tiny_video.path, "--overwrite", "-q").exit_code == 0
    assert (workdir / "tiny.lptrack.csv").read_text().startswith(HEADER)


def test_an_output_of_another_video_of_that_name_points_to_parents_not_only_to_skip_existing(tmp_path, workdir):
    # xargs -n 1 over day1/cam.mp4 and day2/cam.mp4 into one --out-dir: the second finds day1's output under its own
    # name. The message offered --skip-existing alone, which then skipped day2 as done (exit 0, its track never
    # made) or, from another ROI, replaced day1's.
    from conftest import _make_video

    for day in ("day1", "day2"):
        (tmp_path / day).mkdir()
        _make_video(tmp_path / day, "cam.mp4", n_frames=6, seed=3)
    assert invoke(tmp_path / "day1/cam.mp4", "--no-video", "--out-dir", "tracks", "-q").exit_code == 0
    result = invoke(tmp_path / "day2/cam.mp4", "--no-video", "--out-dir", "tracks", "-q")
    assert result.exit_code == 1
    assert result.stderr == ("lptrack: error: output CSV 'tracks/cam.lptrack.csv' already exists; use --overwrite to "
                             "replace it (or --skip-existing to keep it if this video wrote it; videos of one name "
                             "from several folders need --parents)\n")
    for day in ("day1", "day2"):  # as the message says
        assert invoke(tmp_path / day / "cam.mp4", "--no-video", "--out-dir", "tracks", "--parents", "-q").exit_code == 0
    assert len(list((workdir / "tracks").rglob("cam.lptrack.csv"))) == 3


def test_a_url_is_refused_as_such_not_reported_missing_under_a_mangled_name(tiny_video, workdir):
    # Read as a path, 'http://host/x.mp4' was "video 'http:/host/x.mp4' not found" (exit 1): '//' collapsed, and no
    # word that lptrack reads files only.
    result = invoke("http://example.com/clip.mp4", "--roi", "80,60,20")
    assert result.exit_code == 2
    assert result.stderr == ("lptrack: error: Invalid value for 'VIDEO...': 'http://example.com/clip.mp4' is a URL; "
                             "lptrack reads and writes local files only (a video online: download it first, e.g. "
                             "ffmpeg -i 'http://example.com/clip.mp4' -c copy clip.mp4) (see 'lptrack run --help')\n")
    output = invoke(tiny_video.path, "--no-video", "--csv", "s3://bucket/t.csv")
    assert output.exit_code == 2
    assert "'s3://bucket/t.csv' is a URL; lptrack reads and writes local files only (see" in output.stderr
    assert listing(workdir) == []
    # A colon alone is a file name like another.
    assert invoke(tiny_video.path, "--no-video", "--csv", "take:1.csv", "-q").exit_code == 0


def test_roi_partly_over_the_border_is_accepted(tiny_video, workdir):
    # That trackers follow such a ROI is test_trackers.py's test_roi_partly_over_the_border_still_tracks.
    roi = Ellipse.circle(10, 60, 20)
    assert 0.5 < roi.fraction_inside(*tiny_video.size) < 0.95
    result = invoke(tiny_video.path, "--roi", roi.to_spec(), "--csv", "-", "--no-video", "--frames", "2")
    assert result.exit_code == 0, result.stderr
    first = read_rows(result.stdout)[0]
    assert first["status"] == "init"
    assert [float(first[k]) for k in ("cx", "cy", "a", "b", "angle_deg")] == [10.0, 60.0, 20.0, 20.0, 0.0]


def test_interrupt_exits_130_and_leaves_nothing(tiny_video, workdir, monkeypatch):
    real_draw = pipeline.draw_state

    def draw_then_interrupt(frame, state, *, frame_index, status, **options):
        if frame_index == 5:
            raise KeyboardInterrupt
        return real_draw(frame, state, frame_index=frame_index, status=status, **options)

    monkeypatch.setattr(pipeline, "draw_state", draw_then_interrupt)
    result = invoke(tiny_video.path)
    assert result.exit_code == 130
    assert result.stderr == "lptrack: interrupted\n"
    assert listing(workdir) == []  # no finished-looking file, no temporary file


def test_a_tracker_that_refuses_the_roi_writes_nothing_not_even_a_header(tiny_video, workdir):
    # The tracker starts before any output is opened: a reader of --csv - saw an empty but valid CSV (a header).
    for named in (["--csv", "-", "--no-video"], []):
        result = invoke(tiny_video.path, "--roi", "80,60,2", "--tracker", "cv-mil", *named)
        assert (result.exit_code, result.stdout) == (2, "")
        assert result.stderr.startswith("lptrack: error: cv-mil cannot start on a box under 5 px a side")
        assert listing(workdir) == []


def test_help_explains_roi_and_lists_every_tracker():
    result = CliRunner().invoke(main, ["run", "--help"])
    assert result.exit_code == 0
    assert "cx,cy,a,b,angle" in result.stdout and "counter-clockwise" in result.stdout
    assert HEADER in result.stdout
    for name in tracker_names():
        assert name in result.stdout


# -- bad input: one line on stderr, the right exit code, no traceback, nothing left behind --------------------

def _not_a_video(folder: Path) -> Path:
    path = folder / "notes.mp4"
    path.write_text("not a video\n" * 100)
    return path


def _text_file(folder: Path) -> Path:
    # FFmpeg's tty demuxer would play a .txt file as a video of its characters.
    path = folder / "notes.txt"
    path.write_text("a line of notes\n" * 100)
    return path


def _zero_bytes(folder: Path) -> Path:
    path = folder / "empty.mp4"
    path.touch()
    return path


def _no_frames(folder: Path) -> Path:
    import cv2

    path = folder / "noframes.avi"
    cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25.0, (64, 48)).release()
    return path


BAD = {
    # id: (video maker or None for the tiny video, extra args, exit code, fragments of the message)
    "missing-file": (lambda d: d / "nope.mp4", ["--roi", "1,2,3"], 1, ["nope.mp4", "not found"]),
    "not-a-video": (_not_a_video, ["--roi", "1,2,3"], 1, ["notes.mp4", "cannot read"]),
    "zero-byte-video": (_zero_bytes, ["--roi", "1,2,3"], 1, ["no frames"]),
    "video-without-frames": (_no_frames, ["--roi", "1,2,3"], 1, ["noframes.avi"]),
    "text-file": (_text_file, ["--roi", "1,2,3"], 1, ["notes.txt", "text file"]),
    "roi-two-numbers": (None, ["--roi", "1,2"], 2, ["cx,cy,r", "cx,cy,a,b,angle"]),
    "roi-spaces": (None, ["--roi", "80 60 20"], 2, ["commas", "cx,cy,r"]),
    "roi-semicolons": (None, ["--roi", "80;60;20"], 2, ["commas", "cx,cy,r"]),
    "roi-stray-comma": (None, ["--roi", "80,60,20,"], 2, ["empty field", "cx,cy,r"]),
    "roi-not-numbers": (None, ["--roi", "a,b,c"], 2, ["not a list of numbers", "cx,cy,r"]),
    "roi-negative-radius": (None, ["--roi", "80,60,-5"], 2, ["> 0", "cx,cy,r"]),
    "roi-zero-radius": (None, ["--roi", "80,60,0"], 2, ["> 0", "cx,cy,r"]),
    "roi-mostly-outside": (None, ["--roi", "159,119,30"], 2, ["mostly outside", "160x120", "tiny.mp4"]),
    "roi-centre-outside": (None, ["--roi", "200,60,10"], 2, ["outside", "0 <= cx <= 159"]),
    "start-frame-past-end": (None, ["--start-frame", "99"], 2, ["past the end", "20 frames"]),
    "missing-output-folder": (None, ["--out", "missing/out.mp4"], 1, ["missing", "does not exist"]),
    "missing-csv-folder": (None, ["--csv", "missing/out.csv"], 1, ["missing", "does not exist"]),
    # Over the file system's 255 bytes a name: pathlib raised it where a missing file gives False.
    "video-name-too-long": (lambda d: d / ("v" * 300 + ".mp4"), ["--roi", "1,2,3"], 1,
                            ["cannot use the name 'vvvv", "vvv.mp4': it has 304 bytes", "at most 255"]),
    "csv-name-too-long": (None, ["--csv", "c" * 300 + ".csv"], 1, ["the name 'cccc", "304 bytes"]),
    "output-folder-is-a-file": (None, ["--csv", "{video}/out.csv"], 1, ["not a folder"]),
    # A folder for -o is said as for --csv (it was click's "is a directory", exit 2).
    "out-is-a-folder": (None, ["--out", "."], 1, ["cannot write output video '.': it is a folder; give a file name "
                                                  "(outputs go into a folder with --out-dir .)"]),
    "csv-is-a-folder": (None, ["--csv", "."], 1, ["cannot write output CSV '.': it is a folder"]),
    # A folder to be made: '-o out/' lost its slash and was "unsupported extension ''" (exit 2).
    "out-names-a-folder": (None, ["--out", "out/"], 1, ["cannot write output video 'out/': it names a folder; give "
                                                        "a file name (outputs go into a folder with --out-dir out)"]),
    "csv-names-a-folder": (None, ["--csv", "out/"], 1, ["cannot write output CSV 'out/': it names a folder; give a "
                                                        "file name (outputs go into a folder with --out-dir out)"]),
    "out-dir-is-a-file": (None, ["--out-dir", "{video}"], 1, ["tiny.mp4' is a file, not a folder"]),
    "out-dir-below-a-file": (None, ["--out-dir", "{video}/sub"], 1, ["tiny.mp4' is a file, not a folder"]),
    "csv-is-the-roi-file": (None, ["--csv", "{roi}", "--no-video", "--overwrite"], 1,
                            ["output CSV", "tiny.roi' is the input's ROI file; choose another name"]),
    "video-is-the-input": (None, ["--out", "{video}", "--overwrite"], 1,
                           ["output video", "tiny.mp4' is the input video; choose another name"]),
    "zero-frames": (None, ["--frames", "0"], 2, ["--frames"]),
    "unsupported-video-extension": (None, ["--out", "out.txt"], 2, ["unsupported extension", ".mp4"]),
    "out-and-no-video": (None, ["--out", "a.mp4", "--no-video"], 2, ["--no-video"]),
    "video-to-stdout": (None, ["--out", "-"], 2, ["the annotated video cannot go to stdout ('-o -')", "--no-video"]),
    "param-unknown": (None, ["--param", "nosuch=1"], 2, ["no parameter 'nosuch' in lpcf", "learning_rate (0.02)"]),
    "param-misspelt": (None, ["--param", "learnig_rate=0.05"], 2,
                       ["no parameter 'learnig_rate' in lpcf (did you mean 'learning_rate'?)"]),
    "tracker-misspelt": (None, ["--tracker", "lpfc"], 2,
                         ["'lpfc' is not a tracker (did you mean 'lpcf'?); choose one of: fixed,"]),
    "tracker-unknown": (None, ["--tracker", "nosuch"], 2, ["'nosuch' is not a tracker; choose one of: fixed,"]),
    "param-no-value": (None, ["--param", "learning_rate"], 2, ["--param takes NAME=VALUE", "'learning_rate'"]),
    "param-not-a-number": (None, ["--param", "learning_rate=fast"], 2,
                           ["learning_rate takes a finite number (default 0.02), got 'fast'"]),
    "param-not-whole": (None, ["--tracker", "fixed", "--param", "window=9.5"], 2,
                        ["fixed: parameter window takes a whole number (default 11), got '9.5'"]),
    "param-not-a-flag": (None, ["--param", "scale_filter=maybe"], 2, ["takes true or false"]),
    "param-out-of-range": (None, ["--param", "learning_rate=2"], 2, ["lpcf: learning_rate must be", "got 2"]),
    "param-of-another-tracker": (None, ["--tracker", "cv-mil", "--param", "window=9"], 2,
                                 ["no parameter 'window' in cv-mil", "cv-mil takes seed (0)"]),
}


@pytest.mark.parametrize("make, args, code, fragments", BAD.values(), ids=BAD.keys())
def test_bad_input(tiny_video, workdir, make, args, code, fragments):
    video = make(tiny_video.path.parent) if make else tiny_video.path
    inputs_before = listing(tiny_video.path.parent)
    args = [a.replace("{video}", str(video)).replace("{roi}", str(video.with_suffix(".roi"))) for a in args]
    result = invoke(video, *args)
    assert result.exit_code == code, result.stderr
    assert "Traceback" not in result.stdout + result.stderr
    assert result.stdout == ""
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("lptrack: error: "), result.stderr
    for fragment in fragments:
        assert fragment in lines[0]
    assert listing(workdir) == []
    assert listing(tiny_video.path.parent) == inputs_before


def test_out_dir_never_silently_ignored(tiny_video, workdir):
    # --out-dir is the folder for the outputs lptrack names (README); a path given is used as given, and said so.
    result = invoke(tiny_video.path, "--csv", "mine.csv", "--out-dir", "out")
    assert result.exit_code == 0, result.stderr
    assert listing(workdir) == ["mine.csv", "out"] and listing(workdir / "out") == ["tiny.lptrack.mp4"]
    assert result.stderr.startswith("lptrack: note: --out-dir holds the outputs lptrack names; 'mine.csv' is "
                                    "written where named\n")


@pytest.mark.parametrize("args", [["--csv", "mine.csv", "--no-video"], ["--csv", "-", "--out", "v.mp4"],
                                  ["--csv", "mine.csv", "--out", "v.mp4"]])
def test_out_dir_left_no_output_is_an_error(tiny_video, workdir, args):
    result = invoke(tiny_video.path, *args, "--out-dir", "out")
    assert result.exit_code == 2
    assert result.stdout == "" and listing(workdir) == []
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("lptrack: error: --out-dir would hold nothing: it is the folder "
                                                   "for the outputs lptrack names, and --csv "), result.stderr


def removed_once_before_the_outputs_are_checked(monkeypatch, folder: Path) -> list[int]:
    """Make ``folder`` vanish once, just before a run checks its outputs: what a parallel run into the same folder
    that failed does when it removes the folder it made (``xargs -P``). Returns the count of checks."""
    checks = []
    real_check = pipeline.check_outputs

    def check_outputs(*args, **kwargs):
        checks.append(1)
        if len(checks) == 1:
            folder.rmdir()
        return real_check(*args, **kwargs)

    monkeypatch.setattr(pipeline, "check_outputs", check_outputs)
    return checks


def test_an_out_dir_removed_by_a_parallel_run_is_made_again(tiny_video, workdir, monkeypatch):
    checks = removed_once_before_the_outputs_are_checked(monkeypatch, workdir / "out")
    result = invoke(tiny_video.path, "--out-dir", "out")
    assert result.exit_code == 0, result.stderr
    assert len(checks) == 2 and listing(workdir / "out") == ["tiny.lptrack.csv", "tiny.lptrack.mp4"]
    assert len(read_rows((workdir / "out" / "tiny.lptrack.csv").read_text())) == tiny_video.n_frames


def test_rows_on_stdout_are_not_sent_twice_when_the_out_dir_goes(tiny_video, workdir, monkeypatch):
    checks = removed_once_before_the_outputs_are_checked(monkeypatch, workdir / "out")
    result = invoke(tiny_video.path, "--out-dir", "out", "--csv", "-")
    assert result.exit_code == 1 and len(checks) == 1
    assert result.stderr.endswith("folder 'out' does not exist\n"), result.stderr
    assert listing(workdir) == []


def test_rows_into_a_pipe_are_not_sent_twice_when_the_out_dir_goes(tiny_video, workdir, monkeypatch):
    # --csv /dev/stdout or a named pipe is written in place, as '-' is: its header and first row went out before the
    # first frame's video opened in --out-dir; started again, they were sent twice.
    from logpolar_track import video as video_module

    real_open = video_module.VideoWriter._open
    opens = []

    def open_once_gone(self, width, height):
        opens.append(1)
        if len(opens) == 1:
            self.wanted_path.parent.rmdir()  # a parallel run into it that failed
        return real_open(self, width, height)

    monkeypatch.setattr(video_module.VideoWriter, "_open", open_once_gone)
    pipe = workdir / "rows"
    os.mkfifo(pipe)
    read, stop = [], threading.Event()

    def reader():
        while not stop.is_set():
            with open(pipe) as rows:
                read.append(rows.read())

    thread = threading.Thread(target=reader, daemon=True)
    thread.start()
    result = invoke(tiny_video.path, "--out-dir", "out", "--csv", str(pipe))
    stop.set()
    while thread.is_alive():  # unblock the reader's open
        try:
            os.close(os.open(pipe, os.O_WRONLY | os.O_NONBLOCK))
        except OSError:
            pass
        thread.join(0.05)
    assert "".join(read).count("frame,time_s") == 1, read
    assert result.exit_code == 1 and len(opens) == 1
    assert result.stderr.endswith("folder 'out' does not exist (removed after the run started)\n"), result.stderr


def test_no_roi_and_no_sidecar(tiny_video, workdir):
    tiny_video.path.with_suffix(".roi").unlink()
    result = invoke(tiny_video.path)
    assert result.exit_code == 2
    assert "no ROI" in result.stderr and "--roi" in result.stderr and "tiny.roi" in result.stderr
    assert listing(workdir) == []


def test_unwritable_output_folder(tiny_video, workdir, monkeypatch):
    locked = workdir / "locked"
    locked.mkdir()
    if os.name != "posix" or os.geteuid() == 0:  # root may write to a read-only folder: os.access says so
        real_access = os.access
        monkeypatch.setattr(outputs.os, "access", lambda path, mode, **kw: (
            not (Path(path).resolve() == locked.resolve() and mode & os.W_OK) and real_access(path, mode, **kw)))
    locked.chmod(0o500)
    try:
        result = invoke(tiny_video.path, "--csv", "locked/out.csv", "--no-video")
    finally:
        locked.chmod(0o700)
    assert result.exit_code == 1 and result.stdout == ""
    assert result.stderr == ("lptrack: error: cannot write output CSV 'locked/out.csv': folder 'locked' is not "
                             "writable\n")
    assert listing(locked) == []


# -- the library underneath ----------------------------------------------------------------------------------

def test_track_video_yields_init_then_one_result_per_frame(tiny_video):
    results = list(track_video(tiny_video.path, "80,60,20"))
    assert len(results) == tiny_video.n_frames
    assert results[0].status == "init" and results[0].state.scale == 1.0
    assert [r.frame for r in results] == list(range(tiny_video.n_frames))


class Still(Tracker):
    """A stand-in tracker without rotation that never finds the object after init."""

    name = "still-test"
    measures_rotation = False

    def init(self, frame, roi):
        self.state = TrackState(roi, 1.0, None, 1.0)
        return self.state

    def update(self, frame):
        return False, self.state


def test_param_tunes_the_tracker_as_tracker_params_do(tiny_video, workdir):
    result = invoke(tiny_video.path, "--no-video", "--csv", "tuned.csv", "--param", "learning_rate=0.2",
                    "--param", "colour_weight=0")
    assert result.exit_code == 0, result.stderr
    run_video(tiny_video.path, None, csv_out=workdir / "library.csv",
              tracker_params={"learning_rate": 0.2, "colour_weight": 0.0})
    run_video(tiny_video.path, None, csv_out=workdir / "default.csv")
    tuned = (workdir / "tuned.csv").read_text()
    assert tuned == (workdir / "library.csv").read_text()
    assert tuned != (workdir / "default.csv").read_text()


def test_running_out_of_memory_is_one_line_and_leaves_no_output(tiny_video, workdir, monkeypatch):
    class Greedy(Tracker):
        name = "greedy-test"

        def init(self, frame, roi):
            return TrackState(roi, 1.0, 0.0, 1.0)

        def update(self, frame):
            raise MemoryError("Unable to allocate 149. GiB")

    monkeypatch.setattr(pipeline, "_make_tracker", lambda tracker, params: Greedy())
    result = invoke(tiny_video.path)
    assert result.exit_code == 1 and result.stdout == ""
    assert result.stderr == ("lptrack: error: out of memory; a smaller video, fewer --jobs or smaller tracker "
                             "parameters need less\n")
    assert listing(workdir) == []


def test_param_of_a_thesis_tracker(tiny_video, workdir):
    # A match never reaches 1: with lost_threshold=1 every frame after the first is reported lost.
    result = invoke(tiny_video.path, "-o", "lost.mp4", "--csv", "-", "--tracker", "fixed",
                    "--param", "lost_threshold=1")
    assert result.exit_code == 0, result.stderr
    rows = read_rows(result.stdout)
    assert [r["status"] for r in rows] == ["init"] + ["lost"] * (tiny_video.n_frames - 1)
    assert "lptrack: tiny.mp4: 20 frames (19 lost) with fixed at " in result.stderr.splitlines()[-1]
    # Lost frames are drawn in the lost colour, nowhere in the tracked one; the init frame in the tracked one.
    for k in (1, 10, tiny_video.n_frames - 1):
        frame = decoded_frame(workdir / "lost.mp4", k)
        assert outline_share(frame, rows[k], LOST_COLOUR) > 0.75, k  # red suffers most from mp4v
        assert outline_share(frame, rows[k], TRACKED_COLOUR) < 0.1, k
    assert outline_share(decoded_frame(workdir / "lost.mp4", 0), rows[0], TRACKED_COLOUR) > 0.9
    default = invoke(tiny_video.path, "--no-video", "--csv", "-", "--tracker", "fixed")
    assert {r["status"] for r in read_rows(default.stdout)[1:]} == {"tracked"}


def test_track_video_accepts_a_tracker_instance(tiny_video):
    results = list(track_video(tiny_video.path, Ellipse.circle(80, 60, 20), Still()))
    assert [r.status for r in results] == ["init"] + ["lost"] * (tiny_video.n_frames - 1)


def test_tracker_without_rotation_leaves_rotation_empty(tiny_video, tmp_path):
    summary = run_video(tiny_video.path, "80,60,24,16,30", tracker=Still(), csv_out=tmp_path / "t.csv")
    assert summary.lost == tiny_video.n_frames - 1 and summary.tracker == "still-test"
    rows = read_rows((tmp_path / "t.csv").read_text())
    assert {r["rotation_deg"] for r in rows} == {""} and {r["angle_deg"] for r in rows} == {"30.000"}
    # In JSON lines an empty field is null (not ""); frames are ints and scores floats, whatever their digits.
    run_video(tiny_video.path, "80,60,24,16,30", tracker=Still(), csv_out=tmp_path / "t.jsonl",
              csv_options={"data_format": "jsonl"})
    records = [json.loads(line) for line in (tmp_path / "t.jsonl").read_text().splitlines()]
    assert [r["frame"] for r in records] == list(range(tiny_video.n_frames))
    assert all(r["rotation_deg"] is None for r in records)
    assert all(type(r["frame"]) is int and type(r["score"]) is float for r in records)
    assert [r["score"] for r in records] == [1.0] * tiny_video.n_frames  # '1.0000' in the CSV
    assert [r["status"] for r in records] == ["init"] + ["lost"] * (tiny_video.n_frames - 1)


def test_run_video_summary(tiny_video, tmp_path):
    summary = run_video(tiny_video.path, None, csv_out=tmp_path / "t.csv", video_out=tmp_path / "t.mp4")
    assert summary.frames == tiny_video.n_frames and summary.video_out == tmp_path / "t.mp4"
    assert summary.fourcc == "mp4v" and summary.csv_out == str(tmp_path / "t.csv")
    assert summary.video_fps == pytest.approx(30.0) and (summary.width, summary.height) == (160, 120)


@pytest.mark.parametrize("name", ["clip.roi", "clip.mp4.roi"])
def test_read_roi_sidecar_names(tmp_path, name):
    (tmp_path / name).write_text("# initial ROI\n10,20,30,15,45\n")
    assert read_roi_sidecar(tmp_path / "clip.mp4") == Ellipse(10, 20, 30, 15, 45)
    assert read_roi_sidecar(tmp_path / "other.mp4") is None


def test_bad_roi_sidecar_names_the_file(tmp_path):
    (tmp_path / "clip.roi").write_text("1,2\n")
    with pytest.raises(RoiError, match="clip.roi"):
        read_roi_sidecar(tmp_path / "clip.mp4")


# -- the real console script ----------------------------------------------------------------------------------

def test_console_script_csv_dash_is_clean(tiny_video, workdir):
    script = shutil.which("lptrack", path=str(Path(sys.executable).parent)) or shutil.which("lptrack")
    if script is None:
        pytest.skip("the lptrack console script is not installed (pip install -e .)")
    proc = subprocess.run([script, "run", str(tiny_video.path), "--csv", "-", "--no-video"],
                          capture_output=True, text=True, timeout=120, cwd=workdir)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[0] == HEADER and len(lines) == 1 + tiny_video.n_frames
    assert all(len(row) == len(COLUMNS) for row in csv.reader(lines))
    assert "frames" in proc.stderr and "Traceback" not in proc.stderr
    assert listing(workdir) == []


def test_start_time_starts_at_the_frame_shown_then(tiny_video, workdir):
    # 30 fps: 0.2 s is frame 6; the same CSV as --start-frame 6, and the frame 'lptrack frame --time' shows.
    by_frame = invoke(str(tiny_video.path), "--start-frame", "6", "--no-video", "--csv", "-")
    for time_text in ("0.2", "0:00.2", "00:00:00.200"):
        result = invoke(str(tiny_video.path), "--start-time", time_text, "--no-video", "--csv", "-")
        assert result.exit_code == 0, result.stderr
        assert result.stdout == by_frame.stdout and result.stdout.splitlines()[1].startswith("6,0.200000,")
        assert "lptrack: note: 0.2 s is frame 6 of tiny.mp4 (at 0.200 s); tracking starts there" in result.stderr
    late = invoke(str(tiny_video.path), "--start-time", "5", "--no-video")
    assert late.exit_code == 2 and "lptrack: error: time 5 s lies past the end of" in late.stderr
    assert "give a time before 0.667 s or a frame from 0 to 19" in late.stderr
    both = invoke(str(tiny_video.path), "--start-time", "0.2", "--start-frame", "3", "--no-video")
    assert both.exit_code == 2 and "give one of them" in both.stderr
    many = invoke(str(tiny_video.path), str(tiny_video.path), "--start-time", "0.2", "--no-video", "--csv", "-")
    assert many.exit_code == 2 and "--start-time is for one video; with several videos give --start-frame N" in (
        many.stderr)
    for bad in ("-1", "1:75", "1_0", "ten"):
        result = invoke(str(tiny_video.path), "--start-time", bad, "--no-video")
        assert result.exit_code == 2 and f"'{bad}' is not a time" in result.stderr, result.stderr
    assert listing(workdir) == []


def test_start_time_is_looked_up_after_the_cheap_checks(tiny_video, workdir, monkeypatch):
    # Finding the frame at a time decodes the video up to it (minutes into a long one): a missing ROI or an output
    # that exists was said only after that.
    from logpolar_track.cli import run as cli_run

    looked_up = []
    real = cli_run._start_frame_at_time
    monkeypatch.setattr(cli_run, "_start_frame_at_time", lambda *a: looked_up.append(a) or real(*a))
    assert invoke(str(tiny_video.path), "--start-time", "0.2", "--no-video").exit_code == 0
    assert len(looked_up) == 1
    again = invoke(str(tiny_video.path), "--start-time", "0.2", "--no-video")
    assert again.exit_code == 1 and "already exists" in again.stderr and len(looked_up) == 1
    tiny_video.path.with_suffix(".roi").unlink()
    no_roi = invoke(str(tiny_video.path), "--start-time", "0.2", "--no-video", "--csv", "-")
    assert no_roi.exit_code == 2 and "no ROI given" in no_roi.stderr and len(looked_up) == 1
    zero = invoke(str(tiny_video.path), "--start-time", "0.2", "--start-frame", "0", "--roi", "80,60,20")
    assert zero.exit_code == 2 and "give one of them" in zero.stderr  # an explicit 0 is a start frame too


def test_a_long_run_logs_its_progress_where_stderr_is_not_a_terminal(tiny_video, workdir, monkeypatch):
    # A log or a CI job gets a line every _LOG_PROGRESS_SECONDS, not a bar's redraws; a run shorter than that, none.
    from logpolar_track.cli import run as cli_run

    result = invoke(str(tiny_video.path), "--no-video")
    assert result.exit_code == 0 and "frames/s, " not in result.stderr and " of 20 frames" not in result.stderr
    monkeypatch.setattr(cli_run, "_LOG_PROGRESS_SECONDS", 0.0)
    result = invoke(str(tiny_video.path), "--no-video", "--overwrite")
    assert result.exit_code == 0, result.stderr
    lines = [line for line in result.stderr.splitlines() if " of 20 frames" in line]
    assert [line.split(": ")[2].split(" of")[0] for line in lines] == [str(k) for k in range(1, 21)]
    assert re.fullmatch(r"lptrack: tiny\.mp4: 20 of 20 frames \(100 %\), [0-9]+ frames/s", lines[-1]), lines[-1]
    quiet = invoke(str(tiny_video.path), "--no-video", "--overwrite", "-q")
    assert quiet.exit_code == 0 and quiet.stderr == ""


def test_a_run_with_stderr_closed_does_its_work_in_silence(tiny_video, workdir):
    """``2>&-`` leaves Python without sys.stderr: the run failed with exit 1 and no word (an AttributeError on
    ``isatty``). It tracks and writes its outputs as with ``-q``."""
    proc = subprocess.run([sys.executable, "-m", "logpolar_track", "run", str(tiny_video.path), "--no-video"],
                          stdout=subprocess.PIPE, text=True, timeout=120, cwd=workdir,
                          preexec_fn=lambda: os.close(2))
    assert proc.returncode == 0 and proc.stdout == ""
    assert listing(workdir) == [f"{tiny_video.path.stem}.lptrack.csv"]


def test_ctrl_c_while_the_console_script_imports_is_quiet(tmp_path):
    # Ctrl-C in the first few tenths of a second lands in the imports of numpy and OpenCV. Made certain here: the
    # import of numpy is interrupted. Exit 130 with the one line, not a KeyboardInterrupt traceback.
    script = shutil.which("lptrack", path=str(Path(sys.executable).parent)) or shutil.which("lptrack")
    if script is None:
        pytest.skip("the lptrack console script is not installed (pip install -e .)")
    code = ("import runpy, sys\n"
            "class Interrupt:\n"
            "    @staticmethod\n"
            "    def find_spec(name, path=None, target=None):\n"
            "        if name == 'numpy':\n"
            "            raise KeyboardInterrupt\n"
            "sys.meta_path.insert(0, Interrupt)\n"
            f"sys.argv = [{script!r}, 'run', 'clip.mp4', '--roi', '80,60,20']\n"
            f"runpy.run_path({script!r}, run_name='__main__')\n")
    env = {k: v for k, v in os.environ.items() if k != "LPTRACK_DEBUG"}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=tmp_path,
                          env=env)
    assert proc.returncode == 130, proc.stderr
    assert proc.stderr == "lptrack: interrupted\n"


def test_ctrl_c_wrapped_by_an_import_or_while_parsing_is_quiet(monkeypatch, capsys):
    # Two windows before the CLI's own handling: Python 3.11 wraps a Ctrl-C that lands in a dataclass's creation
    # during an import in a RuntimeError, and click says "Aborted!" (exit 1) for one while the arguments are parsed.
    import logpolar_track.__main__ as console
    import logpolar_track.cli as cli

    def imported_when_interrupted(*args, **kwargs):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise RuntimeError("Error calling __set_name__ on 'Field' instance 'outcomes'") from exc

    monkeypatch.delenv("LPTRACK_DEBUG", raising=False)
    monkeypatch.setattr(cli, "main", imported_when_interrupted)
    assert console.main() == 130
    assert capsys.readouterr().err == "lptrack: interrupted\n"

    def not_a_ctrl_c(*args, **kwargs):
        raise RuntimeError("something else")

    def failing_while_handling_a_ctrl_c(*args, **kwargs):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            raise RuntimeError("a bug in clean-up") from None

    for failing, said in ((not_a_ctrl_c, "something else"), (failing_while_handling_a_ctrl_c, "a bug in clean-up")):
        monkeypatch.setattr(cli, "main", failing)
        with pytest.raises(RuntimeError, match=said):
            console.main()

    def interrupted(self, ctx, args):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli.LptrackGroup, "parse_args", interrupted)
    result = CliRunner().invoke(main, ["run", "clip.mp4"])
    assert (result.exit_code, result.stderr) == (130, "lptrack: interrupted\n")


def test_lptrack_debug_shows_the_traceback(workdir):
    """LPTRACK_DEBUG=1 (README) trades the one-line error for the traceback, ending in the error's class."""
    proc = subprocess.run([sys.executable, "-m", "logpolar_track", "run", "missing.mp4", "--roi", "1,2,3"],
                          capture_output=True, text=True, timeout=120, env={**os.environ, "LPTRACK_DEBUG": "1"})
    assert proc.returncode != 0 and proc.stdout == ""
    assert proc.stderr.startswith("Traceback (most recent call last):")
    assert "logpolar_track.errors.VideoError: video 'missing.mp4' not found" in proc.stderr
    assert listing(workdir) == []


def test_unknown_command_is_one_house_line():
    result = CliRunner().invoke(main, ["foo"])
    assert result.exit_code == 2
    assert result.stderr == ("lptrack: error: no command 'foo'; the commands are "
                             f"{', '.join(main.list_commands(None))} (see 'lptrack --help')\n")
    assert "run" in main.list_commands(None) and "bench" in main.list_commands(None)
    result = CliRunner().invoke(main, ["--bogus"])
    assert result.exit_code == 2
    # click's own words: "No such option '--bogus'." from click 8.2, "No such option: --bogus" in 8.1.
    assert result.stderr in ("lptrack: error: No such option '--bogus'. (see 'lptrack --help')\n",
                             "lptrack: error: No such option: --bogus (see 'lptrack --help')\n")


def test_a_video_whose_name_starts_with_a_dash_is_told_how_to_name_it(tiny_video, workdir):
    shutil.copy(tiny_video.path, workdir / "-clip.mp4")
    result = invoke("-clip.mp4", "--roi", "80,60,20")
    assert result.exit_code == 2 and listing(workdir) == ["-clip.mp4"]
    assert result.stderr.startswith("lptrack: error: No such option")
    assert result.stderr.endswith("; for the file '-clip.mp4' give ./-clip.mp4 or -- -clip.mp4 (see 'lptrack run "
                                  "--help')\n")
    result = invoke("--roi", "80,60,20", "--no-video", "--", "-clip.mp4")
    assert result.exit_code == 0 and listing(workdir) == ["-clip.lptrack.csv", "-clip.mp4"]
    assert "for the file" not in invoke("-x", tiny_video.path).stderr  # an option mistyped, no such file
    # another option mistyped, the file an option's value: no hint about it
    shutil.copy(tiny_video.path, workdir / "-old.csv")
    assert "for the file" not in invoke(tiny_video.path, "--csv", "-old.csv", "--bogus").stderr


def test_cli_keeps_opencv_warnings_off_stderr():
    # One warning per frame when a disk fills up would bury lptrack's own message; the package imports cv2
    # before the CLI module runs, so the level must be set through OpenCV's API.
    code = "import logpolar_track.cli; from logpolar_track import cv_compat; print(cv_compat.get_log_level())"
    env = {k: v for k, v in os.environ.items() if k != "OPENCV_LOG_LEVEL"}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=60)
    from logpolar_track import cv_compat

    assert int(proc.stdout) == cv_compat.LOG_LEVEL_ERROR == 2, proc.stderr  # cv::utils::logging::LOG_LEVEL_ERROR


def test_a_run_whose_csv_fails_at_the_end_leaves_no_video(tiny_video, workdir, monkeypatch):
    from logpolar_track.errors import OutputError
    from logpolar_track.results import CsvWriter

    def fail(self):
        raise OutputError("cannot write output CSV: No space left on device")

    monkeypatch.setattr(CsvWriter, "close", fail)
    result = invoke(tiny_video.path)
    assert result.exit_code == 1 and "No space left" in result.stderr
    assert listing(workdir) == []  # the finished video was removed with it: all outputs or none


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_stdout_that_cannot_be_written_is_one_line(tiny_video, workdir):
    with open("/dev/full", "w") as full:
        proc = subprocess.run([sys.executable, "-m", "logpolar_track", "run", str(tiny_video.path), "--no-video",
                               "--csv", "-"], stdout=full, stderr=subprocess.PIPE, text=True, timeout=120)
    assert proc.returncode == 1
    assert proc.stderr.strip() == "lptrack: error: cannot write the rows to stdout: No space left on device"


def _data_commands(tiny_video, workdir) -> dict[str, list[str]]:
    """Commands whose data goes to stdout (a ROI spec, a table, JSON, help, the version)."""
    run_csv = workdir / "run.csv"
    run_csv.write_text(",".join(COLUMNS) + "\n" + "".join(f"{i},0,1,1,1,1,0,1,0,1,tracked\n" for i in range(150)))
    gt = Path(__file__).resolve().parents[1] / "sample_videos" / "spin.gt.csv"  # 150 frames
    return {"roi": ["roi", str(tiny_video.path), "--from-box", "20,20,30,30"],
            "eval": ["eval", str(run_csv), str(gt)],
            "eval --json -": ["eval", str(run_csv), str(gt), "--json", "-"],
            "run --help": ["run", "--help"],
            "samples --help": ["samples", "--help"],
            "--version": ["--version"]}


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_every_command_writing_data_to_stdout_ends_in_one_line_or_quietly(tiny_video, workdir):
    """A full disk behind stdout is one line and exit 1, as for `run --csv -`; a reader that left (`| head`) ends
    quietly with 141; a closed stdout (`>&-`) is an error, not data lost in silence."""
    def lptrack(args, **how):
        return subprocess.run([sys.executable, "-m", "logpolar_track", *args], stderr=subprocess.PIPE, text=True,
                              timeout=120, **how)

    for name, args in _data_commands(tiny_video, workdir).items():
        assert lptrack(args, stdout=subprocess.PIPE).returncode == 0, name
        with open("/dev/full", "w") as full:
            proc = lptrack(args, stdout=full)
        assert (proc.returncode, proc.stderr) == (1, "lptrack: error: cannot write to stdout: No space left on "
                                                     "device\n"), name
        read_end, write_end = os.pipe()
        os.close(read_end)  # the reader has gone before the first write
        try:
            proc = lptrack(args, stdout=write_end)
        finally:
            os.close(write_end)
        assert (proc.returncode, proc.stderr) == (141, ""), name
    closed = {**_data_commands(tiny_video, workdir),  # and commands that print the path of a file they write
              "frame": ["frame", str(tiny_video.path), "-o", str(workdir / "f.png")],
              "eval --json FILE": [*_data_commands(tiny_video, workdir)["eval"], "--json", str(workdir / "m.json")],
              "bench --json -": ["bench", "--dataset", str(Path(__file__).resolve().parents[1] / "sample_videos"),
                                 "--trackers", "fixed", "--json", "-"]}
    for name, args in closed.items():
        proc = lptrack(args, preexec_fn=lambda: os.close(1))
        assert (proc.returncode, proc.stderr) == (1, "lptrack: error: cannot write to stdout: it is closed\n"), name
    assert not (workdir / "f.png").exists() and not (workdir / "m.json").exists()  # refused before the work
    # The rows of a run: refused before the work, and no annotated video is left behind.
    proc = lptrack(["run", str(tiny_video.path), "--csv", "-"], preexec_fn=lambda: os.close(1))
    assert (proc.returncode, proc.stderr) == (1, "lptrack: error: cannot write the rows to stdout: it is closed\n")
    assert [name for name in listing(workdir) if ".mp4" in name] == []


def test_jobs_and_scheduler_contradict_each_other(tiny_video, workdir):
    result = invoke(tiny_video.path.parent, "--scheduler", "tcp://127.0.0.1:1", "--jobs", "2", "--no-video")
    assert result.exit_code == 2 and "--jobs and --scheduler contradict each other" in result.stderr
    result = CliRunner().invoke(main, ["bench", "--scheduler", "tcp://127.0.0.1:1", "--jobs", "1"])
    assert result.exit_code == 2 and "--jobs and --scheduler contradict each other" in result.stderr


def test_a_csv_named_as_a_video_is_refused_before_any_work(tiny_video, workdir):
    for name in ("out.mp4", "out.PNG"):
        result = invoke(tiny_video.path, "--no-video", "--csv", name)
        assert result.exit_code == 2
        assert f"cannot write the CSV to '{name}'" in result.stderr and "name it .csv (or .jsonl)" in result.stderr
    assert listing(workdir) == []


@pytest.mark.skipif(not os.path.exists("/dev/stdout"), reason="needs /dev/stdout")
def test_csv_to_dev_stdout_redirected_to_a_file_is_written_not_replaced(tiny_video, workdir):
    # /dev/stdout links to the open file: renaming a finished temporary file over it would replace the link.
    with open(workdir / "rows.csv", "w") as rows:
        proc = subprocess.run([sys.executable, "-m", "logpolar_track", "run", str(tiny_video.path), "--no-video",
                               "--csv", "/dev/stdout"], stdout=rows, stderr=subprocess.PIPE, text=True,
                              timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert len(read_rows((workdir / "rows.csv").read_text())) == tiny_video.n_frames
    assert os.path.islink("/dev/stdout")


def test_out_dir_that_cannot_be_made_is_one_line_for_a_batch_too(tiny_video, workdir):
    (workdir / "afile").write_text("")
    result = invoke(tiny_video.path.parent, "--out-dir", "afile/sub")
    assert result.exit_code == 1
    assert result.stderr.strip() == "lptrack: error: cannot create output folder 'afile/sub': 'afile' is a file, " \
                                    "not a folder"


def test_scheduler_with_one_video_runs_it_as_a_batch(tiny_video, workdir):
    result = invoke(tiny_video.path, "--scheduler", "tcp://127.0.0.1:1", "--out", "x.mp4")
    assert result.exit_code == 2 and "with --scheduler give --out-dir DIR" in result.stderr


def test_roi_sidecar_comments_and_ambiguities(tmp_path):
    """``#`` starts a comment anywhere on a line; a sidecar with two ROIs, or two sidecars that disagree, is an
    error naming the files, not a silent choice."""
    video = tmp_path / "clip.mp4"
    (tmp_path / "clip.roi").write_text("10,20,30  # the ball\n\n")
    assert read_roi_sidecar(video) == Ellipse.circle(10, 20, 30)
    (tmp_path / "clip.mp4.roi").write_text("10,20,30\n")  # the same ROI twice is no ambiguity
    assert read_roi_sidecar(video) == Ellipse.circle(10, 20, 30)
    (tmp_path / "clip.mp4.roi").write_text("10,20,31\n")
    with pytest.raises(RoiError, match="clip.roi.*clip.mp4.roi.*disagree"):
        read_roi_sidecar(video)
    (tmp_path / "clip.mp4.roi").unlink()
    (tmp_path / "clip.roi").write_text("10,20,30\n# next\n40,50,10\n")
    with pytest.raises(RoiError, match=r"clip.roi' holds 2 lines \(lines 1, 3\); write one line"):
        read_roi_sidecar(video)
    (tmp_path / "clip.roi").write_text("# nothing yet\n")
    with pytest.raises(RoiError, match="clip.roi' is empty"):
        read_roi_sidecar(video)
    (tmp_path / "clip.roi").write_bytes(b"\xc3\x28garbage")  # unreadable input (exit 1), not a bad ROI (2)
    with pytest.raises(LptrackError, match="cannot read ROI file") as info:
        read_roi_sidecar(video)
    assert info.value.exit_code == 1


class ThreadsSeen(Still):
    """:class:`Still`, noting OpenCV's thread count at each update."""

    def __init__(self):
        self.seen = []

    def update(self, frame):
        self.seen.append(cv2.getNumThreads())
        return super().update(frame)


def test_run_video_tracks_with_one_opencv_thread_and_restores_the_setting(tiny_video, tmp_path, two_opencv_threads):
    before = cv2.getNumThreads()
    assert before == two_opencv_threads
    tracker = ThreadsSeen()
    run_video(tiny_video.path, "80,60,20", tracker=tracker, csv_out=tmp_path / "t.csv")
    assert set(tracker.seen) == {1} and cv2.getNumThreads() == before
    tracker = ThreadsSeen()
    run_video(tiny_video.path, "80,60,20", tracker=tracker, csv_out=tmp_path / "u.csv", threads=None)
    assert set(tracker.seen) == {before}


# -- image sequences --------------------------------------------------------------------------------------------
@pytest.fixture
def image_sequence(tiny_video, tmp_path):
    """``tiny_video``'s frames as ``shots/frame_0001.png`` ... (numbered from 1, as OTB's are): its pattern."""
    folder = tmp_path / "shots"
    folder.mkdir()
    for number, frame in enumerate(tiny_video.frames, start=1):
        cv2.imwrite(str(folder / f"frame_{number:04d}.png"), frame)
    return folder / "frame_%04d.png"


def test_an_image_sequence_runs_like_a_video(tiny_video, image_sequence, workdir):
    result = invoke(image_sequence, "--roi", "80,60,20")
    assert result.exit_code == 0, result.stderr
    # Named after the pattern without its number; no frame rate of its own, so 25 fps is assumed, and said.
    assert listing(workdir) == ["frame.lptrack.csv", "frame.lptrack.mp4"]
    assert (f"lptrack: warning: '{image_sequence}' reports no frame rate; assumed 25 fps for time_s and the "
            f"output video") in result.stderr
    rows = read_rows((workdir / "frame.lptrack.csv").read_text())
    assert [int(r["frame"]) for r in rows] == list(range(tiny_video.n_frames))  # frame 0 is frame_0001.png
    assert float(rows[-1]["time_s"]) == pytest.approx(19 / 25.0, abs=1e-6)
    assert {r["status"] for r in rows[1:]} == {"tracked"}
    assert np.median(centre_errors(rows, tiny_video.poses)) < 1.0
    assert count_frames(workdir / "frame.lptrack.mp4")[:2] == (tiny_video.n_frames, tiny_video.size)
    # Without an output video the rate is only the times'.
    result = invoke(image_sequence, "--roi", "80,60,20", "--no-video", "--csv", "-")
    assert result.exit_code == 0, result.stderr
    assert (f"lptrack: warning: '{image_sequence}' reports no frame rate; assumed 25 fps for time_s (give --fps to "
            "set it)\n"
            in result.stderr)
    # The summary names the pattern with its folder (the pattern alone says little).
    assert "\nlptrack: shots/frame_%04d.png: 20 frames (0 lost) with lpcf" in result.stderr


def test_an_image_sequence_reads_its_roi_sidecar_and_goes_through_a_batch(tiny_video, image_sequence, workdir):
    image_sequence.with_name("frame.roi").write_text("80,60,20\n")
    result = invoke(image_sequence, tiny_video.path, "--no-video", "--out-dir", "tracks", "-q")
    assert result.exit_code == 0, result.stderr
    assert sorted(p.name for p in (workdir / "tracks").rglob("*.csv")) == ["frame.lptrack.csv", "tiny.lptrack.csv"]
    rows = read_rows(next((workdir / "tracks").rglob("frame.lptrack.csv")).read_text())
    assert len(rows) == tiny_video.n_frames and (rows[0]["cx"], rows[0]["a"]) == ("80.000", "20.000")
    # The rate assumed for the sequence is said in a batch too (it was said for single runs only).
    result = invoke(image_sequence, tiny_video.path, "--no-video", "--out-dir", "again")
    assert result.exit_code == 0, result.stderr
    assert (f"lptrack: warning: '{image_sequence}' reports no frame rate; assumed 25 fps for time_s (give --fps to "
            f"set it)\n") in result.stderr
    assert result.stderr.count("reports no frame rate") == 1


def test_an_image_sequence_whose_numbers_skip_is_warned_of_once(image_sequence, workdir):
    """bench said that image numbers skip, run did not: frames are the images in number order (README), so from a
    missing number on, a frame's number is not its image's."""
    for number in (3, 7, 8):
        image_sequence.with_name(f"frame_{number:04d}.png").unlink()
    result = invoke(image_sequence, "--roi", "80,60,20", "--no-video", "--csv", "-")
    assert result.exit_code == 0, result.stderr
    assert [int(r["frame"]) for r in read_rows(result.stdout)] == list(range(17))  # numbers kept as documented
    warning = ("lptrack: warning: shots/frame_%04d.png: image numbers skip from frame_0002.png to frame_0004.png (and "
               "1 more gap); frames are the images in number order, so frame 2 is frame_0004.png")
    assert result.stderr.splitlines().count(warning) == 1
    # In a batch too, once.
    batch = invoke(image_sequence, image_sequence, "--roi", "80,60,20", "--no-video", "--out-dir", "out", "--jobs", "1")
    assert batch.exit_code == 0, batch.stderr
    assert batch.stderr.count("image numbers skip") == 1


def test_a_folder_of_images_given_as_the_video_is_told_its_pattern(image_sequence, workdir):
    result = invoke(image_sequence.parent, "--roi", "80,60,20")
    assert result.exit_code == 2
    assert result.stderr == (f"lptrack: error: no videos found in '{image_sequence.parent}' (folders are searched "
                             f"for .mp4, .m4v, .mov, .avi, .mkv, ... files; for an image sequence give its "
                             f"images' pattern, e.g. '{image_sequence}')\n")
    assert listing(workdir) == []


def test_a_pattern_that_matches_no_image_is_one_line(image_sequence, workdir):
    result = invoke(image_sequence.with_name("frame_%03d.png"), "--roi", "80,60,20")
    assert result.exit_code == 1
    assert result.stderr == (f"lptrack: error: no images match '{image_sequence.with_name('frame_%03d.png')}': "
                             f"%03d stands for the frame number, e.g. '{image_sequence.with_name('frame_001.png')}'\n")
    assert listing(workdir) == []


def test_fps_sets_the_rate_of_an_image_sequence_and_overrides_a_videos(tiny_video, image_sequence, workdir):
    result = invoke(image_sequence, "--roi", "80,60,20", "--fps", "12.5")
    assert result.exit_code == 0, result.stderr
    assert "warning" not in result.stderr  # the rate was given: nothing was assumed
    rows = read_rows((workdir / "frame.lptrack.csv").read_text())
    assert [float(r["time_s"]) for r in rows] == pytest.approx([i / 12.5 for i in range(tiny_video.n_frames)])
    assert count_frames(workdir / "frame.lptrack.mp4")[2] == pytest.approx(12.5, abs=0.01)
    # A video's own rate (30) gives way too, in one process and in a batch.
    result = invoke(tiny_video.path, "--fps", "10", "--no-video", "--csv", "-", "-q")
    assert float(read_rows(result.stdout)[-1]["time_s"]) == pytest.approx(1.9)
    result = invoke(tiny_video.path, image_sequence, "--roi", "80,60,20", "--fps", "10", "--no-video", "--csv", "-",
                    "-q")
    assert result.exit_code == 0, result.stderr
    assert [float(r["time_s"]) for r in read_rows(result.stdout) if r["frame"] == "19"] == pytest.approx([1.9, 1.9])


@pytest.mark.parametrize("rate", ["0", "-5", "nan", "inf", "1e-300", "2e6"])
def test_a_frame_rate_that_is_not_a_positive_number_is_refused(tiny_video, image_sequence, workdir, rate):
    for inputs in ((image_sequence,), (image_sequence, tiny_video.path)):
        result = invoke(*inputs, "--roi", "80,60,20", "--fps", rate)
        assert result.exit_code == 2
        assert result.stderr == (f"lptrack: error: the frame rate must be a positive number of frames per second, "
                                 f"from 0.001 to 1,000,000, got {float(rate):g}\n")
        assert listing(workdir) == []


def test_a_roi_sidecar_saved_with_a_byte_order_mark_is_read(tiny_video, workdir):
    """Notepad saves UTF-8 with a BOM; it showed as an invisible character in 'is not a list of numbers'."""
    tiny_video.path.with_suffix(".roi").write_text("\ufeff80,60,20\r\n", encoding="utf-8")
    result = invoke(tiny_video.path, "--no-video", "--csv", "-", "--frames", "2")
    assert result.exit_code == 0, result.stderr
    assert read_rows(result.stdout)[0]["cx"] == "80.000"


@pytest.mark.parametrize("encoding", ["utf-16-le", "utf-16-be"])
def test_roi_files_saved_as_utf16_are_read(tiny_video, workdir, encoding):
    """Windows PowerShell 5's ``echo 80,60,20 > tiny.roi`` writes UTF-16 with a byte-order mark: a sidecar and a
    --roi-file so saved are read as UTF-8 ones are (the codec's own message was shown)."""
    tiny_video.path.with_suffix(".roi").write_bytes(("\ufeff80,60,20\r\n").encode(encoding))
    result = invoke(tiny_video.path, "--no-video", "--csv", "-", "--frames", "2")
    assert result.exit_code == 0, result.stderr
    assert read_rows(result.stdout)[0]["cx"] == "80.000"
    tiny_video.path.with_suffix(".roi").unlink()
    roi_file = workdir / "rois.csv"
    roi_file.write_bytes(f"\ufeff{tiny_video.path},70,50,20\r\n".encode(encoding))
    result = invoke("--roi-file", roi_file, "--no-video", "--csv", "-", "--frames", "2")
    assert result.exit_code == 0, result.stderr
    assert read_rows(result.stdout)[0]["cx"] == "70.000"


@pytest.mark.parametrize("data", [b"\xc3\x28\x00\x01", "80,60,20\n".encode("utf-16-le")])
def test_a_roi_file_that_is_not_text_is_one_line(tiny_video, workdir, data):
    # UTF-16 without a byte-order mark is valid UTF-8 with NULs between the digits: it was "'8 0 ' is not a number",
    # NULs written to the terminal.
    tiny_video.path.with_suffix(".roi").write_bytes(data)
    result = invoke(tiny_video.path, "--no-video", "--csv", "-", "--frames", "2")
    assert result.exit_code == 1
    assert result.stderr == (f"lptrack: error: cannot read ROI file '{tiny_video.path.with_suffix('.roi')}': it is "
                             f"not text in UTF-8 (nor UTF-16 with a byte-order mark); save it as UTF-8\n")


def test_a_video_written_under_another_name_is_said_under_quiet_too(tiny_video, workdir):
    """mp4v takes no rate of 65536 fps or more: the annotated video falls back to MJPG in .avi, which a script
    that named out.mp4 must hear of even with -q."""
    result = invoke(tiny_video.path, "-o", "out.mp4", "--fps", "65536", "-q", "--frames", "2")
    assert result.exit_code == 0
    assert result.stderr == "lptrack: warning: could not write 'out.mp4'; wrote 'out.avi' (MJPG) instead\n"
    assert Path("out.avi").is_file() and not Path("out.mp4").exists()


def test_fps_takes_a_fraction_as_ffmpeg_does(tiny_video, workdir):
    result = invoke(tiny_video.path, "--no-video", "--csv", "-", "--frames", "3", "--fps", "30000/1001")
    assert result.exit_code == 0 and read_rows(result.stdout)[2]["time_s"] == "0.066733"
    bad = invoke(tiny_video.path, "--no-video", "--csv", "-", "--fps", "30/0")
    assert bad.exit_code == 2 and "'30/0' is not a frame rate; give frames per second as a number" in bad.stderr


def test_a_roi_on_a_flat_area_gets_a_warning(tmp_path, workdir):
    """A ROI on a letterbox bar: every frame is lost, and the summary says why."""
    rng = np.random.default_rng(0)
    path = tmp_path / "bars.mp4"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 25.0, (160, 120))
    for _ in range(5):
        frame = np.zeros((120, 160, 3), np.uint8)
        frame[:, 80:] = rng.integers(0, 255, (120, 80, 3))
        writer.write(frame)
    writer.release()
    flat = invoke(path, "--roi", "30,60,15", "--no-video")
    assert flat.exit_code == 0
    assert "warning: bars.mp4: the ROI covers a flat area on its start frame (one colour" in flat.stderr
    textured = invoke(path, "--roi", "120,60,15", "--no-video", "--overwrite")
    assert textured.exit_code == 0 and "flat area" not in textured.stderr


class _DroppedFrames:
    """A capture of the tiny video (30 fps) whose stream timestamps say that 10 frames were dropped after frame 9
    (a phone slowing down): frame k >= 10 is stamped (k + 10) / 30 s. Composition: cv2 classes are unsafe to
    subclass."""

    def __init__(self, path):
        self._cap = cv2.VideoCapture(str(path))
        self._read = 0

    def read(self):
        ok, frame = self._cap.read()
        self._read += ok
        return ok, frame

    def grab(self):
        ok = self._cap.grab()
        self._read += ok
        return ok

    def get(self, prop):
        if prop == cv2.CAP_PROP_POS_MSEC:
            index = self._read - 1
            return (index + (10 if index >= 10 else 0)) * 1000.0 / 30.0
        return self._cap.get(prop)

    def __getattr__(self, name):
        return getattr(self._cap, name)


def test_a_varying_frame_rate_is_timed_by_the_streams_timestamps(tiny_video, workdir, monkeypatch):
    import logpolar_track.video as video_module

    monkeypatch.setattr(video_module, "_open_capture", _DroppedFrames)
    result = invoke(tiny_video.path, "--no-video", "--csv", "-")
    assert result.exit_code == 0, result.stderr
    times = [row["time_s"] for row in read_rows(result.stdout)]
    assert times[9] == "0.300000" and times[10] == "0.666667" and times[19] == "0.966667"
    assert ("note: tiny.mp4's frame rate varies: time_s follows its timestamps from frame 10 on (before, frame / "
            "30 fps kept to them)") in result.stderr
    # From a start frame past the change, times still count from frame 0.
    later = invoke(tiny_video.path, "--no-video", "--csv", "-", "--start-frame", "12")
    assert read_rows(later.stdout)[0]["time_s"] == "0.733333"
    assert "tiny.mp4's frame rate varies: time_s follows its timestamps, not frame / 30 fps" in later.stderr
    # --fps keeps frame / fps; a batch says it too.
    given = invoke(tiny_video.path, "--no-video", "--csv", "-", "--fps", "30")
    assert read_rows(given.stdout)[10]["time_s"] == "0.333333" and "varies" not in given.stderr
    batch = invoke(tiny_video.path, tiny_video.path.parent, "--no-video", "--out-dir", "out", "--jobs", "1")
    assert "tiny.mp4's frame rate varies: time_s follows its timestamps from frame 10 on" in batch.stderr


def test_a_frame_at_a_time_of_a_varying_rate_is_found_by_its_timestamps(tiny_video, monkeypatch):
    """lptrack frame --time: frame 11 is at (11 + 10) / 30 = 0.7 s by its stamp (round(0.7 x 30) = 21 lies past
    the end of the 20 frames), and its caption's time is the run's."""
    import logpolar_track.video as video_module
    from logpolar_track.video import read_frame

    monkeypatch.setattr(video_module, "_open_capture", _DroppedFrames)
    frame = read_frame(tiny_video.path, time_s=0.7)
    assert frame.index == 11 and frame.time_s == pytest.approx(0.7)
    assert read_frame(tiny_video.path, time_s=0.45).index == 9  # 0.3 s is nearer than frame 10's 0.667 s
    assert read_frame(tiny_video.path, 11).time_s == pytest.approx(0.7)


def test_a_damaged_stretch_is_passed_over_and_said_which_frames_have_no_row(make_video, tmp_path, workdir):
    """A video damaged in the middle ended the run there, with "truncated?"; the rest of it is tracked now."""
    clip = make_video(tmp_path, "clip.mp4", n_frames=60)
    damage_middle(clip.path)
    with VideoReader(clip.path) as reader:
        for _ in reader:
            pass
    (first, count), = reader.undecodable
    result = invoke(clip.path, "--no-video", "--csv", "-")
    assert result.exit_code == 0, result.stderr
    rows = read_rows(result.stdout)
    assert [int(r["frame"]) for r in rows] == [i for i in range(60) if not first <= i < first + count]
    assert float(rows[-1]["time_s"]) == pytest.approx(59 / clip.fps, abs=1e-6)
    lines = result.stderr.splitlines()
    assert lines[0] == (f"lptrack: warning: clip.mp4: {count} frames could not be decoded (the file is damaged there) "
                        f"and have no row: {first}-{first + count - 1}; tracking went on after them")
    assert len(lines) == 2 and lines[1].startswith(f"lptrack: clip.mp4: {60 - count} frames (")


#: Test videos made by tests/data/make_counter_h264.py: 40 frames of 64x48 at 25 fps, each showing its number.
DATA = Path(__file__).parent / "data"


def test_a_run_over_damaged_h264_numbers_and_times_its_rows_by_their_frames(workdir):
    """H.264 with B-frames, frames 14-18 lost (tests/data/damaged_h264.mp4). The failures FFmpeg reports before the
    frames its decoder held come out were counted as frames: rows 10-12, 17 and 18 were frames 9-13, row 17 at 0.48 s
    (frame 12's time), a note said the rate varied and the warning named frames 9 and 13-16."""
    result = invoke(DATA / "damaged_h264.mp4", "--roi", "32,24,12", "--no-video", "--csv", "-")
    assert result.exit_code == 0, result.stderr
    rows = read_rows(result.stdout)
    assert [int(r["frame"]) for r in rows] == [*range(14), *range(19, 40)]
    assert all(r["time_s"] == f"{int(r['frame']) / 25:.6f}" for r in rows)
    lines = result.stderr.splitlines()
    assert lines[0] == ("lptrack: warning: damaged_h264.mp4: 5 frames could not be decoded (the file is damaged there) "
                        "and have no row: 14-18; tracking went on after them")
    assert len(lines) == 2 and "varies" not in result.stderr
    # --fps sets the times, not the numbers (the stream's stamps, at its own rate, place the lost frames).
    given = invoke(DATA / "damaged_h264.mp4", "--roi", "32,24,12", "--no-video", "--csv", "-", "--fps", "10", "-q")
    assert [(r["frame"], r["time_s"]) for r in read_rows(given.stdout)][13:15] == [("13", "1.300000"),
                                                                                   ("19", "1.900000")]
    # From a start frame: frame 13 is frame 13 (it was refused as damaged), a lost one is refused.
    later = invoke(DATA / "damaged_h264.mp4", "--roi", "32,24,12", "--no-video", "--csv", "-", "--start-frame", "13")
    assert later.exit_code == 0, later.stderr
    assert [(r["frame"], r["time_s"]) for r in read_rows(later.stdout)[:2]] == [("13", "0.520000"), ("19", "0.760000")]
    lost = invoke(DATA / "damaged_h264.mp4", "--roi", "32,24,12", "--no-video", "--csv", "-", "--start-frame", "17")
    assert lost.exit_code != 0 and lost.stdout == ""
    assert "frame 17 of" in lost.stderr and "cannot be decoded (the file is damaged at frames 14-18)" in lost.stderr


def test_frame_at_n_of_damaged_h264_is_frame_n(workdir):
    """lptrack frame --at 10 wrote frame 9's picture, --at 17 frame 12's, and --at 13 was refused as damaged: the
    picture written is the number's."""
    pictures = {}
    for n in (10, 11, 13, 20, 39):
        result = CliRunner().invoke(main, ["frame", str(DATA / "damaged_h264.mp4"), "--at", str(n), "--grid", "0"],
                                    catch_exceptions=False)
        assert result.exit_code == 0, result.stderr
        pictures[n] = cv2.imread(result.stdout.strip())
    shown = {n: sum(1 << bit for bit in range(8)
                    if image[bit // 4 * 16 + 4:bit // 4 * 16 + 12, bit % 4 * 16 + 4:bit % 4 * 16 + 12].mean() > 128)
             for n, image in pictures.items()}
    # 13 refers to lost frame 14: FFmpeg conceals it with another picture; from the key frame at 20, its own.
    assert {n: shown[n] for n in (10, 11, 20, 39)} == {10: 10, 11: 11, 20: 20, 39: 39}
    refused = CliRunner().invoke(main, ["frame", str(DATA / "damaged_h264.mp4"), "--at", "17"])
    assert refused.exit_code != 0 and "damaged at frames 14-18" in refused.stderr


def test_a_run_over_h264_cut_short_ends_with_its_last_frame(workdir):
    """The first 70 % of the H.264 file: the packet cut in two is refused before the frames the decoder held come
    out; the last two rows were numbered 19 and 20 (frames 18 and 19), after "1 frame could not be decoded: 18"."""
    result = invoke(DATA / "truncated_h264.mp4", "--roi", "32,24,12", "--no-video", "--csv", "-")
    assert result.exit_code == 0, result.stderr
    rows = read_rows(result.stdout)
    assert [(int(r["frame"]), r["time_s"]) for r in rows] == [(i, f"{i / 25:.6f}") for i in range(20)]
    assert "could not be decoded" not in result.stderr
    assert ("lptrack: warning: truncated_h264.mp4: ended after 20 of the 40 frames its container announces"
            in result.stderr)


def test_log_progress_rate_leaves_out_the_time_before_the_first_frame(monkeypatch, capsys):
    # A minute spent seeking to --start-frame (or starting a batch's workers) kept the rate low for the whole run.
    from logpolar_track.cli import run as cli_run

    clock = [100.0]
    monkeypatch.setattr(cli_run.time, "monotonic", lambda: clock[0])
    log = cli_run._LogProgress("clip.mp4")
    clock[0] = 160.0
    log(1, 1000)
    clock[0] = 200.0
    log(401, 1000)
    assert capsys.readouterr().err.splitlines()[-1] == "lptrack: clip.mp4: 401 of 1000 frames (40 %), 10 frames/s"
