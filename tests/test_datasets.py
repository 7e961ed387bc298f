"""Dataset discovery and streaming (logpolar_track.datasets) on tiny fixtures of every layout."""

from __future__ import annotations

import inspect
import math
import pickle
import re
from pathlib import Path

import cv2
import numpy as np
import pytest

from logpolar_track.bench import run_one
from logpolar_track.datasets import discover, load_ground_truth
from logpolar_track.errors import InputError, UsageError
from logpolar_track.evaluate import GroundTruthError, rotated_box_corners

SHARED_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def _images(folder: Path, n: int, *, digits: int = 4, grey: bool = False, size=(48, 32)) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    for i in range(1, n + 1):
        img = np.full((size[1], size[0]) if grey else (size[1], size[0], 3), 10 * i, np.uint8)
        cv2.imwrite(str(folder / f"{i:0{digits}d}.jpg"), img)
    return folder


def _otb(root: Path, name: str, n_frames: int, lines: list[str], sep: str = ",", newline: str = "\n") -> Path:
    seq = root / name
    _images(seq / "img", n_frames, grey=True)
    (seq / "groundtruth_rect.txt").write_text(newline.join(line.replace(",", sep) for line in lines) + newline)
    return seq


def test_otb_folder_commas_more_frames_than_lines(tmp_path):
    seq_dir = _otb(tmp_path, "walk", 5, ["11,21,10,6", "12,21,10,6", "13,21,10,6"])
    (seq,) = discover(seq_dir)
    assert (seq.name, seq.kind, seq.n_frames, seq.start) == ("walk", "otb", 5, 0)
    assert seq.gt.valid.tolist() == [True, True, True, False, False]  # frames past the last line: unscored
    assert (seq.roi.cx, seq.roi.cy, seq.roi.a, seq.roi.b) == (15, 23, 5, 3)  # 1-based x=11 -> 10, +w/2


def test_otb_tabs_crlf_and_leading_nan_line(tmp_path):
    seq_dir = _otb(tmp_path, "toy", 4, ["NaN,NaN,NaN,NaN", "1,1,8,8", "2,1,8,8", "3,1,8,8"], sep="\t",
                   newline="\r\n")
    (seq,) = discover(seq_dir)
    assert seq.start == 1  # the tracker starts on the first frame with ground truth
    assert seq.gt.valid.tolist() == [False, True, True, True]
    assert (seq.roi.cx, seq.roi.cy) == (4, 4)


def test_a_sequence_played_backwards_starts_on_its_last_frame_with_ground_truth(tmp_path):
    # Frames 5 and 6 have no line and frame 4 a NaN one: played backwards, frame 3 (forwards) comes first.
    lines = [f"{10 + i},21,10,6" for i in range(4)] + ["NaN,NaN,NaN,NaN"]
    (seq,) = discover(_otb(tmp_path, "walk", 7, lines))
    back = seq.backwards()
    assert (back.name, back.start, back.n_frames, back.played_backwards) == ("walk-backwards", 3, 7, True)
    assert back.gt.valid.tolist() == [False, False, False, True, True, True, True]
    assert (back.roi.cx, back.roi.cy, back.roi.a, back.roi.b) == (17, 23, 5, 3)  # line 4, 1-based x=13 -> 12, +5
    assert [int(f.mean()) for _, _, f in back.frames()] == pytest.approx([70, 60, 50, 40, 30, 20, 10], abs=2)
    assert back.describe()["start_frame"] == 3 and back.describe()["backwards"] and not seq.describe()["backwards"]


