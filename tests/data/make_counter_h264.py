"""Make counter_h264.mp4 and its damaged copies, the test videos of a damaged H.264 file (tests/test_video.py).

Run from this folder with FFmpeg (libx264) on the PATH: ``python make_counter_h264.py``. CI has no FFmpeg, so the
outputs are committed; this script is how they were made (FFmpeg 5.1, libx264 164).

counter_h264.mp4: 40 frames of 64x48 at 25 fps, H.264 with B-frames and a key frame every 10 frames, each frame
showing its own number (8 blocks of 16x16, white for a 1 bit, bit 0 top left, row by row) over a seeded noise
texture. damaged_h264.mp4: the same with the packets of frames 14-18 (presentation order) zeroed, as a failing card
does. FFmpeg refuses them as OpenCV reads them, before the frames its decoder still holds for reordering come out
(the first refusal before frames 9-11, the other four before 12 and 13): a reader counting refusals as frames
numbered frames 9-13 as 10-12, 17 and 18. truncated_h264.mp4: counter_h264.mp4's first 70 % of bytes, cut in the
packet of key frame 20; its refusal came before frames 18 and 19, numbered 19 and 20. damaged_vfr_h264.mp4: a
varying rate (see main), whose lost frames were counted at its average rate: 2 where 3 are lost.
damaged_gop_h264.mp4: counter_h264.mp4's frames without B-frames, 200 bytes at 2262 overwritten with seeded random
bytes (made with the FFmpeg 9.0 of the imageio-ffmpeg wheel): frames 7-15 lost for 4 refusals, numbered 11 on when
each refusal counted at most a frame. damaged_late_h264.mp4: counter_h264.mp4 with 400 bytes at 2702 garbled
likewise: frames 9-17 lost, and frame 9's picture comes out after 18's, which numbered every later frame one late.
"""

import random
import subprocess
from pathlib import Path

import numpy as np

N, W, H, FPS = 40, 64, 48, 25
LOST = range(14, 19)


def frames():
    rng = np.random.default_rng(7)
    texture = rng.integers(60, 196, (H, W), dtype=np.uint8)
    for n in range(N):
        frame = np.roll(texture, n, axis=1).copy()
        for bit in range(8):
            row, col = divmod(bit, 4)
            frame[row * 16:row * 16 + 16, col * 16:col * 16 + 16] = 255 if n >> bit & 1 else 0
        yield np.repeat(frame[:, :, None], 3, axis=2)


def encode(raw: bytes, out: str, *filters: str, b_frames: int = 3) -> None:
    subprocess.run(["ffmpeg", "-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", "bgr24", "-s", f"{W}x{H}", "-r",
                    str(FPS), "-i", "-", *filters, "-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "28", "-bf",
                    str(b_frames),
                    "-g", "10", "-keyint_min", "10", "-sc_threshold", "0", "-movflags", "+faststart", out],
                   input=raw, check=True)


def zero_packets(path: str, lost, out: str) -> None:
    """``path`` with the packets of the frames stamped at ``lost`` (in frames of 1 / FPS) zeroed, into ``out``."""
    packets = subprocess.run(["ffprobe", "-v", "error", "-select_streams", "v", "-show_entries",
                              "packet=pts_time,pos,size", "-of", "csv=p=0", path],
                             capture_output=True, text=True, check=True).stdout.split()
    data = bytearray(Path(path).read_bytes())
    for line in packets:
        pts, size, pos = line.split(",")
        if round(float(pts) * FPS) in lost:
            data[int(pos):int(pos) + int(size)] = bytes(int(size))
    Path(out).write_bytes(data)


def main():
    raw = b"".join(f.tobytes() for f in frames())
    encode(raw, "counter_h264.mp4")
    zero_packets("counter_h264.mp4", LOST, "damaged_h264.mp4")
    intact = Path("counter_h264.mp4").read_bytes()
    Path("truncated_h264.mp4").write_bytes(intact[:len(intact) * 7 // 10])
    # A varying rate: frames 10-19 left out with their stamps (a phone's pause), 30 frames whose container reports
    # 18.75 fps on average; then the packets of the frames stamped 33-35 (its frames 23-25) zeroed.
    encode(raw, "vfr.tmp.mp4", "-vf", "select='not(between(n,10,19))'", "-fps_mode", "passthrough")
    zero_packets("vfr.tmp.mp4", range(33, 36), "damaged_vfr_h264.mp4")
    Path("vfr.tmp.mp4").unlink()
    # Stretches of bytes garbled (not packets zeroed): without B-frames fewer refusals than frames lost; with them
    # also a lost frame's picture out of order.
    encode(raw, "gop.tmp.mp4", b_frames=0)
    garble("gop.tmp.mp4", 87, 2262, 200, "damaged_gop_h264.mp4")
    Path("gop.tmp.mp4").unlink()
    garble("counter_h264.mp4", 77, 2702, 400, "damaged_late_h264.mp4")


def garble(path: str, seed: int, start: int, length: int, out: str) -> None:
    """``path`` with ``length`` bytes from ``start`` overwritten with random bytes of ``seed``, into ``out``."""
    data = bytearray(Path(path).read_bytes())
    rnd = random.Random(seed)
    rnd.randrange(len(data) // 3, len(data) - 300), rnd.choice([100, 200, 400, 800])  # the draws that chose these
    data[start:start + length] = bytes(rnd.randrange(256) for _ in range(length))
    Path(out).write_bytes(data)


if __name__ == "__main__":
    main()
