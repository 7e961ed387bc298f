"""``lptrack bench`` and ``lptrack eval`` end to end on tiny generated sequences with exact ground truth."""

from __future__ import annotations

import json
import math
import os
import pickle
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest
from conftest import CliRunner

from logpolar_track.bench import (evaluate_run, format_paired, mean_over_starts, paired_differences, run_bench, run_one,
                                  start_roi)
from logpolar_track.errors import OutputError, UsageError
from logpolar_track.cli import main
from logpolar_track.datasets import discover
from logpolar_track.geometry import Ellipse, parse_roi
from logpolar_track.results import COLUMNS
from logpolar_track.synthetic import Pose, similarity_path, synthetic_sequence
from logpolar_track.trackers import base
from logpolar_track.trackers.base import Tracker, TrackState
from logpolar_track.trackers.opencv import CSRTTracker, KCFTracker

N_FRAMES = 12
_TRUTH: dict[str, list] = {}  # ROI spec -> per-frame ellipses, scales, rotations (for the oracle below)


def _write_sequence(folder: Path, name: str, start, seed: int) -> None:
    roi = Ellipse(start[0], start[1], 18.0, 14.0, 20.0)
    poses = similarity_path(N_FRAMES, start, scale_range=(0.9, 1.15), turns=0.1, radius_px=6.0)
    frames = list(synthetic_sequence(poses, roi, size=(160, 120), seed=seed, noise=1.0))
    writer = cv2.VideoWriter(str(folder / f"{name}.avi"), cv2.VideoWriter_fourcc(*"MJPG"), 25.0, (160, 120))
    assert writer.isOpened(), "test set-up: cannot open an MJPG writer"
    for f in frames:
        writer.write(f)
    writer.release()
    rows, truth = [], []
    for i, p in enumerate(poses):
        e = roi.moved(p.cx, p.cy, p.scale, p.rotation_deg)
        rows.append(f"{i},{e.cx!r},{e.cy!r},{e.a!r},{e.b!r},{e.angle_deg!r},{p.scale!r},{p.rotation_deg!r}\n")
        truth.append((e, p.scale, p.rotation_deg))
    (folder / f"{name}.gt.csv").write_text("frame,cx,cy,a,b,angle_deg,scale,rotation_deg\n" + "".join(rows))
    (folder / f"{name}.roi").write_text(roi.to_spec() + "\n")
    _TRUTH[roi.to_spec()] = truth


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("bench_ds")
    _write_sequence(folder, "alpha", (70.0, 55.0), seed=1)
    _write_sequence(folder, "beta", (85.0, 62.0), seed=2)
    return folder


class _Oracle(Tracker):
    """Reports the ground truth exactly: its scores pin down the scoring, not a tracker."""

    name = "test-oracle"
    summary = "test only"

    def init(self, frame, roi):
        self.truth, self.i = _TRUTH[roi.to_spec()], 0
        return self._state()

    def update(self, frame):
        self.i += 1
        return True, self._state()

    def _state(self):
        e, s, r = self.truth[self.i]
        return TrackState(e, s, r, 1.0)


@pytest.fixture
def oracle(monkeypatch):
    monkeypatch.setitem(base._REGISTRY, _Oracle.name, _Oracle)
    return _Oracle.name


class _Boaster(_Oracle):
    """The ground truth until frame 6, then 100 px off it while still saying tracked; lost on frame 3."""

    name = "test-boaster"

    def update(self, frame):
        self.i += 1
        ok, state = self.i != 3, self._state()
        if self.i >= 6:
            e = state.ellipse
            state = TrackState(e.moved(e.cx + 100.0, e.cy), state.scale, state.rotation_deg, 1.0)
        return ok, state


def _run(*args):
    return CliRunner().invoke(main, list(map(str, args)))


def test_bench_reports_how_often_tracked_is_wrong(dataset, oracle, monkeypatch):
    monkeypatch.setitem(base._REGISTRY, _Boaster.name, _Boaster)
    res = _run("bench", "--dataset", dataset, "--trackers", f"{oracle},{_Boaster.name}", "--json", "-", "--quiet")
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    for r in doc["results"]:
        if r["tracker"] == oracle:
            assert r["lost_rate"] == 0 and r["off_tracked_rate"] == 0
        else:  # 12 frames: the first is the start, frame 3 lost, frames 6 to 11 (6 of the 10 tracked) off
            assert r["lost_rate"] == pytest.approx(1 / 12) and r["off_tracked_rate"] == pytest.approx(6 / 10)
    summary = {s["tracker"]: s for s in doc["summary"]}
    assert summary[_Boaster.name]["off_tracked_rate"] == pytest.approx(0.6)
    table = res.stderr.splitlines()  # with --json -, the table goes to stderr
    header = table[0].split()
    assert header[-3:] == ["lost%", "off_tracked%", "fps"]
    row = next(line.split() for line in table if line.startswith("mean") and _Boaster.name in line)
    assert row[header.index("lost%") + 1:header.index("off_tracked%") + 2] == ["8.3", "60.0"]


def test_bench_end_to_end_json(dataset, oracle, tmp_path):
    out = tmp_path / "bench.json"
    res = _run("bench", "--dataset", dataset, "--trackers", f"fixed,cv-mil,{oracle}", "--json", out, "--quiet")
    assert res.exit_code == 0, res.output + res.stderr
    doc = json.loads(out.read_text())
    assert doc["schema_version"] == 1 and doc["tool"] == "lptrack bench"
    assert set(doc["versions"]) >= {"lptrack", "python", "numpy", "opencv"}
    assert doc["machine"]["cpu_count"] >= 1
    assert doc["machine"]["vector_extensions"] in {None, "AVX-512", "AVX2", "AVX", "SSE4.2", "NEON"}
    assert doc["parameters"]["trackers"] == ["fixed", "cv-mil", oracle]
    assert [s["name"] for s in doc["sequences"]] == ["alpha", "beta"]
    pairs = [(r["sequence"], r["tracker"]) for r in doc["results"]]
    assert pairs == [(s, t) for s in ("alpha", "beta") for t in ("fixed", "cv-mil", oracle)]
    assert "iou" not in doc["results"][0]  # per-frame arrays only with --per-frame
    for r in doc["results"]:
        assert r["frames_scored"] == N_FRAMES and r["error"] is None and len(r["success_curve"]) == 21
        if r["tracker"] == oracle:  # exact ground truth back: every metric at its best
            assert r["success_rate"] == 1.0 and r["auc"] == pytest.approx(20 / 21)
            assert r["centre_error_median_px"] == pytest.approx(0, abs=1e-9)
            assert r["scale_error_median_pct"] == pytest.approx(0, abs=1e-9)
            assert r["rotation_error_median_deg"] == pytest.approx(0, abs=1e-9)
        if r["tracker"] == "cv-mil":
            assert r["rotation_error_median_deg"] is None and r["fps"] > 0
        if r["tracker"] == "fixed":  # a slow, gentle synthetic path: the thesis tracker keeps the object
            assert r["success_rate"] >= 0.9 and r["centre_error_median_px"] < 2.0
    summary = {s["tracker"]: s for s in doc["summary"]}
    assert summary[oracle]["auc"] == pytest.approx(20 / 21) and summary["cv-mil"]["rotation_error_median_deg"] is None
    table = res.stdout.splitlines()
    assert table[0].split()[:4] == ["sequence", "tracker", "frames", "success%"]
    assert sum(line.startswith("mean (2)") for line in table) == 3
    assert any(line.split()[:2] == ["alpha", oracle] and line.split()[3] == "100.0" for line in table)


class _ThreadsSeen(_Oracle):
    """:class:`_Oracle`, noting OpenCV's thread count at each update."""

    name = "test-threads-seen"
    seen: list = []

    def update(self, frame):
        self.seen.append(cv2.getNumThreads())
        return super().update(frame)


@pytest.mark.parametrize("args, expected", [([], 1), (["--threads", "2"], 2)])
def test_bench_runs_each_tracker_on_one_opencv_thread_unless_told(dataset, monkeypatch, tmp_path, args, expected):
    monkeypatch.setitem(base._REGISTRY, _ThreadsSeen.name, _ThreadsSeen)
    monkeypatch.setattr(_ThreadsSeen, "seen", [])
    previous = cv2.getNumThreads()
    cv2.setNumThreads(3)
    try:
        res = _run("bench", "--dataset", dataset, "--trackers", _ThreadsSeen.name, "--json", tmp_path / "b.json",
                   "-q", *args)
        assert cv2.getNumThreads() == 3  # restored
    finally:
        cv2.setNumThreads(previous)
    assert res.exit_code == 0, res.stderr
    assert set(_ThreadsSeen.seen) == {expected} and len(_ThreadsSeen.seen) == 2 * (N_FRAMES - 1)
    assert json.loads((tmp_path / "b.json").read_text())["parameters"]["opencv_threads"] == expected