def test_every_nth_frame_of_an_image_sequence_from_its_first_with_ground_truth(tmp_path):
    # Frame 0 has a NaN line: the tracker starts on frame 1, so every third frame is 1, 4, 7 (and no frame 8 line).
    lines = ["NaN,NaN,NaN,NaN"] + [f"{10 + i},21,{10 + i},6" for i in range(1, 8)]
    (seq,) = discover(_otb(tmp_path, "walk", 9, lines))
    third = seq.every(3)
    assert (third.name, third.start, third.n_frames, third.fps, third.frame_step) == ("walk-every3", 0, 3, 10.0, 3)
    assert [int(f.mean()) for _, _, f in third.frames()] == pytest.approx([20, 50, 80], abs=2)
    assert [i for i, _, _ in third.frames()] == [0, 1, 2]
    assert third.gt.boxes[:, 2].tolist() == [11, 14, 17]  # the widths of lines 2, 5 and 8
    assert third.gt.scale.tolist() == pytest.approx([1.0, math.sqrt(14 / 11), math.sqrt(17 / 11)])
    assert third.roi == seq.roi and seq.describe()["frame_step"] == 1
    assert (third.describe()["frame_step"], third.describe()["first_frame"]) == (3, 1)  # frame 0 is image 1
    assert [t for _, t, _ in third.frames()] == pytest.approx([1 / 30, 4 / 30, 7 / 30])  # the images' own times
    sent = pickle.loads(pickle.dumps(third))  # as Dask sends it to its workers
    assert (sent.frame_files, sent.frame_step, sent.first_frame) == (third.frame_files, 3, 1)
    assert np.array_equal(sent.gt.boxes, third.gt.boxes)
    # Played backwards first, then every second frame: lines 8, 6, 4, 2.
    back = seq.backwards().every(2)
    assert back.name == "walk-backwards-every2" and back.gt.boxes[:, 2].tolist() == [17, 15, 13, 11]
    assert seq.every(1) is seq
    for n in (0, 1.5, 2.0, True):  # 1.5 and 2.0 failed in slicing with a TypeError, True was every frame
        with pytest.raises(UsageError, match=f"every takes a whole number of frames >= 1, got {n!r}"):
            seq.every(n)


def test_an_image_sequence_played_there_and_back_from_its_first_frame_with_ground_truth(tmp_path):
    # Frame 0 has a NaN line: the passes run over frames 1-4: 1 2 3 4, 3 2 1, 2 3 4.
    lines = ["NaN,NaN,NaN,NaN"] + [f"{10 + i},21,{10 + i},6" for i in range(1, 5)]
    (seq,) = discover(_otb(tmp_path, "walk", 5, lines))
    three = seq.there_and_back(3)
    assert (three.name, three.start, three.n_frames, three.passes, three.pass_frames) == ("walk-passes3", 0, 10, 3, 4)
    assert [int(f.mean()) for _, _, f in three.frames()] == pytest.approx([20, 30, 40, 50, 40, 30, 20, 30, 40, 50],
                                                                          abs=2)
    assert three.gt.boxes[:, 2].tolist() == [11, 12, 13, 14, 13, 12, 11, 12, 13, 14]  # each frame's own line
    assert three.gt.scale[[0, 6]].tolist() == [1.0, 1.0] and three.roi == seq.roi
    assert three.describe()["passes"] == 3 and seq.describe()["passes"] == 1
    # Played backwards first (from frame 4), then there and back: lines 4 3 2 1, frame 0's NaN, and back.
    widths = seq.backwards().there_and_back(2).gt.boxes[:, 2]
    assert np.array_equal(widths, [14, 13, 12, 11, np.nan, 11, 12, 13, 14], equal_nan=True)
    assert seq.there_and_back(1) is seq
    for n in (0, 2.5, True):
        with pytest.raises(UsageError, match=f"passes takes a whole number >= 1, got {n!r}"):
            seq.there_and_back(n)


def test_every_nth_frame_of_a_video(tmp_path):
    frames = [np.full((40, 64, 3), 20 * i, np.uint8) for i in range(8)]
    writer = cv2.VideoWriter(str(tmp_path / "disc.avi"), cv2.VideoWriter_fourcc(*"MJPG"), 25.0, (64, 40))
    for f in frames:
        writer.write(f)
    writer.release()
    # No ground truth on frame 0 and no .roi: the tracker starts on frame 1.
    (tmp_path / "disc.gt.csv").write_text("frame,cx,cy,a,b,angle_deg,scale,rotation_deg\n"
                                          + "".join(f"{i},{30 + i},20,10,10,0,1,{5 * i}\n" for i in range(1, 8)))
    (seq,) = discover(tmp_path)
    assert seq.start == 1
    half = seq.every(2)
    assert (half.name, half.start, half.n_frames, half.first_frame, half.fps) == ("disc-every2", 0, 4, 1, 12.5)
    kept = list(half.frames())
    assert [i for i, _, _ in kept] == [0, 1, 2, 3]
    assert [t for _, t, _ in kept] == pytest.approx([0.04, 0.12, 0.2, 0.28])  # the video's own times
    assert [int(f.mean()) for _, _, f in kept] == pytest.approx([20, 60, 100, 140], abs=3)
    assert half.gt.rotation_deg.tolist() == [0, 10, 20, 30]  # from frame 1's 5 degrees
    # Every second frame of that: frames 1 and 5 of the video.
    quarter = half.every(2)
    assert (quarter.frame_step, quarter.first_frame) == (4, 1)
    assert [int(f.mean()) for _, _, f in quarter.frames()] == pytest.approx([20, 100], abs=3)
    # With a .roi sidecar the tracker starts on frame 0, ground truth or not.
    (tmp_path / "disc.roi").write_text("30,20,9\n")
    (seq,) = discover(tmp_path)
    third = pickle.loads(pickle.dumps(seq.every(3)))
    assert (third.start, third.first_frame, third.n_frames) == (0, 0, 3)
    assert [int(f.mean()) for _, _, f in third.frames()] == pytest.approx([0, 60, 120], abs=3)
    assert third.gt.valid.tolist() == [False, True, True] and third.gt.rotation_deg[1:].tolist() == [0, 15]


