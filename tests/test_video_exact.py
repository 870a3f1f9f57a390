"""Video files are read frame for frame as decoded: no frame duplicated to fit
a nominal rate, the true count however many the header announces, and a
clear message naming that count when a selection runs past the end."""
from __future__ import annotations

import cv2
import imageio_ffmpeg
import numpy as np
import pytest

from ivkernels.io import probe_frames, read_frames
from ivkernels.colour import srgb_to_linear

T, H, W = 8, 24, 32


def _distinct_frames(n=T):
    """Frames that differ strongly from each other (a random texture each)."""
    rng = np.random.default_rng(7)
    base = rng.integers(0, 256, (n, H // 8, W // 8, 3), dtype=np.uint8)
    return np.repeat(np.repeat(base, 8, axis=1), 8, axis=2)


def _encode(path, frames, codec, output_params):
    writer = imageio_ffmpeg.write_frames(str(path), (W, H), fps=25, codec=codec, pix_fmt_out="yuv420p",
                                         macro_block_size=1, ffmpeg_log_level="error",
                                         output_params=output_params)
    writer.send(None)
    for f in frames:
        writer.send(np.ascontiguousarray(f))
    writer.close()
    return path


@pytest.fixture(scope="module")
def videos(tmp_path_factory):
    d = tmp_path_factory.mktemp("videos")
    frames = _distinct_frames()
    return frames, {
        # a gap in the timestamps after the first frame (a variable frame rate)
        "gap.mkv": _encode(d / "gap.mkv", frames, "libx264",
                           ["-vf", "setpts='if(eq(N,0),0,N+1)'", "-fps_mode", "passthrough"]),
        # the header says 50 fps, the frames come at 25: the header counts twice the frames
        "h50.avi": _encode(d / "h50.avi", frames, "mpeg4",
                           ["-vf", "settb=1/50,setpts=2*N", "-fps_mode", "passthrough",
                            "-enc_time_base", "1/50", "-q:v", "2"]),
        "plain.mp4": _encode(d / "plain.mp4", frames, "libx264", []),
    }


def _opencv_frames(path):
    cap = cv2.VideoCapture(str(path))
    out = []
    while True:
        ok, f = cap.read()
        if not ok:
            break
        out.append(f[:, :, ::-1])
    cap.release()
    return np.stack(out)


@pytest.mark.parametrize("name", ["gap.mkv", "h50.avi", "plain.mp4"])
def test_frames_are_those_opencv_decodes(videos, name):
    source, paths = videos
    ref = srgb_to_linear(_opencv_frames(paths[name]).astype(np.float32) / 255)
    assert ref.shape[0] == T
    got = read_frames(paths[name])
    assert got.shape == (T, H, W, 3)
    # each frame read is OpenCV's frame of the same index, and no other
    dist = np.abs(got[:, None] - ref[None]).mean(axis=(2, 3, 4))
    assert np.array_equal(dist.argmin(axis=1), np.arange(T)), dist
    assert np.diag(dist).max() < 0.01
    # and the first two frames differ (a duplicated first frame made frame 1 equal frame 0)
    assert np.abs(got[1] - got[0]).mean() > 0.05


def test_a_selection_counts_decoded_frames(videos):
    _, paths = videos
    full = read_frames(paths["gap.mkv"])
    np.testing.assert_array_equal(read_frames(paths["gap.mkv"], start=1, stop=7, step=2), full[1:7:2])


def test_header_that_over_counts_is_not_damage(videos):
    _, paths = videos
    assert probe_frames(paths["h50.avi"])[0] == 2 * T          # the header's estimate
    assert read_frames(paths["h50.avi"]).shape[0] == T          # what decodes
    assert read_frames(paths["h50.avi"], start=T - 2).shape[0] == 2


@pytest.mark.parametrize("kwargs, match", [
    ({"stop": T + 5}, rf"stop {T + 5} \(--stop\) is past the end of video file .* which holds {T} "
                      rf"frames \(0 to {T - 1}\); give a stop of at most {T}"),
    ({"start": 2 * T - 1}, rf"start {2 * T - 1} \(--start\) is past the end of .* holds {T} frames"),
])
def test_past_the_end_names_the_real_count(videos, kwargs, match):
    _, paths = videos
    with pytest.raises(ValueError, match=match):
        read_frames(paths["h50.avi"], **kwargs)


def test_past_the_end_of_a_folder_names_the_count(tmp_path):
    for t in range(3):
        cv2.imwrite(str(tmp_path / f"f{t}.png"), np.full((8, 8, 3), 40 * t, np.uint8))
    with pytest.raises(ValueError, match=r"stop 5 \(--stop\) is past the end of folder .* holds 3 frames"):
        read_frames(tmp_path, stop=5)
    with pytest.raises(ValueError, match=r"stop 4 .* holds 3 frames"):
        probe_frames(tmp_path, stop=4)
    assert read_frames(tmp_path, stop=3).shape[0] == 3