class _Tuned(_Oracle):
    """:class:`_Oracle` with two tuning parameters, noting the values it was made with."""

    name = "test-tuned"
    made: list = []

    def __init__(self, *, gain: float = 1.0, steps: int = 3):
        self.made.append((gain, steps))


def test_bench_param_tunes_the_trackers_that_take_it(dataset, monkeypatch, tmp_path):
    monkeypatch.setitem(base._REGISTRY, _Tuned.name, _Tuned)
    monkeypatch.setattr(_Tuned, "made", [])
    res = _run("bench", "--dataset", dataset, "--trackers", f"{_Tuned.name},cv-mil", "--param", "gain=2.5",
               "--param", "steps=4", "--json", tmp_path / "b.json", "-q")
    assert res.exit_code == 0, res.stderr
    # Made once when the values were checked, then once per sequence; the numbers typed as the defaults are.
    assert _Tuned.made == [(2.5, 4)] * 3 and type(_Tuned.made[1][1]) is int
    doc = json.loads((tmp_path / "b.json").read_text())
    assert doc["parameters"]["tracker_params"] == {_Tuned.name: {"gain": 2.5, "steps": 4}}
    assert all(r["error"] is None for r in doc["results"])


def test_bench_json_to_stdout_is_only_json(dataset, tmp_path):
    res = _run("bench", "--dataset", dataset, "--trackers", "cv-mil", "--json", "-", "--per-frame", "-q")
    assert res.exit_code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert len(doc["results"][0]["iou"]) == N_FRAMES
    assert "mean (2)" in res.stderr  # the table went to stderr
    # Without a JSON to hold them the arrays went nowhere, and nothing said so.
    res = _run("bench", "--dataset", dataset, "--trackers", "cv-mil", "--per-frame", "-q")
    assert res.exit_code == 2 and res.stdout == ""
    assert res.stderr == ("lptrack: error: --per-frame adds per-frame arrays to the JSON; give --json PATH "
                          "(or --json -) too\n")


def test_bench_keeps_its_figures_when_its_json_name_was_taken_or_stdout_fails(dataset, oracle, tmp_path, monkeypatch):
    # A long run whose --json name another run wrote meanwhile lost everything (no table, no JSON): the table is on
    # stdout and the JSON beside the other's, named in the error.
    from logpolar_track.cli import bench as cli_bench

    out = tmp_path / "b.json"
    real_run_bench = _another_run_writes(out, monkeypatch)
    res = _run("bench", "--dataset", dataset, "--trackers", oracle, "--json", out, "-q")
    assert res.exit_code == 1
    assert res.stderr == (f"lptrack: error: JSON output '{out}' already exists (written while this run went on); use "
                          f"--overwrite to replace it; this run's JSON is in '{tmp_path / 'b.1.json'}'\n")
    assert "mean (2)" in res.stdout and out.read_text() == "the other run's\n"
    assert json.loads((tmp_path / "b.1.json").read_text())["parameters"]["trackers"] == [oracle]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.1.json", "b.json"]
    # The JSON is written before the table: stdout failing (`> /dev/full`, a reader gone) does not lose it.
    monkeypatch.setattr(cli_bench, "run_bench", real_run_bench)

    def stdout_full(text):
        raise OutputError("cannot write to stdout: No space left on device")

    monkeypatch.setattr(cli_bench, "write_stdout", stdout_full)
    res = _run("bench", "--dataset", dataset, "--trackers", oracle, "--json", tmp_path / "c.json", "-q")
    assert (res.exit_code, res.stderr) == (1, "lptrack: error: cannot write to stdout: No space left on device\n")
    assert json.loads((tmp_path / "c.json").read_text())["parameters"]["trackers"] == [oracle]


def _another_run_writes(out, monkeypatch):
    """Make ``lptrack bench`` find its --json name ``out`` taken (another run's JSON written) once its runs are done;
    returns the real ``run_bench``."""
    from logpolar_track.cli import bench as cli_bench

    real_run_bench = cli_bench.run_bench

    def run_bench_while_another_writes(*args, **kwargs):
        results = real_run_bench(*args, **kwargs)
        out.write_text("the other run's\n")
        return results

    monkeypatch.setattr(cli_bench, "run_bench", run_bench_while_another_writes)
    return real_run_bench


def test_bench_still_draws_its_plot_when_its_json_cannot_be_written(dataset, oracle, tmp_path, monkeypatch):
    # A --json name taken while the run went on stopped bench before its --plot was drawn: the plot was lost, and
    # the one error line named only the JSON.
    pytest.importorskip("matplotlib")
    from logpolar_track.cli import bench as cli_bench

    out, png = tmp_path / "b.json", tmp_path / "b.png"
    _another_run_writes(out, monkeypatch)
    res = _run("bench", "--dataset", dataset, "--trackers", oracle, "--json", out, "--plot", png, "-q")
    assert res.exit_code == 1
    assert res.stderr == (f"lptrack: error: JSON output '{out}' already exists (written while this run went on); use "
                          f"--overwrite to replace it; this run's JSON is in '{tmp_path / 'b.1.json'}'\n")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.1.json", "b.json", "b.png"]
    # Both taken: each output's error is said, the JSON's last.
    out.unlink()

    def plot_taken(*args, **kwargs):
        raise OutputError(f"plot '{png}' already exists (written while this run went on); use --overwrite to "
                          f"replace it")

    monkeypatch.setattr(cli_bench, "plot_curves", plot_taken)
    res = _run("bench", "--dataset", dataset, "--trackers", oracle, "--json", out, "--plot", tmp_path / "c.png", "-q")
    assert res.exit_code == 1
    assert res.stderr.splitlines() == [
        f"lptrack: error: plot '{png}' already exists (written while this run went on); use --overwrite to replace it",
        f"lptrack: error: JSON output '{out}' already exists (written while this run went on); use --overwrite to "
        f"replace it; this run's JSON is in '{tmp_path / 'b.2.json'}'"]


def test_run_bench_takes_a_whole_number_of_starts(dataset):
    for starts in (1.5, True, 0, 34):
        with pytest.raises(UsageError, match=f"starts must be a whole number from 1 to 33, got {starts!r}"):
            run_bench(discover(dataset), ["fixed"], starts=starts)


def test_run_bench_in_processes_keeps_order_and_numbers(dataset):
    seqs = discover(dataset)
    pickle.dumps((seqs, run_one))  # what a process pool (or a Dask cluster) has to ship
    one = run_bench(seqs, ["fixed", "cv-mil"], jobs=1)
    two = run_bench(seqs, ["fixed", "cv-mil"], jobs=2)
    again = run_bench(seqs[::-1], ["cv-mil"], jobs=2)
    assert [(r["sequence"], r["tracker"]) for r in two] == [(r["sequence"], r["tracker"]) for r in one]
    for a, b in zip(one, two):
        if a["tracker"] == "fixed":  # deterministic in any process
            assert a["iou"] == b["iou"] and a["centre_error_px"] == b["centre_error_px"]
    # MIL (random inside OpenCV) repeats exactly with a fresh process per pair, whatever the order.
    mil = {r["sequence"]: r["iou"] for r in two if r["tracker"] == "cv-mil"}
    assert {r["sequence"]: r["iou"] for r in again} == mil


def test_bench_on_a_dask_cluster_gives_the_same_numbers(dataset):
    distributed = pytest.importorskip("dask.distributed")
    local = _run("bench", "--dataset", dataset, "--trackers", "fixed", "--json", "-", "-q")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, protocol="tcp",
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        remote = _run("bench", "--dataset", dataset, "--trackers", "fixed", "--json", "-", "-q",
                      "--scheduler", cluster.scheduler_address)
    assert local.exit_code == remote.exit_code == 0, remote.stderr
    local_doc, remote_doc = json.loads(local.stdout), json.loads(remote.stdout)
    assert remote_doc["parameters"]["scheduler"] == cluster.scheduler_address
    for a, b in zip(local_doc["results"], remote_doc["results"]):
        assert (a["sequence"], a["auc"], a["centre_error_median_px"]) == (b["sequence"], b["auc"],
                                                                         b["centre_error_median_px"])


@pytest.mark.parametrize("cpuinfo, expected", [
    ("processor\t: 0\nflags\t\t: fpu sse4_2 avx avx2 fma avx512f avx512bw\n", "AVX-512"),
    ("processor\t: 0\nflags\t\t: fpu sse4_2 avx avx2 fma\n", "AVX2"),
    ("processor\t: 0\nFeatures\t: fp asimd evtstrm aes\n", "NEON"),
    ("processor\t: 0\nflags\t\t: fpu mmx\n", None),
    (None, None),  # no /proc/cpuinfo
])
def test_vector_extensions_name_the_widest_the_cpu_reports(tmp_path, cpuinfo, expected):
    from logpolar_track.bench import vector_extensions

    fake = tmp_path / "cpuinfo"
    if cpuinfo is not None:
        fake.write_text(cpuinfo)
    assert vector_extensions(fake) == expected