def test_spaces_and_more_lines_than_frames(tmp_path):
    seq_dir = _otb(tmp_path, "s", 2, ["1 1 8 8", "2 1 8 8", "3 1 8 8"], sep=" ")
    (seq,) = discover(seq_dir)
    assert len(seq.gt) == 2 and seq.n_frames == 2


def test_frames_are_streamed_bgr_in_natural_order(tmp_path):
    seq_dir = _otb(tmp_path, "s", 3, ["1,1,8,8"] * 3)
    (seq,) = discover(seq_dir)
    frames = seq.frames()
    assert inspect.isgenerator(frames)
    got = list(frames)
    assert [i for i, _, _ in got] == [0, 1, 2]
    assert got[1][1] == pytest.approx(1 / 30)
    assert all(f.shape == (32, 48, 3) and f.dtype == np.uint8 for _, _, f in got)  # grey JPEGs come as BGR
    assert [int(f.mean()) for _, _, f in got] == pytest.approx([10, 20, 30], abs=2)


def test_vot_polygons_in_imgs_and_color_and_folder(tmp_path):
    lines = []
    for i, angle in enumerate([20, 25, 30]):
        poly = rotated_box_corners([24, 16, 20, 8, angle])[[(i + k) % 4 for k in range(4)]]
        lines.append(",".join(f"{v:.3f}" for v in poly.ravel()))
    for where in ("imgs", "color", "."):
        seq_dir = tmp_path / f"vot_{where.strip('.') or 'flat'}"
        _images(seq_dir / where, 3, digits=8)
        (seq_dir / "groundtruth.txt").write_text("\n".join(lines) + "\n")
        (seq,) = discover(seq_dir)
        assert seq.kind == "vot" and seq.n_frames == 3 and seq.gt.rotated
        assert (seq.roi.cx, seq.roi.cy, seq.roi.a, seq.roi.b, seq.roi.angle_deg) == pytest.approx(
            (24, 16, 10, 4, 20), abs=1e-2)
        np.testing.assert_allclose(seq.gt.rotation_deg, [0, 5, 10], atol=1e-2)


def test_vot_four_number_lines_are_zero_based_boxes(tmp_path):
    seq_dir = tmp_path / "v"
    _images(seq_dir, 2, digits=8)
    (seq_dir / "groundtruth.txt").write_text("10,20,8,6\n11,20,8,6\n")
    (seq,) = discover(seq_dir)
    assert not seq.gt.rotated and (seq.roi.cx, seq.roi.cy) == (14, 23)


def test_uav123_folder(tmp_path):
    seq_dir = tmp_path / "boat9"
    _images(seq_dir / "img", 3, digits=6)
    (seq_dir / "boat9.txt").write_text("5,5,10,10\nNaN,NaN,NaN,NaN\n6,5,10,10\n")
    (seq,) = discover(seq_dir)
    assert seq.kind == "uav123" and seq.gt.valid.tolist() == [True, False, True]


def test_folder_of_folders_in_natural_order_and_empty(tmp_path):
    for name in ("b10", "b2", "a"):
        _otb(tmp_path / "set", name, 2, ["1,1,8,8"] * 2)
    (tmp_path / "set" / "notes").mkdir()
    assert [s.name for s in discover(tmp_path / "set")] == ["a", "b2", "b10"]
    assert discover(tmp_path / "set" / "notes") == []
    with pytest.raises(InputError, match="does not exist"):  # a missing input: exit 1, as a missing video
        discover(tmp_path / "missing")


