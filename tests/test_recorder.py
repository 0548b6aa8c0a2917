"""The viewer's Record button (viewer/recorder.py): the video plays at the speed the window was
seen, whatever rate the window draws at."""
import imageio.v2 as imageio_v2
import numpy as np
import pytest

from springsim.viewer.recorder import LONGEST_STILL, ScreenRecorder


class FakeClock:
    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def record(tmp_path, times, fps=30.0):
    """Draw one frame (a flat grey of level 10 k, k mod 25) at each of ``times`` (s); the frames read back
    and the number written after each draw."""
    clock = FakeClock()
    recorder = ScreenRecorder(tmp_path, fps=fps, clock=clock)
    recorder.start("test")
    written = []
    for k, t in enumerate(times):
        clock.now = 100.0 + t     # the clock's zero does not matter
        recorder.add(np.full((32, 48, 3), 10 * (k % 25), np.uint8))
        written.append(recorder.frames)
    path = recorder.stop()
    with imageio_v2.get_reader(path) as reader:
        levels = [int(np.median(frame)) for frame in reader]
    return levels, written


def test_slow_frames_are_repeated_and_fast_ones_dropped(tmp_path):
    # at 30 fps: t = 0.1 s is due frame 4, 0.15 s frame 5, 0.16 s none new, 0.2 s frames 6 and 7
    levels, written = record(tmp_path, [0.0, 0.1, 0.15, 0.16, 0.2])
    assert written == [1, 4, 5, 5, 7]
    expected = [0, 10, 10, 10, 20, 40, 40]     # the frame drawn at 0.16 s is never shown
    assert len(levels) == 7
    assert np.abs(np.array(levels) - expected).max() <= 2   # H.264 rounding


@pytest.mark.parametrize("fps", [30.0, 24.0])
def test_the_video_lasts_as_long_as_the_recording(tmp_path, fps):
    times = np.cumsum(np.full(40, 0.07))           # a window drawing at about 14 frames/s
    levels, written = record(tmp_path, times - times[0], fps=fps)
    duration = len(levels) / fps
    assert duration == pytest.approx(times[-1] - times[0], abs=1.0 / fps)


def test_a_long_pause_is_cut_short(tmp_path):
    levels, written = record(tmp_path, [0.0, 0.5, 30.0, 30.1])
    still = written[2] - written[1]
    assert still == int(LONGEST_STILL * 30)
    assert written[3] - written[2] == 3        # and the timing goes on from there