def test_start_rois_are_otbs_spatial_robustness_starts():
    """Start 0 is the ground truth's ROI; 1-8 shift it by 10 % of its bounding box (sides, then corners), 9-12
    scale it by 0.8, 0.9, 1.1 and 1.2 about its centre (OTB's SRE), keeping its angle; 13-32 are 20 more."""
    roi = Ellipse(100.0, 80.0, 20.0, 10.0, 0.0)  # bounding box 40 x 20 px
    assert start_roi(roi, 0) == roi
    centres = [start_roi(roi, k).centre for k in range(1, 9)]
    assert centres == [pytest.approx(c) for c in [(96, 80), (104, 80), (100, 78), (100, 82),
                                                  (96, 78), (104, 78), (96, 82), (104, 82)]]
    assert [(start_roi(roi, k).a, start_roi(roi, k).b) for k in range(9, 13)] == [
        pytest.approx((16, 8)), pytest.approx((18, 9)), pytest.approx((22, 11)), pytest.approx((24, 12))]
    tilted = Ellipse(100.0, 80.0, 20.0, 10.0, 90.0)  # axis a upright: bounding box 20 x 40 px
    moved = start_roi(tilted, 8)
    assert moved.centre == pytest.approx((102, 84)) and moved.angle_deg == 90.0
    # 13-32: more starts of the same kind, within 8 % of the box and 0.9 to 1.1 of its size, all different.
    more = [start_roi(roi, k) for k in range(13, 33)]
    assert all(abs(e.cx - 100) <= 0.08 * 40 and abs(e.cy - 80) <= 0.08 * 20 and 0.9 <= e.a / 20 <= 1.1
               and e.b / e.a == pytest.approx(0.5) and e.angle_deg == 0.0 for e in more)
    assert len({(e.cx, e.cy, e.a) for e in more}) == 20
    with pytest.raises(UsageError, match="start 33 is not one of 0 to 32"):
        start_roi(roi, 33)


def test_bench_from_several_starts_gives_their_mean(dataset):
    seqs = discover(dataset)
    [single] = run_bench(seqs[:1], ["fixed"])
    [merged] = run_bench(seqs[:1], ["fixed"], starts=3, jobs=2)
    assert merged["starts"] == 3 and len(merged["auc_per_start"]) == 3
    assert merged["auc_per_start"][0] == single["auc"]  # start 0 is the plain run
    assert merged["auc"] == pytest.approx(sum(merged["auc_per_start"]) / 3)
    assert merged["frames_scored"] == N_FRAMES and merged["updates"] == 3 * (N_FRAMES - 1)
    res = _run("bench", "--dataset", dataset, "--trackers", "fixed", "--starts", "3", "--json", "-", "-q")
    assert res.exit_code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["parameters"]["starts"] == 3 and len(doc["parameters"]["start_perturbations"]) == 3
    assert [r["starts"] for r in doc["results"]] == [3, 3]
    assert doc["results"][0]["auc"] == pytest.approx(merged["auc"])
    assert res.stderr.startswith("Means over 3 starts per sequence")


def test_bench_on_a_stderr_that_is_not_a_terminal_says_each_tenth_of_its_runs(dataset, tmp_path):
    # A log file or a CI job: a line as each tenth of the runs is done, not a bar's redraws; none under --quiet.
    res = _run("bench", "--dataset", dataset, "--trackers", "fixed", "--starts", "13", "-j", "1",
               "--json", tmp_path / "b.json")
    assert res.exit_code == 0, res.stderr
    lines = [line for line in res.stderr.splitlines() if "runs done" in line]
    tenths = [3, 6, 8, 11, 13, 16, 19, 21, 24, 26]  # the first run past each tenth of 26 (not the code's formula again)
    assert [line.split()[1] for line in lines] == [f"{k}/26" for k in tenths]
    assert lines[-1] == "lptrack: 26/26 runs done (last: fixed on beta)"
    quiet = _run("bench", "--dataset", dataset, "--trackers", "fixed", "--starts", "2", "-q", "--json", "-")
    assert quiet.exit_code == 0 and "runs done" not in quiet.stderr


def test_paired_differences_are_start_by_start_with_their_standard_error():
    results = [{"sequence": "a", "tracker": "x", "auc_per_start": [0.5, 0.6, 0.7, 0.6, 0.9]},
               {"sequence": "a", "tracker": "y", "auc_per_start": [0.4, 0.4, 0.4, 0.4, 0.4], "failed_starts": [4]},
               {"sequence": "b", "tracker": "x", "auc_per_start": [0.5, 0.5, 0.5, 0.5]},
               {"sequence": "b", "tracker": "y", "auc_per_start": [0.4, 0.5, 0.3, float("nan")]},
               {"sequence": "c", "tracker": "x", "auc_per_start": [0.7]},
               {"sequence": "c", "tracker": "y", "auc_per_start": [0.2]}]
    [p] = paired_differences(results, ["x", "y"])
    assert p["tracker"] == "y" and p["against"] == "x"
    # a: 0.1, 0.2, 0.3, 0.2 (start 4 failed for y: left out), standard error 0.041: 4.9 of them, beyond t(3) = 3.18.
    se_a = math.sqrt(0.02 / 3) / 2
    assert p["sequences"]["a"] == {"difference": pytest.approx(0.2), "standard_error": pytest.approx(se_a),
                                   "starts": 4}
    # b: 0.1, 0, 0.2 (NaN left out), standard error 0.058: 3.5 of them, within t(2) = 4.30 (beyond 2).
    assert p["sequences"]["b"]["difference"] == pytest.approx(0.1)
    assert p["sequences"]["b"]["standard_error"] == pytest.approx(0.1 / math.sqrt(3))
    # c: one start, no standard error: undecided, and the mean over the sequences has none either.
    assert p["sequences"]["c"] == {"difference": pytest.approx(0.5), "standard_error": None, "starts": 1}
    assert p["difference"] == pytest.approx(0.8 / 3) and p["standard_error"] is None
    assert (p["ahead"], p["level"], p["behind"], p["undecided"]) == (1, 1, 0, 1)
    assert paired_differences(results, ["x"]) == []
    text = format_paired([p]).splitlines()
    assert text[0].startswith("x's AUC minus each other tracker's")
    assert text[3].split() == ["a", "+0.200", "±", "0.041"] and text[5].split() == ["c", "+0.500"]
    assert text[-2].split() == ["mean", "(3)", "+0.267"]
    assert text[-1].split() == ["ahead/level/behind/undecided", "1/1/0/1"]
    # Without sequence a for another tracker z (it failed on every start there), its mean says it is over 2.
    results += [{"sequence": "a", "tracker": "z", "auc_per_start": [0.1] * 5, "failed_starts": list(range(5))},
                {"sequence": "b", "tracker": "z", "auc_per_start": [0.5, 0.5, 0.5, 0.5]},
                {"sequence": "c", "tracker": "z", "auc_per_start": [0.7]}]
    _, z = paired_differences(results, ["x", "y", "z"])
    assert list(z["sequences"]) == ["b", "c"] and z["difference"] == pytest.approx(0.0)
    text = format_paired([p, z]).splitlines()
    assert text[3].split()[-1] == "n/a" and text[-2].split()[-2:] == ["+0.000", "(2)"]


def test_mean_over_starts_averages_the_status_rates_and_names_failed_starts():
    def run(start, lost, off, error=None):
        return {"sequence": "s", "tracker": "t", "start": start, "frames_scored": 10, "success_rate": 1.0, "auc": 0.5,
                "iou_mean": 0.5, "precision_20": 1.0, "centre_error_median_px": 1.0, "scale_error_median_pct": 1.0,
                "rotation_error_median_deg": None, "lost_rate": lost, "off_tracked_rate": off,
                "success_curve": [1.0] * 21, "precision_curve": [1.0] * 51, "updates": 9, "lost_frames": 0,
                "update_time_s": 0.1, "error": error}

    merged = mean_over_starts([run(0, 0.1, 0.0), run(1, 0.3, 0.5, "ValueError: x"), run(2, 0.2, float("nan"))])
    assert merged["lost_rate"] == pytest.approx(0.2) and merged["off_tracked_rate"] == pytest.approx(0.25)
    assert merged["failed_starts"] == [1] and merged["error"] == "start 1: ValueError: x"