def test_lptrack_sample_video_with_gt_and_roi(tmp_path):
    frames = [np.full((40, 64, 3), 20 * i, np.uint8) for i in range(4)]
    writer = cv2.VideoWriter(str(tmp_path / "disc.avi"), cv2.VideoWriter_fourcc(*"MJPG"), 25.0, (64, 40))
    assert writer.isOpened()
    for f in frames:
        writer.write(f)
    writer.release()
    (tmp_path / "disc.gt.csv").write_text("frame,cx,cy,a,b,angle_deg,scale,rotation_deg\n"
                                          + "".join(f"{i},{30 + i},20,10,10,0,1,{5 * i}\n" for i in range(4)))
    (tmp_path / "disc.roi").write_text("30,20,9\n")
    (seq,) = discover(tmp_path)
    assert (seq.name, seq.kind, seq.start, seq.fps) == ("disc", "lptrack", 0, 25.0)
    assert seq.roi.to_spec() == "30,20,9"  # the .roi sidecar wins over the first ground-truth row
    assert [i for i, _, _ in seq.frames()] == [0, 1, 2, 3]
    assert seq.gt.rotation_deg.tolist() == [0, 5, 10, 15]
    assert load_ground_truth(tmp_path).rotation_deg.tolist() == [0, 5, 10, 15]


@pytest.mark.skipif(not SHARED_DATA.is_dir(), reason="../shared/data (real benchmark sequences) is absent")
def test_shared_benchmark_sequences():
    seqs = {s.name: s for s in discover(SHARED_DATA)}
    expected = {"bag": 196, "boat1": 301, "crossing": 120, "freeman1": 326, "human3": 199, "motorrolling": 164,
                "toy": 271}
    assert {n: s.n_frames for n, s in seqs.items()} == expected
    assert {n: s.kind for n, s in seqs.items()} == {"bag": "vot", "boat1": "uav123", "crossing": "otb",
                                                   "freeman1": "otb", "human3": "otb", "motorrolling": "otb",
                                                   "toy": "otb"}
    for s in seqs.values():
        assert s.start == 0 and s.gt.valid.all() and len(s.gt) == s.n_frames
    # First boxes (1-based x,y,w,h in the files) -> inscribed ellipses in 0-based pixels.
    assert seqs["crossing"].roi.to_spec() == "212.5,175,8.5,25,0"    # 205,151,17,50 (tabs)
    assert seqs["motorrolling"].roi.to_spec() == "177,129.5,61,62.5,0"  # 117,68,122,125
    assert seqs["toy"].roi.to_spec() == "171,134.5,20,33.5,0"        # tab-separated, CRLF
    bag = seqs["bag"].roi  # rotated quadrilateral 291.8,203.6,396.4,264.3,442.2,185.4,337.6,124.7
    assert (bag.cx, bag.cy) == pytest.approx((367.0, 194.5), abs=0.5)
    assert (bag.a, bag.b) == pytest.approx((60.4, 45.6), abs=0.3)
    assert bag.angle_deg == pytest.approx(-30.1, abs=0.3)  # long side runs down-right on screen
    assert seqs["bag"].gt.rotated and not seqs["toy"].gt.rotated
    _, _, frame = next(seqs["human3"].frames())
    assert frame.shape == (640, 480, 3)
    assert math.isfinite(seqs["boat1"].gt.scale[-1])


@pytest.mark.skipif(not SHARED_DATA.is_dir(), reason="../shared/data (real benchmark sequences) is absent")
def test_shared_sequences_played_backwards():
    seqs = {s.name: s for s in discover(SHARED_DATA)}
    crossing, bag = seqs["crossing"].backwards(), seqs["bag"].backwards()
    assert crossing.name == "crossing-backwards" and crossing.start == 0 and crossing.n_frames == 120
    assert crossing.roi.to_spec() == "62,110,7,18,0"  # the last line, 56,93,14,36 (1-based)
    _, _, first = next(crossing.frames())
    np.testing.assert_array_equal(first, cv2.imread(str(SHARED_DATA / "crossing" / "img" / "0120.jpg")))
    # bag's last polygon is the axis-aligned rectangle (132, 107)-(307, 256); its rotation counts from there.
    assert (bag.roi.cx, bag.roi.cy, bag.roi.a, bag.roi.b) == pytest.approx((219.5, 181.5, 87.5, 74.5), abs=0.2)
    forwards = seqs["bag"].gt
    assert bag.gt.rotation_deg[0] == 0.0 and bag.gt.rotation_deg[-1] == pytest.approx(-forwards.rotation_deg[-1])
    assert bag.gt.scale[-1] == pytest.approx(1 / forwards.scale[-1])


def test_one_sequence_asked_for_where_there_is_none_says_why(tmp_path):
    """load_ground_truth and run_one on a folder that looks like a sequence but is not one say what it lacks (they
    said only that it holds 0 sequences)."""
    folder = _images(tmp_path / "walk" / "img", 3).parent
    for call, expected in ((load_ground_truth, "give one sequence folder or ground-truth file"),
                           (lambda path: run_one(path, "fixed"), "run_one takes one")):
        with pytest.raises(UsageError) as caught:
            call(folder)
        assert str(caught.value) == (
            f"'{folder}' holds 0 sequences: it has images in '{folder / 'img'}' but no ground truth beside them; with "
            f"images there lptrack reads groundtruth_rect.txt (OTB) or walk.txt (UAV123); {expected}"
            + (" (.gt.csv, groundtruth_rect.txt, groundtruth.txt, <name>.txt)" if call is load_ground_truth else ""))


