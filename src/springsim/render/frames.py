"""Simulating a scene for a video: the frames of the one frame sampler (``springsim.sampling``)."""


def simulate_frames(sim, duration: float, fps: float, progress: bool = True):
    """Times (F,) and positions (F, P, 3) of the frames of ``duration`` s at ``fps``: frame k is
    the state ``round(k / (fps dt))`` steps after the current one, the last at ``duration``.

    Rounding each frame's own step count, not a fixed number of steps per frame, keeps the video
    in real time when 1 / fps is not a whole number of steps (dt = 1/60 s at 25 fps)."""
    from ..recording import record

    recording = record(sim, duration, fps, progress=progress)
    return recording.time, recording.positions