def test_bench_from_several_starts_compares_the_first_tracker_with_the_others(dataset):
    res = _run("bench", "--dataset", dataset, "--trackers", "fixed,diffdecomp,cv-mil", "--starts", "2", "--json",
               "-", "-q")
    assert res.exit_code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert [(p["against"], p["tracker"]) for p in doc["paired"]] == [("fixed", "diffdecomp"), ("fixed", "cv-mil")]
    auc = {(r["sequence"], r["tracker"]): r["auc_per_start"] for r in doc["results"]}
    for p in doc["paired"]:
        for name, seq in p["sequences"].items():
            mine, theirs = auc[(name, "fixed")], auc[(name, p["tracker"])]
            assert seq["difference"] == pytest.approx((mine[0] - theirs[0] + mine[1] - theirs[1]) / 2)
    assert "fixed's AUC minus each other tracker's" in res.stderr and "ahead/level/behind" in res.stderr
    one = _run("bench", "--dataset", dataset, "--trackers", "fixed,diffdecomp", "--json", "-", "-q")
    assert json.loads(one.stdout)["paired"] == [] and "minus each other" not in one.stderr


def _otb_folder(root: Path, name: str, poses: list[Pose], roi: Ellipse) -> Path:
    """An OTB sequence folder (``img/0001.jpg``..., ``groundtruth_rect.txt`` of 1-based x,y,w,h) of the
    synthetic object following ``poses``."""
    folder = root / name
    (folder / "img").mkdir(parents=True)
    lines = []
    for i, (frame, pose) in enumerate(zip(synthetic_sequence(poses, roi, size=(200, 140), seed=3), poses), 1):
        cv2.imwrite(str(folder / "img" / f"{i:04d}.jpg"), frame)
        x, y, w, h = roi.moved(pose.cx, pose.cy, pose.scale, pose.rotation_deg).bounding_box()
        lines.append(f"{x + 1:.2f},{y + 1:.2f},{w:.2f},{h:.2f}")
    (folder / "groundtruth_rect.txt").write_text("\n".join(lines) + "\n")
    return folder


def test_bench_plays_image_sequences_backwards(tmp_path):
    # The object travels 60 px and grows by 30 %: played backwards it starts where it ended and shrinks back.
    roi = Ellipse(60.0, 70.0, 20.0, 20.0, 0.0)
    n = 16
    poses = [Pose(60.0 + 4 * i, 70.0, 1.3 ** (i / (n - 1)), 0.0) for i in range(n)]
    _otb_folder(tmp_path, "walk", poses, roi)
    res = _run("bench", "--dataset", tmp_path, "--trackers", "lpcf", "--backwards", "--json", "-", "-q")
    assert res.exit_code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["parameters"]["backwards"] is True
    [seq], [result] = doc["sequences"], doc["results"]
    assert seq["name"] == result["sequence"] == "walk-backwards" and seq["start_frame"] == 0 and seq["backwards"]
    last = roi.moved(poses[-1].cx, poses[-1].cy, poses[-1].scale, 0.0)
    assert parse_roi(seq["roi"]).centre == pytest.approx(last.centre, abs=0.01)  # inscribed in the last box
    # Tracked from the last frame back to the first (frames in the wrong order would lose it at once).
    assert result["frames_scored"] == n and result["success_rate"] == 1.0
    assert result["scale_error_median_pct"] < 3.0