def _named_images(folder: Path, names: list[str]) -> Path:
    """Tiny frames named as given, the k-th (in the order given) of grey level 10 * (k + 1)."""
    folder.mkdir(parents=True, exist_ok=True)
    for k, name in enumerate(names):
        cv2.imwrite(str(folder / name), np.full((32, 48, 3), 10 * (k + 1), np.uint8))
    return folder


def _lasot(root: Path, name: str, lines: list[str], occluded: list[int], out_of_view: list[int]) -> Path:
    """A LaSOT sequence as published: <class>/<class>-<n>/img/00000001.jpg ..., comma-separated groundtruth.txt, and
    the two flag files of one comma-separated line each."""
    seq = root / name.rsplit("-", 1)[0] / name
    _named_images(seq / "img", [f"{i:08d}.jpg" for i in range(1, len(lines) + 1)])
    (seq / "groundtruth.txt").write_text("".join(line + "\n" for line in lines))
    (seq / "full_occlusion.txt").write_text(",".join(map(str, occluded)))
    (seq / "out_of_view.txt").write_text(",".join(map(str, out_of_view)))
    (seq / "nlp.txt").write_text("white cat lying on the sofa\n")
    return seq


def test_lasot_root_class_folders_and_absent_frames(tmp_path):
    """A LaSOT root is read through its class folders (img/ + groundtruth.txt was skipped as a pair lptrack did not
    read); frames flagged fully occluded or out of view are not scored whatever their box (LaSOT leaves such boxes
    arbitrary: 1,1,-1,-1, or a plausible box where the target was last seen), and 1-based boxes move by -1 px."""
    root = tmp_path / "LaSOT"
    cat = _lasot(root, "cat-1", ["11,21,10,6", "12,21,10,6", "1,1,-1,-1", "40,30,10,6", "14,21,10,6"],
                 [0, 0, 1, 0, 0], [0, 0, 0, 1, 0])
    # A sequence whose first frame has its target out of view: the tracker starts on the next.
    _lasot(root, "cat-10", ["20,20,8,8", "21,21,8,8", "22,21,8,8"], [0, 0, 0], [1, 0, 0])
    _lasot(root, "bear-2", ["5,5,8,8", "6,5,8,8"], [0, 0], [0, 0])
    unread: list = []
    seqs = discover(root, unread)
    assert unread == []
    assert [(s.name, s.kind) for s in seqs] == [("bear-2", "lasot"), ("cat-1", "lasot"), ("cat-10", "lasot")]
    bear, first, late = seqs
    assert (first.path, first.gt_path, first.n_frames, first.start) == (cat, cat / "groundtruth.txt", 5, 0)
    assert first.gt.valid.tolist() == [True, True, False, False, True]  # line 4's box is plausible but flagged
    assert (first.roi.cx, first.roi.cy, first.roi.a, first.roi.b) == (15, 23, 5, 3)  # x = 11 - 1, + w / 2
    assert [int(f.mean()) for _, _, f in first.frames()] == pytest.approx([10, 20, 30, 40, 50], abs=2)
    assert (late.start, late.gt.valid.tolist(), late.roi.cx) == (1, [False, True, True], 24)  # 21 - 1 + 4
    assert first.fps == 30.0 and first.notes == ()
    # eval reads the file with its flags, as bench does.
    assert load_ground_truth(cat / "groundtruth.txt").valid.tolist() == [True, True, False, False, True]


def test_lasot_folder_without_its_flags_says_what_it_lacks(tmp_path):
    seq = _lasot(tmp_path, "cat-1", ["11,21,10,6", "12,21,10,6"], [0, 0], [0, 0])
    (seq / "out_of_view.txt").unlink()
    unread: list = []
    assert discover(tmp_path, unread) == []
    assert unread == [(seq, f"groundtruth.txt and images in '{seq / 'img'}' but not LaSOT's out_of_view.txt beside "
                            f"them, which say the frames where the target is absent; with images there lptrack reads "
                            f"groundtruth.txt with those (LaSOT), groundtruth_rect.txt (OTB) or cat-1.txt (UAV123)")]


def test_sequences_below_the_search_depth_are_said_to_be_skipped(tmp_path):
    """LaSOT extracted as published under /data/LaSOT is four levels below /data (LaSOT/LaSOTBenchmark/<class>/
    <class>-<n>): a root mixing it with GOT-10k (three down) ran GOT-10k's sequences and left LaSOT's out without a
    word. The class folders where the search stopped are now said to be skipped, and why."""
    lasot = tmp_path / "LaSOT" / "LaSOTBenchmark"
    _lasot(lasot, "cat-1", ["11,21,10,6", "12,21,10,6"], [0, 0], [0, 0])
    _lasot(lasot, "bear-2", ["5,5,8,8", "6,5,8,8"], [0, 0], [0, 0])
    _got10k(tmp_path / "GOT-10k" / "val", "GOT-10k_Val_000001", ["5,5,8,8"] * 3, absence=[0, 0, 0], cover=[8, 8, 8])
    unread: list = []
    assert [s.name for s in discover(tmp_path, unread)] == ["GOT-10k_Val_000001"]
    why = ("sub-folders below the 3 levels searched under a dataset; give a folder nearer its sequences (its parent, "
           "say) as the dataset")
    assert unread == [(lasot / "bear", why), (lasot / "cat", why)]
    assert [s.name for s in discover(tmp_path / "LaSOT", [])] == ["bear-2", "cat-1"]  # a folder nearer: all read
    # A folder at that depth with nothing below it, or only a sequence's frames, is not named.
    (tmp_path / "a" / "b" / "c" / "img").mkdir(parents=True)
    (tmp_path / "a" / "b" / "d").mkdir()
    unread = []
    discover(tmp_path, unread)
    assert [folder for folder, _ in unread] == [lasot / "bear", lasot / "cat"]


def _got10k(split: Path, name: str, lines: list[str], absence: list[int] | None, cover: list[int] | None) -> Path:
    """A GOT-10k sequence as published: frames in the folder, groundtruth.txt, one label per line, meta_info.ini, and
    the split's list.txt."""
    seq = split / name
    _named_images(seq, [f"{i:08d}.jpg" for i in range(1, 4 if absence is None else len(absence) + 1)])
    (seq / "groundtruth.txt").write_text("".join(line + "\n" for line in lines))
    for label, values in (("absence", absence), ("cover", cover), ("cut_by_image", absence)):
        if values is not None:
            (seq / f"{label}.label").write_text("".join(f"{v}\n" for v in values))
    (seq / "meta_info.ini").write_text("[METAINFO]\nobject_class: cat\nanno_fps: 10Hz\nresolution: (48, 32)\n")
    with open(split / "list.txt", "a") as f:
        f.write(name + "\n")
    return seq


def test_got10k_val_split_and_absent_frames(tmp_path):
    """GOT-10k's frames lie in the sequence folder beside groundtruth.txt, as VOT's do: it was read as VOT (0-based,
    every box scored). Frames with absence 1 or cover 0 are not scored, as the toolkit's evaluation leaves out
    frames whose cover is 0; boxes are 1-based; its frame rate is 10 fps."""
    split = tmp_path / "GOT-10k" / "val"
    seq = _got10k(split, "GOT-10k_Val_000001", ["11,21,10,6", "12,21,10,6", "0,0,0,0", "14,21,10,6", "15,21,10,6"],
                  absence=[0, 0, 1, 0, 0], cover=[8, 5, 0, 0, 7])
    _got10k(split, "GOT-10k_Val_000002", ["5,5,8,8"] * 3, absence=[0, 0, 0], cover=[8, 8, 8])
    unread: list = []
    seqs = discover(tmp_path, unread)
    assert unread == [] and [(s.name, s.kind) for s in seqs] == [("GOT-10k_Val_000001", "got10k"),
                                                                 ("GOT-10k_Val_000002", "got10k")]
    got = seqs[0]
    assert (got.path, got.n_frames, got.start, got.fps) == (seq, 5, 0, 10.0)
    assert got.gt.valid.tolist() == [True, True, False, False, True]  # absent, then fully covered
    assert (got.roi.cx, got.roi.cy, got.roi.a, got.roi.b) == (15, 23, 5, 3)  # x = 11 - 1, + w / 2
    assert [f.name for f in got.frame_files] == [f"{i:08d}.jpg" for i in range(1, 6)]
    assert load_ground_truth(seq / "groundtruth.txt").valid.tolist() == [True, True, False, False, True]