def test_bench_tracks_every_nth_frame(tmp_path, dataset):
    # 4 px a frame: every third frame the object moves 12 px, and the rows say which frames were tracked.
    roi = Ellipse(60.0, 70.0, 20.0, 20.0, 0.0)
    n = 16
    poses = [Pose(60.0 + 4 * i, 70.0, 1.3 ** (i / (n - 1)), 0.0) for i in range(n)]
    _otb_folder(tmp_path, "walk", poses, roi)
    res = _run("bench", "--dataset", tmp_path, "--trackers", "lpcf", "--every", "3", "--json", "-", "-q")
    assert res.exit_code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["parameters"]["every"] == 3
    [seq], [result] = doc["sequences"], doc["results"]
    assert seq["name"] == result["sequence"] == "walk-every3" and seq["frame_step"] == 3
    assert result["frames_scored"] == 6 and result["success_rate"] == 1.0  # frames 0, 3, ..., 15
    # Videos too, played forwards: every second of N_FRAMES frames.
    res = _run("bench", "--dataset", dataset, "--trackers", "fixed", "--every", "2", "--json", "-", "-q")
    assert res.exit_code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert [r["sequence"] for r in doc["results"]] == ["alpha-every2", "beta-every2"]
    assert {r["frames_scored"] for r in doc["results"]} == {(N_FRAMES + 1) // 2}


def test_bench_plays_image_sequences_there_and_back_and_scores_each_pass(tmp_path):
    # The object travels 60 px and grows by 30 %, then goes back and again: three passes of 16, 15 and 15 frames.
    roi = Ellipse(60.0, 70.0, 20.0, 20.0, 0.0)
    n = 16
    poses = [Pose(60.0 + 4 * i, 70.0, 1.3 ** (i / (n - 1)), 0.0) for i in range(n)]
    _otb_folder(tmp_path, "walk", poses, roi)
    res = _run("bench", "--dataset", tmp_path, "--trackers", "lpcf", "--passes", "3", "--starts", "2", "--json", "-")
    assert res.exit_code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["parameters"]["passes"] == 3
    [seq], [result] = doc["sequences"], doc["results"]
    assert seq["name"] == result["sequence"] == "walk-passes3" and seq["passes"] == 3
    assert result["frames_scored"] == 46 and result["success_rate"] == 1.0
    # Each pass scored on its own frames: followed on every pass, alike.
    assert len(result["auc_per_pass"]) == 3 and min(result["auc_per_pass"]) > 0.75
    assert doc["summary"][0]["auc_per_pass"] == result["auc_per_pass"]
    shown = "Mean IoU AUC per pass (--passes):\n  lpcf: " + " / ".join(f"{v:.3f}" for v in result["auc_per_pass"])
    assert shown in res.stderr  # the table goes to stderr with --json -


def test_auc_per_pass_splits_the_frames_at_the_turns():
    from logpolar_track.bench import auc_per_pass

    from types import SimpleNamespace

    from logpolar_track.evaluate import auc, success_curve

    # A sequence of 4 frames played in 3 passes: frames 0-3, 4-6, 7-9 (frame 8 without ground truth).
    valid = np.array([True] * 8 + [False, True])
    played = SimpleNamespace(passes=3, pass_frames=4, gt=SimpleNamespace(valid=valid))
    frames = np.flatnonzero(valid)
    iou = np.array([1.0] * 4 + [0.0] * 3 + [0.5] * 2)
    expected = [auc(success_curve(np.full(n, value))) for n, value in ((4, 1.0), (3, 0.0), (2, 0.5))]
    assert expected[0] > expected[2] > expected[1] == 0.0
    assert auc_per_pass(played, frames, iou) == pytest.approx(expected)
    # A run that stopped in the second pass: the frames it never reached are misses, not left out.
    stopped = auc_per_pass(played, frames[:5], iou[:5])
    assert stopped == pytest.approx([expected[0], 0.0, 0.0])
    played.gt.valid = np.array([True] * 7 + [False] * 3)
    assert np.isnan(auc_per_pass(played, frames[:7], iou[:7])[2])  # a pass without ground truth


def test_a_failed_run_is_marked_in_the_mean_it_enters(tmp_path):
    """A run stopped by an error is scored over the frames it reached; the mean row says one of its runs failed."""
    roi = Ellipse(60.0, 70.0, 20.0, 20.0, 0.0)
    folder = _otb_folder(tmp_path, "walk", [Pose(60.0 + 2 * i, 70.0, 1.0, 0.0) for i in range(8)], roi)
    (folder / "img" / "0005.jpg").write_bytes(b"not a JPEG")
    res = _run("bench", "--dataset", tmp_path, "--trackers", "fixed", "-q")
    assert res.exit_code == 1 and "fixed failed on walk: cannot read frame image" in res.stderr
    table = res.stdout.splitlines()
    assert table[2].split()[:3] == ["walk", "fixed", "(failed)"]
    assert table[-1].split()[:5] == ["mean", "(1)", "fixed", "(1", "failed)"]


def test_a_start_box_outside_its_frame_is_reported_with_where_it_starts(tmp_path):
    """The tracker's error names the start ROI and its image, so that the ground-truth line is found (it gave the
    ROI's centre alone)."""
    roi = Ellipse(60.0, 70.0, 20.0, 20.0, 0.0)
    folder = _otb_folder(tmp_path, "walk", [Pose(60.0 + 2 * i, 70.0, 1.0, 0.0) for i in range(6)], roi)
    lines = (folder / "groundtruth_rect.txt").read_text().splitlines()
    (folder / "groundtruth_rect.txt").write_text("\n".join(["0,0,0,0", "301,41,20,20"] + lines[2:]) + "\n")
    res = _run("bench", "--dataset", tmp_path, "--trackers", "fixed", "-q", "--every", "2")
    assert res.exit_code == 1
    assert res.stderr.splitlines() == [
        f"lptrack: error: fixed failed on walk-every2: initial ROI 310,50,10 on '{folder / 'img' / '0002.jpg'}': ROI "
        f"centre (310, 50) lies outside the 200x140 frame; give a centre with 0 <= cx <= 199 and 0 <= cy <= 139"]


def _bench_notes(dataset: Path) -> list[str]:
    """The note lines of a successful ``lptrack bench`` of ``fixed`` over ``dataset``."""
    res = _run("bench", "--dataset", dataset, "--trackers", "fixed")
    assert res.exit_code == 0, res.stderr
    return [line for line in res.stderr.splitlines() if line.startswith("lptrack: note:")]


def test_bench_notes_ground_truth_out_of_step_with_its_images(tmp_path):
    roi = Ellipse(60.0, 70.0, 20.0, 20.0, 0.0)
    folder = _otb_folder(tmp_path, "walk", [Pose(60.0 + 2 * i, 70.0, 1.0, 0.0) for i in range(8)], roi)
    (folder / "img" / "0004.jpg").unlink()  # a missing image: lines 4 to 8 now fall on the next images
    (folder / "img" / "._0001.jpg").write_bytes(b"macOS resource fork")  # hidden: not a frame
    assert _bench_notes(tmp_path) == [
        f"lptrack: note: {folder / 'groundtruth_rect.txt'} has 8 lines for 7 images; line k is matched to the k-th "
        f"image, and the lines after the last image are not used",
        f"lptrack: note: {folder / 'img'}: image numbers skip from 0003.jpg to 0005.jpg; lines are still matched "
        f"to images in order"]
    assert "lptrack: note:" not in _run("bench", "--dataset", tmp_path, "--trackers", "fixed", "-q").stderr
    # Every 100th frame leaves the first alone: nothing to track.
    res = _run("bench", "--dataset", tmp_path, "--trackers", "fixed", "--every", "100")
    assert res.exit_code == 2 and res.stdout == ""
    assert res.stderr.splitlines() == ["lptrack: error: --every 100 leaves 1 frame of 'walk-every100', nothing to "
                                       "track; give a smaller N"]
    # Beside a sequence long enough, the short one is skipped with a note: it stopped the whole run.
    _otb_folder(tmp_path, "long", [Pose(60.0 + 2 * i, 70.0, 1.0, 0.0) for i in range(12)], roi)
    res = _run("bench", "--dataset", tmp_path, "--trackers", "fixed", "--every", "10")
    assert res.exit_code == 0, res.stderr
    assert "lptrack: note: skipped 'walk-every10': --every 10 leaves it 1 frame, nothing to track" in res.stderr
    assert "long-every10" in res.stdout and "walk-every10" not in res.stdout


def test_bench_finds_sample_videos_below_others_and_says_which_lack_ground_truth(dataset, tmp_path):
    """A folder of sample videos ended the search there: a video without its .gt.csv beside them was skipped without
    a word, and the sequences in a folder below them were not found."""
    for name in ("alpha.avi", "alpha.gt.csv", "alpha.roi"):
        shutil.copy(dataset / name, tmp_path / name)
    shutil.copy(dataset / "alpha.avi", tmp_path / "nogt.avi")
    (tmp_path / "deeper").mkdir()
    for name in ("beta.avi", "beta.gt.csv", "beta.roi"):
        shutil.copy(dataset / name, tmp_path / "deeper" / name)
    res = _run("bench", "--dataset", tmp_path, "--trackers", "fixed")
    assert res.exit_code == 0, res.stderr
    assert [line for line in res.stderr.splitlines() if line.startswith("lptrack: note:")] == [
        f"lptrack: note: skipped '{tmp_path / 'nogt.avi'}', which has no nogt.gt.csv ground truth beside it"]
    assert [line.split()[0] for line in res.stdout.splitlines()[2:4]] == ["alpha", "beta"]


def test_bench_says_which_folders_it_skipped_and_why(tmp_path):
    """A folder that holds frames or ground truth but is not a sequence is skipped with a note saying what it lacks
    (it was skipped without a word); where nothing else is found, the error says it."""
    roi = Ellipse(60.0, 70.0, 20.0, 20.0, 0.0)
    poses = [Pose(60.0 + 2 * i, 70.0, 1.0, 0.0) for i in range(4)]
    _otb_folder(tmp_path, "walk", poses, roi)
    no_truth = _otb_folder(tmp_path, "run", poses, roi)
    (no_truth / "groundtruth_rect.txt").rename(no_truth / "groundtruth_rect.bak")
    no_images = tmp_path / "sit"
    no_images.mkdir()
    (no_images / "groundtruth.txt").write_text("1,2,3,4\n")
    (tmp_path / "empty").mkdir()  # holds nothing: not a sequence, and nothing to say
    # LaSOT's img/ + groundtruth.txt without its flags of the frames where the target is absent.
    mixed = _otb_folder(tmp_path, "stand", poses, roi)
    (mixed / "groundtruth_rect.txt").rename(mixed / "groundtruth.txt")
    cv2.imwrite(str(tmp_path / "cover.jpg"), np.zeros((8, 8, 3), np.uint8))  # a stray image beside the sequences
    assert _bench_notes(tmp_path) == [
        f"lptrack: note: skipped '{no_truth}', which has images in '{no_truth / 'img'}' but no ground truth beside "
        f"them; with images there lptrack reads groundtruth_rect.txt (OTB) or run.txt (UAV123)",
        f"lptrack: note: skipped '{no_images}', which has groundtruth.txt but no images (in img/, imgs/, color/ or "
        f"the folder itself)",
        f"lptrack: note: skipped '{mixed}', which has groundtruth.txt and images in '{mixed / 'img'}' but not "
        f"LaSOT's full_occlusion.txt and out_of_view.txt beside them, which say the frames where the target is "
        f"absent; with images there lptrack reads groundtruth.txt with those (LaSOT), groundtruth_rect.txt (OTB) or "
        f"stand.txt (UAV123)"]
    assert "lptrack: note:" not in _run("bench", "--dataset", tmp_path, "--trackers", "fixed", "-q").stderr
    # With the notes, --json is written as with -q (the notes' list once took the place of the skipped trackers').
    docs = []
    for quiet in ((), ("-q",)):
        res = _run("bench", "--dataset", tmp_path, "--trackers", "fixed,cv-kcf", "--json", "-", *quiet)
        assert res.exit_code == 0, res.stderr
        docs.append(json.loads(res.stdout))
    assert docs[0]["skipped_trackers"] == docs[1]["skipped_trackers"]
    assert [r["sequence"] for r in docs[0]["results"]] == ["walk"]
    res = _run("bench", "--dataset", no_truth, "--trackers", "fixed")
    assert res.exit_code == 2 and res.stderr.splitlines() == [
        f"lptrack: error: no sequences found in '{no_truth}': it has images in '{no_truth / 'img'}' but no ground "
        f"truth beside them; with images there lptrack reads groundtruth_rect.txt (OTB) or run.txt (UAV123)"]
    # Beyond five, the rest are counted (a dataset laid out otherwise would name every folder).
    for k in range(4):
        (tmp_path / f"sit{k}").mkdir()
        (tmp_path / f"sit{k}" / "groundtruth.txt").write_text("1,2,3,4\n")
    notes = _bench_notes(tmp_path)
    assert len(notes) == 6 and notes[-1] == ("lptrack: note: skipped 2 more folders that hold frames, videos or "
                                             "ground truth but are not sequences")
    (tmp_path / "walk" / "groundtruth_rect.txt").unlink()
    res = _run("bench", "--dataset", tmp_path, "--trackers", "fixed")
    assert res.exit_code == 2 and res.stderr.startswith(
        f"lptrack: error: no sequences found in '{tmp_path}' (searched 3 folders down; skipped 9 folders, e.g. "
        f"'{no_truth}', which has images in")


def test_bench_on_a_lasot_root_leaves_absent_frames_unscored_and_skips_a_test_split(tmp_path):
    """LaSOT's img/ + groundtruth.txt was skipped as a pair lptrack did not read; now its frames flagged out of view
    or fully occluded are left out of the score (their boxes are arbitrary), and a GOT-10k test sequence (one line of
    ground truth) is skipped with a note saying it cannot be scored."""
    roi = Ellipse(60.0, 70.0, 20.0, 20.0, 0.0)
    seq = _otb_folder(tmp_path / "LaSOT" / "thing", "thing-1", [Pose(60.0, 70.0, 1.0, 0.0)] * 6, roi)
    lines = (seq / "groundtruth_rect.txt").read_text().splitlines()
    (seq / "groundtruth_rect.txt").unlink()
    lines[3] = "1,1,-1,-1"  # as LaSOT writes an absent target's box
    lines[4] = "150,10,30,30"  # an arbitrary box, far from the object: scored, it would cost a miss
    (seq / "groundtruth.txt").write_text("\n".join(lines) + "\n")
    (seq / "full_occlusion.txt").write_text("0,0,0,1,0,0")
    (seq / "out_of_view.txt").write_text("0,0,0,0,1,0")
    test = tmp_path / "GOT-10k" / "test" / "GOT-10k_Test_000001"
    test.mkdir(parents=True)
    for i in range(1, 4):
        cv2.imwrite(str(test / f"{i:08d}.jpg"), np.zeros((32, 48, 3), np.uint8))
    (test / "groundtruth.txt").write_text("10,10,8,8\n")
    res = _run("bench", "--dataset", tmp_path, "--trackers", "fixed", "--json", "-")
    assert res.exit_code == 0, res.stderr
    assert [line for line in res.stderr.splitlines() if line.startswith("lptrack: note:")] == [
        f"lptrack: note: skipped '{test}', which has groundtruth.txt with one line, the first frame's box (GOT-10k's "
        f"test split, whose ground truth is kept for its evaluation server): nothing to score"]
    doc = json.loads(res.stdout)
    assert [(s["name"], s["kind"], s["frames"], s["scored_frames"]) for s in doc["sequences"]] == [
        ("thing-1", "lasot", 6, 4)]
    (result,) = doc["results"]
    assert (result["frames_scored"], result["success_rate"]) == (4, 1.0)  # the object never moves


def test_dataset_errors_say_where(tmp_path, dataset):
    roi = Ellipse(60.0, 70.0, 20.0, 20.0, 0.0)
    deep = tmp_path / "deep"
    _otb_folder(deep / "a" / "b" / "c" / "d", "walk", [Pose(60.0, 70.0, 1.0, 0.0)] * 3, roi)
    res = _run("bench", "--dataset", deep, "--trackers", "fixed")
    # The folder where the search stopped is named (it was not: nothing said the sequence was one level too deep).
    assert res.exit_code == 2 and res.stderr.startswith(
        f"lptrack: error: no sequences found in '{deep}' (searched 3 folders down; skipped a folder "
        f"'{deep / 'a' / 'b' / 'c'}', which has sub-folders below the 3 levels searched under a dataset; give a folder "
        f"nearer its sequences (its parent, say) as the dataset); expected")
    twin = tmp_path / "twin"
    twin.mkdir()
    (twin / "alpha.avi").symlink_to(dataset / "alpha.avi")
    for suffix in (".gt.csv", ".roi"):
        (twin / f"alpha{suffix}").write_text((dataset / f"alpha{suffix}").read_text())
    res = _run("bench", "--dataset", dataset, "--dataset", twin, "--trackers", "fixed")
    assert res.exit_code == 2 and res.stderr.splitlines() == [
        f"lptrack: error: several sequences are called alpha: '{dataset / 'alpha.avi'}' and '{twin / 'alpha.avi'}'; "
        f"give datasets whose names differ"]


@pytest.mark.parametrize("flag", [["--backwards"], ["--passes", "2"]])
def test_bench_plays_only_image_sequences_backwards_or_there_and_back(dataset, flag):
    res = _run("bench", "--dataset", dataset, "--trackers", "fixed", *flag)
    assert res.exit_code == 2 and res.stdout == ""
    assert res.stderr.strip().splitlines() == [
        f"lptrack: error: {flag[0]} plays image sequences only (OTB, VOT, UAV123, LaSOT, GOT-10k, TrackingNet), and "
        f"alpha.avi is a "
        "video; give --dataset with such folders"]


SPEED_TAKES_NO = ("no --dataset, --per-frame, --plot, --starts, --backwards, --every, --passes, --threads, --param, "
                  "--jobs or --scheduler")


@pytest.mark.parametrize("args, message", [
    (["--starts", "34"], "1<=x<=33"),
    (["--starts", "2", "--speed"], SPEED_TAKES_NO),
    (["--backwards", "--speed"], SPEED_TAKES_NO),
    (["--every", "2", "--speed"], SPEED_TAKES_NO),
    (["--every", "0"], "x>=1"),
    (["--passes", "2", "--speed"], SPEED_TAKES_NO),
    (["--passes", "0"], "x>=1"),
    (["--threads", "2", "--speed"], SPEED_TAKES_NO),
    (["--param", "window=9", "--speed"], SPEED_TAKES_NO),
    (["--jobs", "2", "--speed"], SPEED_TAKES_NO),
    (["--scheduler", "tcp://127.0.0.1:1", "--speed"], SPEED_TAKES_NO),
    (["--param", "nosuch=9"], "no parameter 'nosuch' in fixed: fixed takes window (11)"),
    (["--param", "window"], "--param takes NAME=VALUE"),
    (["--threads", "0"], "x>=1")])
def test_bad_starts_are_usage_errors(dataset, args, message):
    res = _run("bench", "--trackers", "fixed", *args)
    assert res.exit_code == 2 and message in res.stderr and res.stdout == ""


def test_unknown_tracker_is_a_usage_error(dataset):
    res = _run("bench", "--dataset", dataset, "--trackers", "fixed,nosuch")
    assert res.exit_code == 2 and "unknown tracker 'nosuch'" in res.stderr
    assert res.stdout == ""
    near = _run("bench", "--dataset", dataset, "--trackers", "lpcf,kcf")
    assert near.exit_code == 2 and "unknown tracker 'kcf' (did you mean 'cv-kcf'?)" in near.stderr


@pytest.mark.skipif(KCFTracker.available(), reason="opencv-contrib is installed: KCF/CSRT are available")
def test_contrib_peers_skipped_cleanly_without_contrib(dataset):
    res = _run("bench", "--dataset", dataset, "--trackers", "cv-kcf,cv-mil,cv-csrt")
    assert res.exit_code == 0, res.stderr
    assert "skipping cv-kcf" in res.stderr and "opencv-contrib-python-headless" in res.stderr
    rows = [line.split() for line in res.stdout.splitlines()[2:]]
    trackers = {r[1] for r in rows if r and r[0] not in ("mean", "--------")}
    assert trackers == {"cv-mil"}
    # None runnable: one line with the reasons, not notes before it; nor notes before a bad dataset's line.
    res = _run("bench", "--dataset", dataset, "--trackers", "cv-kcf,cv-csrt")
    assert res.exit_code == 2 and len(res.stderr.splitlines()) == 1
    assert res.stderr.startswith("lptrack: error: none of the requested trackers can run here (cv-kcf: ")
    res = _run("bench", "--dataset", dataset / "missing", "--trackers", "cv-kcf,cv-mil")
    assert res.exit_code == 1 and len(res.stderr.splitlines()) == 1 and "does not exist" in res.stderr


@pytest.mark.skipif(not (KCFTracker.available() and CSRTTracker.available()), reason="needs opencv-contrib")
def test_contrib_peers_run_when_present(dataset):
    results = run_bench(discover(dataset), ["cv-kcf", "cv-csrt"])
    for r in results:
        assert r["error"] is None and r["frames_scored"] == N_FRAMES and r["rotation_error_median_deg"] is None
        assert math.isfinite(r["scale_error_median_pct"]) and r["success_rate"] >= 0.5


def _write_run_csv(path: Path, truth, shift: float = 0.0) -> None:
    lines = ["frame,time_s,cx,cy,a,b,angle_deg,scale,rotation_deg,score,status\n"]
    for i, (e, s, r) in enumerate(truth):
        lines.append(f"{i},{i / 25:.6f},{e.cx + shift:.4f},{e.cy:.4f},{e.a:.4f},{e.b:.4f},{e.angle_deg:.4f},"
                     f"{s:.6f},{r:.4f},1,{'init' if i == 0 else 'tracked'}\n")
    path.write_text("".join(lines))


def test_eval_scores_a_run_csv(dataset, tmp_path):
    truth = _TRUTH[(dataset / "alpha.roi").read_text().strip()]
    pred = tmp_path / "alpha.csv"
    _write_run_csv(pred, truth, shift=5.0)
    res = _run("eval", pred, dataset / "alpha.gt.csv", "--json", "-")
    assert res.exit_code == 0, res.stderr
    m = json.loads(res.stdout)["metrics"]
    assert m["frames_scored"] == N_FRAMES and m["centre_error_median_px"] == pytest.approx(5.0, abs=1e-3)
    assert m["rotation_error_median_deg"] == pytest.approx(0, abs=1e-3)
    assert m["success_rate"] == 0.0  # 5 px >= 25 % of the radius sqrt(18*14) * scale <= 15.9 * 1.15 px
    assert "ground_truth_file" not in json.loads(res.stdout)
    # The ground truth given as the video: the file read for it is named too.
    document = json.loads(_run("eval", pred, dataset / "alpha.avi", "--json", "-").stdout)
    assert document["metrics"]["centre_error_median_px"] == pytest.approx(5.0, abs=1e-3)
    assert (document["ground_truth"], document["ground_truth_file"]) == (str(dataset / "alpha.avi"),
                                                                         str(dataset / "alpha.gt.csv"))
    res = _run("eval", pred, dataset)  # a folder with two sequences is ambiguous
    assert res.exit_code == 2 and "2 sequences" in res.stderr
    _write_run_csv(pred, truth)
    res = _run("eval", pred, dataset / "alpha.gt.csv")
    assert res.exit_code == 0 and res.stdout.splitlines()[2].split()[3] == "100.0"


def test_evaluate_run_is_what_eval_does_from_python(dataset, tmp_path):
    truth = _TRUTH[(dataset / "alpha.roi").read_text().strip()]
    pred = tmp_path / "alpha.csv"
    _write_run_csv(pred, truth[:-2], shift=5.0)  # two frames short of the ground truth
    metrics, notes = evaluate_run(pred, dataset / "alpha.gt.csv")
    assert metrics["frames_scored"] == N_FRAMES - 2
    assert metrics["centre_error_median_px"] == pytest.approx(5.0, abs=1e-3)
    assert notes == [f"'{pred}' has no row for 2 of the {N_FRAMES} frames with ground truth; they are not scored"]
    with pytest.raises(UsageError, match="is ground truth \\(a .gt.csv\\), not a run; the run's CSV goes first"):
        evaluate_run(dataset / "alpha.gt.csv", pred)
    # A run saved as UTF-16 (read as a run since it may be) given as the ground truth is said to be a run too.
    utf16 = tmp_path / "alpha16.csv"
    utf16.write_bytes(pred.read_text().encode("utf-16"))
    with pytest.raises(UsageError, match="is an lptrack run .*; the run's CSV goes first"):
        evaluate_run(pred, utf16)
    # A batch's stream against a video's ground truth: that video's rows, as eval scores them (the choice was the
    # CLI's alone, so evaluate_run refused the stream).
    stream = tmp_path / "all.csv"
    header = [f"video,{line}" for line in pred.read_text().splitlines()[:1]]
    for name in ("alpha", "beta"):
        _write_run_csv(tmp_path / "one.csv", _TRUTH[(dataset / f"{name}.roi").read_text().strip()])
        header += [f"{dataset / name}.avi,{line}" for line in (tmp_path / "one.csv").read_text().splitlines()[1:]]
    stream.write_text("\n".join(header) + "\n")
    metrics, _ = evaluate_run(stream, dataset / "alpha.avi")
    assert metrics["frames_scored"] == N_FRAMES and metrics["centre_error_median_px"] == pytest.approx(0, abs=1e-3)


def test_eval_to_a_stdout_that_cannot_encode_its_table_is_one_error_line(dataset, tmp_path):
    pred = tmp_path / "трек.csv"  # the table names the run
    _write_run_csv(pred, _TRUTH[(dataset / "alpha.roi").read_text().strip()])
    env = dict(os.environ, PYTHONIOENCODING="ascii")
    proc = subprocess.run([sys.executable, "-m", "logpolar_track", "eval", str(pred), str(dataset / "alpha.gt.csv")],
                          capture_output=True, env=env)
    assert proc.returncode == 1
    assert proc.stderr.decode() == ("lptrack: error: cannot write to stdout: its encoding (ascii) has no "
                                    "'\\u0442\\u0440\\u0435\\u043a'; set PYTHONIOENCODING=utf-8\n")


def test_json_to_the_file_stdout_writes_to_is_json_alone(dataset, oracle, tmp_path):
    # `--json /dev/stdout` wrote the JSON and then the table into the same stream: neither JSON nor a table.
    pred = tmp_path / "alpha.csv"
    _write_run_csv(pred, _TRUTH[(dataset / "alpha.roi").read_text().strip()])
    for json_out in ("/dev/stdout", "/dev/fd/1"):
        with open(tmp_path / "out.json", "w") as stdout:
            proc = subprocess.run([sys.executable, "-m", "logpolar_track", "eval", str(pred),
                                   str(dataset / "alpha.gt.csv"), "--json", json_out], stdout=stdout,
                                  stderr=subprocess.PIPE)
        assert proc.returncode == 0, proc.stderr
        assert json.loads((tmp_path / "out.json").read_text())["metrics"]["frames_scored"] == N_FRAMES
    # bench too (its table goes to stderr then), and the file stdout is redirected to, named as such.
    with open(tmp_path / "b.json", "w") as stdout:
        proc = subprocess.run([sys.executable, "-m", "logpolar_track", "bench", "--dataset", str(dataset),
                               "--trackers", "cv-mil", "--json", str(tmp_path / "b.json"), "-q"], stdout=stdout,
                              stderr=subprocess.PIPE)
    assert proc.returncode == 0, proc.stderr
    assert json.loads((tmp_path / "b.json").read_text())["tool"] == "lptrack bench"
    assert b"mean (2)" in proc.stderr and sorted(p.name for p in tmp_path.iterdir()) == ["alpha.csv", "b.json",
                                                                                         "out.json"]


@pytest.mark.skipif(os.devnull != "/dev/null", reason="POSIX /dev/null")
def test_bench_json_to_dev_null_with_stdout_to_dev_null_stays_quiet(dataset):
    # /dev/null is also the file stdout writes to: taken as --json -, the table went to stderr.
    proc = subprocess.run([sys.executable, "-m", "logpolar_track", "bench", "--dataset", str(dataset), "--trackers",
                           "cv-mil", "--json", os.devnull, "-q"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    assert (proc.returncode, proc.stderr) == (0, b"")


def test_eval_rejects_unreadable_prediction(dataset, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("frame,cx\n0,1\n")
    res = _run("eval", bad, dataset / "alpha.gt.csv")
    assert res.exit_code == 1 and res.stderr == (f"lptrack: error: run CSV '{bad}' lacks column(s) cy, a, b, "
                                                 f"angle_deg; expected an lptrack run CSV with the header "
                                                 f"{','.join(COLUMNS)}, or its JSON lines (or another tool's CSV with "
                                                 f"at least the columns "
                                                 f"frame,cx,cy,a,b,angle_deg)\n")


def test_bench_outputs_are_checked_before_the_run(dataset, tmp_path):
    res = _run("bench", "--dataset", dataset, "--trackers", "cv-mil", "--json", tmp_path / "no" / "b.json")
    assert res.exit_code == 1 and "folder" in res.stderr and "does not exist" in res.stderr
    assert res.stdout == "" and len(res.stderr.splitlines()) == 1  # no table: nothing ran
    res = _run("bench", "--dataset", dataset, "--trackers", "cv-mil", "--plot", tmp_path / "p.txt")
    assert res.exit_code == 2 and "give a file name ending in .png or .pdf or .svg" in res.stderr
    assert res.stdout == ""
    kept = tmp_path / "kept.json"
    kept.write_text("precious\n")
    res = _run("bench", "--dataset", dataset, "--trackers", "cv-mil", "--json", kept, "-q")
    assert res.exit_code == 1 and res.stdout == "" and kept.read_text() == "precious\n"
    assert res.stderr == f"lptrack: error: JSON output '{kept}' already exists; use --overwrite to replace it\n"
    res = _run("bench", "--dataset", dataset, "--trackers", "cv-mil", "--json", kept, "-q", "--overwrite")
    assert res.exit_code == 0 and json.loads(kept.read_text())["tool"] == "lptrack bench"
    res = _run("bench", "--speed", "--json", kept)
    assert res.exit_code == 1 and "already exists" in res.stderr


def test_bench_runs_a_sequence_given_twice_once(dataset, oracle, tmp_path):
    # `--dataset data --dataset data/alpha.avi` was refused as two sequences called alpha, the one line naming the
    # same file twice; `lptrack run` runs a video named twice once, with a note.
    res = _run("bench", "--dataset", dataset, "--dataset", dataset / "alpha.avi", "--trackers", oracle, "--json", "-")
    assert res.exit_code == 0, res.stderr
    assert [s["name"] for s in json.loads(res.stdout)["sequences"]] == ["alpha", "beta"]
    assert f"lptrack: note: sequence '{dataset / 'alpha.avi'}' is given twice; it is run once\n" in res.stderr
    by_another_path = tmp_path / ".." / dataset.name  # tmp_path and the dataset share a parent
    res = _run("bench", "--dataset", dataset, "--dataset", by_another_path, "--trackers", oracle, "--json", "-")
    assert res.exit_code == 0 and len(json.loads(res.stdout)["sequences"]) == 2
    assert f"lptrack: note: sequence '{dataset / 'alpha.avi'}' is given again as '{by_another_path / 'alpha.avi'}'; " \
           f"it is run once\n" in res.stderr
    # Two sequences of one name in different places are still refused.
    other = tmp_path / "other"
    shutil.copytree(dataset, other)
    res = _run("bench", "--dataset", dataset, "--dataset", other, "--trackers", oracle)
    assert res.exit_code == 2 and res.stderr.startswith("lptrack: error: several sequences are called alpha: ")


def test_missing_dataset_is_an_input_failure_as_a_missing_video_is(tmp_path):
    res = _run("bench", "--dataset", tmp_path / "missing", "--trackers", "cv-mil")
    assert res.exit_code == 1 and res.stderr == (f"lptrack: error: dataset '{tmp_path / 'missing'}' does not exist; "
                                                 f"give a folder of sequences or a sample video\n")


def test_eval_inputs_and_outputs(dataset, tmp_path):
    truth = _TRUTH[(dataset / "alpha.roi").read_text().strip()]
    pred = tmp_path / "alpha.csv"
    _write_run_csv(pred, truth)
    res = _run("eval", tmp_path / "missing.csv", dataset / "alpha.gt.csv")
    assert res.exit_code == 1 and "missing.csv" in res.stderr and len(res.stderr.splitlines()) == 1
    res = _run("eval", pred, tmp_path / "missing.txt")
    assert res.exit_code == 1 and "ground truth" in res.stderr and "does not exist" in res.stderr
    image = tmp_path / "0001.png"  # an image given as the ground truth: one clean line, not its bytes
    cv2.imwrite(str(image), np.zeros((8, 8), np.uint8))
    res = _run("eval", pred, image)
    assert res.exit_code == 1 and res.stderr == (f"lptrack: error: cannot read ground truth '{image}': not a text "
                                                 f"file (UTF-8, or UTF-16 with a byte-order mark); expected one "
                                                 f"x,y,w,h or x1,y1,...,x4,y4 line per frame\n")
    kept = tmp_path / "kept.json"
    kept.write_text("precious\n")
    res = _run("eval", pred, dataset / "alpha.gt.csv", "--json", kept)
    assert res.exit_code == 1 and "already exists; use --overwrite" in res.stderr and kept.read_text() == "precious\n"
    res = _run("eval", pred, dataset / "alpha.gt.csv", "--json", kept, "--overwrite")
    assert res.exit_code == 0 and json.loads(kept.read_text())["tool"] == "lptrack eval"
    # A run CSV covering only part of the ground truth is scored on that part, and said so.
    pred.write_text("".join(pred.read_text().splitlines(keepends=True)[:4]))
    res = _run("eval", pred, dataset / "alpha.gt.csv")
    assert res.exit_code == 0
    assert res.stderr == (f"lptrack: note: '{pred}' has no row for {N_FRAMES - 3} of the {N_FRAMES} frames with "
                          f"ground truth; they are not scored\n")
    # A ground truth that ends before the run (cut short, or another sequence's) was used in silence.
    short = tmp_path / "short.gt.csv"
    short.write_text("".join((dataset / "alpha.gt.csv").read_text().splitlines(keepends=True)[:3]))  # 2 frames
    res = _run("eval", pred, short)
    assert res.exit_code == 0
    assert res.stderr == (f"lptrack: note: 1 of the 3 rows of '{pred}' lies past the end of '{short}' (2 frames); "
                          f"they are not scored (is it this video's ground truth?)\n")


def test_plot(dataset, tmp_path):
    png = tmp_path / "plot.png"
    res = _run("bench", "--dataset", dataset, "--trackers", "cv-mil", "--plot", png, "-q")
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        assert res.exit_code == 2 and "pip install matplotlib" in res.stderr and not png.exists()
        return
    assert res.exit_code == 0, res.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plot_gives_a_tracker_one_colour_in_both_panels(tmp_path, monkeypatch):
    """The legends rank the trackers, each panel by its own figure; the colours followed the ranking, so a tracker
    first in one panel and second in the other changed colour between them."""
    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    from logpolar_track.bench import IOU_THRESHOLDS, PRECISION_THRESHOLDS, plot_curves

    colours = {}

    def record(figure, path, **kwargs):
        Path(path).write_bytes(b"")
        for ax in figure.axes:
            colours[ax.get_title()] = {line.get_label().split(" [")[0]: line.get_color() for line in ax.lines}

    monkeypatch.setattr(Figure, "savefig", record)
    ramp = np.linspace(1, 0, len(IOU_THRESHOLDS)), np.linspace(0, 1, len(PRECISION_THRESHOLDS))
    summary = [{"tracker": "a", "auc": 0.6, "precision_20": 0.5, "success_curve": ramp[0], "precision_curve": ramp[1]},
               {"tracker": "b", "auc": 0.5, "precision_20": 0.7, "success_curve": ramp[0] / 2,
                "precision_curve": ramp[1] / 2}]
    plot_curves(summary, tmp_path / "p.png")
    assert colours["Success plot"] == colours["Precision plot"]
    assert colours["Success plot"]["a"] != colours["Success plot"]["b"]


def test_plot_says_what_was_run(dataset, tmp_path, monkeypatch):
    """A plot of a run played backwards, or from several starts, looked like a plain run's: its caption says."""
    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    captions = []

    def record(figure, path, **kwargs):
        Path(path).write_bytes(b"")
        captions.append(figure._suptitle.get_text() if figure._suptitle else None)

    monkeypatch.setattr(Figure, "savefig", record)
    for extra in ([], ["--starts", "2"]):
        res = _run("bench", "--dataset", dataset, "--trackers", "fixed", "--plot", tmp_path / "p.png", "--overwrite",
                   "-q", *extra)
        assert res.exit_code == 0, res.stderr
    roi = Ellipse(60.0, 70.0, 20.0, 20.0, 0.0)
    _otb_folder(tmp_path / "otb", "still", [Pose(60.0, 70.0, 1.0, 0.0)] * 4, roi)
    for extra in (["--backwards"], ["--backwards", "--every", "2"], ["--passes", "2"]):
        res = _run("bench", "--dataset", tmp_path / "otb", "--trackers", "fixed", "--plot", tmp_path / "p.png",
                   "--overwrite", "-q", *extra)
        assert res.exit_code == 0, res.stderr
    assert captions == ["2 sequences", "2 sequences, means over 2 starts", "1 sequence played backwards",
                        "1 sequence played backwards, every 2nd frame", "1 sequence, 2 passes there and back"]


SAMPLES = Path(__file__).resolve().parents[1] / "sample_videos"


def _children(pid: int) -> list[int]:
    try:
        return [int(c) for c in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]
    except OSError:
        return []


def _reads_a_sample(pid: int) -> bool:
    """Whether process ``pid`` has one of the sample videos open (a bench worker does while it reads frames)."""
    try:
        targets = [os.readlink(fd) for fd in Path(f"/proc/{pid}/fd").iterdir()]
    except OSError:  # it ended, or a descriptor closed while listed
        return False
    return any(t.startswith(str(SAMPLES)) and t.endswith(".mp4") for t in targets)


@pytest.mark.skipif(not Path(f"/proc/{os.getpid()}/task/{os.getpid()}/children").exists(),
                    reason="needs Linux's /proc/PID/task/PID/children")
def test_ctrl_c_to_a_parallel_bench_is_one_line():
    # A terminal's Ctrl-C goes to the whole process group, workers included, while they read frames; the parent
    # then stops them too. Once the workers run, that gave "Exception ignored in: <generator ...>" tracebacks.
    # (SIGINT restored to its default in the child's Python: a background job inherits it ignored.)
    assert (SAMPLES / "spin.gt.csv").is_file(), "sample_videos/ is missing from the checkout"
    restore_sigint = ("import runpy, signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
                      "sys.argv[0] = 'lptrack'; runpy.run_module('logpolar_track', run_name='__main__')")
    process = subprocess.Popen([sys.executable, "-c", restore_sigint, "bench", "--dataset", str(SAMPLES),
                                "--trackers", "spatial", "--jobs", "2", "-q"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 60
        # The workers are children of multiprocessing's fork server, a child of lptrack: wait until both read a
        # sample video's frames (rather than for a second, which a loaded machine may not reach them in).
        while sum(_reads_a_sample(w) for c in _children(process.pid) for w in _children(c)) < 2:
            assert process.poll() is None and time.monotonic() < deadline, "the workers never read frames"
            time.sleep(0.02)
        os.killpg(process.pid, signal.SIGINT)
        out, err = process.communicate(timeout=30)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    assert process.returncode == 130, err
    assert err == "lptrack: interrupted\n" and out == ""