def test_got10k_test_split_is_said_to_be_unscorable(tmp_path):
    """The test split's groundtruth.txt holds the first frame's box only: the sequence was tracked and scored on its
    first frame, as a VOT folder; it is skipped, saying why."""
    split = tmp_path / "test"
    seq = _got10k(split, "GOT-10k_Test_000001", ["11,21,10,6"], absence=None, cover=None)
    why = ("groundtruth.txt with one line, the first frame's box (GOT-10k's test split, whose ground truth is kept for "
           "its evaluation server): nothing to score")
    unread: list = []
    assert discover(split, unread) == [] and unread == [(seq, why)]
    with pytest.raises(UsageError, match=r"holds 0 sequences: it has groundtruth\.txt with one line, the first "):
        load_ground_truth(seq / "groundtruth.txt")


def _trackingnet(split: Path, video: str, n_frames: int, lines: list[str]) -> Path:
    """A TrackingNet video as published: <split>/frames/<video>/0.jpg, 1.jpg, ... (unpadded) and
    <split>/anno/<video>.txt, with the split's zips/ beside them."""
    frames = _named_images(split / "frames" / video, [f"{i}.jpg" for i in range(n_frames)])
    (split / "anno").mkdir(exist_ok=True)
    (split / "anno" / f"{video}.txt").write_text("".join(line + "\n" for line in lines))
    (split / "zips").mkdir(exist_ok=True)
    return frames


def test_trackingnet_splits_unpadded_frame_names_and_test_split(tmp_path):
    """TrackingNet's frames (0.jpg ... 11.jpg) and boxes (anno/<video>.txt, 0-based) lie in two folders of its split:
    each video is a sequence, its frames in numeric order (10.jpg after 9.jpg). The test split's files have one line
    each: it is skipped, saying why."""
    root = tmp_path / "TrackingNet"
    lines = [f"{10 + i},20,10,6" for i in range(12)]
    frames = _trackingnet(root / "TRAIN_0", "a3Ck0U-5_EE_0", 12, lines)
    _trackingnet(root / "TRAIN_1", "B1b9kGnb1B8_1", 3, lines[:3])
    _trackingnet(root / "TEST", "zz0Rn1ja_0", 12, lines[:1])
    _trackingnet(root / "TEST", "zz0Rn1ja_1", 12, lines[:1])
    unread: list = []
    seqs = discover(root, unread)
    assert [(s.name, s.kind) for s in seqs] == [("a3Ck0U-5_EE_0", "trackingnet"), ("B1b9kGnb1B8_1", "trackingnet")]
    assert unread == [(root / "TEST", "2 videos whose anno/<video>.txt has one line, the first frame's box "
                                      "(TrackingNet's test split, whose ground truth is kept for its evaluation "
                                      "server): nothing to score")]
    seq = seqs[0]
    assert (seq.path, seq.gt_path, seq.n_frames, seq.start, seq.notes) == (
        frames, root / "TRAIN_0" / "anno" / "a3Ck0U-5_EE_0.txt", 12, 0, ())
    assert [f.name for f in seq.frame_files][8:] == ["8.jpg", "9.jpg", "10.jpg", "11.jpg"]
    assert [int(f.mean()) for _, _, f in seq.frames()] == pytest.approx([10 * (k + 1) for k in range(12)], abs=2)
    assert (seq.roi.cx, seq.roi.cy, seq.roi.a, seq.roi.b) == (15, 23, 5, 3)  # 0-based: x = 10, + w / 2
    assert seq.gt.valid.all()
    # One video's frames folder, or its anno file, is read as the same sequence (lptrack eval's ground truth).
    (alone,) = discover(frames)
    assert (alone.name, alone.gt_path, alone.roi) == (seq.name, seq.gt_path, seq.roi)
    np.testing.assert_array_equal(load_ground_truth(seq.gt_path).boxes, seq.gt.boxes)
    with pytest.raises(UsageError, match=r"holds 0 sequences: it has .*zz0Rn1ja_0\.txt of one line, the first "):
        load_ground_truth(root / "TEST" / "anno" / "zz0Rn1ja_0.txt")


def test_benchmark_ground_truth_without_its_frames_is_read_with_its_flags(tmp_path):
    """lptrack eval needs a run and its ground truth, not the frames: a LaSOT or GOT-10k groundtruth.txt copied with
    its labels but without the images (LaSOT's are 227 GB) was refused ('holds 0 sequences: it has groundtruth.txt
    but no images') where it had been read before LaSOT and GOT-10k were known, and a TrackingNet anno file whose
    frames are not extracted was read as 1-based. They are read as bench reads them with their frames: flags, origin,
    one row per line; a test split's single line is still refused."""
    lasot = _lasot(tmp_path / "with", "cat-1", ["11,21,10,6", "12,21,10,6", "1,1,-1,-1", "40,30,10,6", "14,21,10,6"],
                   [0, 0, 1, 0, 0], [0, 0, 0, 1, 0])
    got = _got10k(tmp_path / "with" / "val", "GOT-10k_Val_000001", ["11,21,10,6", "12,21,10,6", "-1,-1,-1,-1",
                                                                    "14,21,10,6", "15,21,10,6"],
                  absence=[0, 0, 1, 0, 0], cover=[8, 5, 0, 0, 7])
    tn = _trackingnet(tmp_path / "with" / "TRAIN_0", "a3Ck0U-5_EE_0", 4, [f"{10 + i},20,10,6" for i in range(4)])
    files = {"lasot": (lasot, ["groundtruth.txt", "full_occlusion.txt", "out_of_view.txt"]),
             "got10k": (got, ["groundtruth.txt", "absence.label", "cover.label", "meta_info.ini"]),
             "trackingnet": (tn.parent.parent / "anno", ["a3Ck0U-5_EE_0.txt"])}
    for kind, (folder, names) in files.items():
        alone = tmp_path / "alone" / kind / folder.name
        alone.mkdir(parents=True)
        for name in names:
            (alone / name).write_text((folder / name).read_text())
        if kind == "trackingnet":
            (alone.parent / "zips").mkdir()
        with_frames = load_ground_truth(folder / names[0])
        without = load_ground_truth(alone / names[0])
        assert without.source == kind
        np.testing.assert_array_equal(without.valid, with_frames.valid)
        np.testing.assert_array_equal(without.boxes, with_frames.boxes)
    assert load_ground_truth(tmp_path / "alone" / "lasot" / "cat-1" / "groundtruth.txt").valid.tolist() == [
        True, True, False, False, True]
    # Centre x: 0-based x = 10, + w / 2 (read as 1-based it was 14).
    assert load_ground_truth(tmp_path / "alone" / "trackingnet" / "anno" / "a3Ck0U-5_EE_0.txt").boxes[0, 0] == 15
    test = tmp_path / "alone" / "TEST"
    (test / "anno").mkdir(parents=True)
    (test / "zips").mkdir()
    (test / "anno" / "zz0Rn1ja_0.txt").write_text("10,20,10,6\n")
    with pytest.raises(UsageError, match=r"has one line, the first frame's box \(a test split's"):
        load_ground_truth(test / "anno" / "zz0Rn1ja_0.txt")
    (tmp_path / "alone" / "got10k" / "GOT-10k_Val_000001" / "absence.label").unlink()
    with pytest.raises(UsageError, match=r"is GOT-10k's, but no absence\.label is beside it"):
        load_ground_truth(tmp_path / "alone" / "got10k" / "GOT-10k_Val_000001" / "groundtruth.txt")


def test_a_sequence_with_no_box_to_start_from_is_named(tmp_path):
    """A LaSOT sequence flagged absent on every frame (or an OTB file of NaN lines) stops discovery, as before, but
    the error named no file: in a root of many sequences the user could not tell which."""
    seq = _lasot(tmp_path, "cat-1", ["11,21,10,6", "12,21,10,6"], [1, 0], [0, 1])
    with pytest.raises(GroundTruthError, match=re.escape(
            f"'{seq / 'groundtruth.txt'}' has no box to start the tracker from on any of the 2 images: every line is "
            f"NaN, empty (w or h <= 0), or flagged absent by full_occlusion.txt or out_of_view.txt")):
        discover(tmp_path)
    otb = _otb(tmp_path / "otb", "walk", 2, ["NaN,NaN,NaN,NaN", "1,1,0,5"])
    with pytest.raises(GroundTruthError, match=re.escape(f"'{otb / 'groundtruth_rect.txt'}' has no box to start")):
        discover(otb)


def test_a_folder_of_sequences_with_a_frames_and_an_anno_folder_is_still_searched(tmp_path):
    """A folder holding frames/ and anno/ is read as a TrackingNet split; its other folders were then not searched,
    so OTB sequences beside a frames/ and an anno/ folder of the user's own, found before TrackingNet was read,
    were lost without a word. They are searched as in any folder; the split's frames/, anno/ and zips/ are not."""
    root = tmp_path / "mine"
    (root / "frames").mkdir(parents=True)
    (root / "anno").mkdir()
    _otb(root, "walk", 3, ["11,21,10,6"] * 3)
    unread: list = []
    assert [(s.name, s.kind) for s in discover(root, unread)] == [("walk", "otb")] and unread == []
    _trackingnet(root, "a3Ck0U-5_EE_0", 3, ["10,20,10,6"] * 3)
    assert [(s.name, s.kind) for s in discover(root)] == [("a3Ck0U-5_EE_0", "trackingnet"), ("walk", "otb")]
