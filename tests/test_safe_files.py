"""Files are written whole or not at all, for every writer, whatever happens while writing.

Oracles: after a write fails for lack of space (the file-size limit of the writing process, which
the kernel enforces like a full disk, and which also stops the ffmpeg it starts), the previous
file is byte for byte what it was, nothing else is left in the folder, and the command exits 5
with one line; a symbolic link planted at the target or at the old, predictable temporary name
is never followed (the file it points to is unchanged); SIGTERM during a write leaves the old
file and no temporary file, and the command exits 143.
"""
import os
import signal
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from springsim.errors import OutputFailed
from springsim.render.video import FrameWriter
from springsim.safe_files import atomic_output, check_output_path

SMALL = ["--set", "bodies.0.particles_per_edge=4", "--set", "bodies.0.position.1=2"]


def run_python(code: str, cwd, **options):
    return subprocess.Popen([sys.executable, "-c", textwrap.dedent(code)], cwd=cwd,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **options)


def noise_frames(count, height=96, width=160):
    """Frames that compress badly, so that an MP4 of them is large."""
    rng = np.random.default_rng(0)
    return rng.integers(0, 256, (count, height, width, 3), dtype=np.uint8)


def test_a_full_disk_during_run_keeps_the_previous_npz_and_exits_5_with_one_line(tmp_path):
    good = tmp_path / "frames.npz"
    good.write_bytes(b"the previous, good file")
    # the size limit is set just before the NPZ is written, so compiling (and caching) the kernels
    # before it is not affected; the run's NPZ is about 0.2 MB
    process = run_python(f"""
        import resource, sys
        from springsim import cli, recording
        write_npz = recording.write_npz
        def write_on_a_full_disk(path, arrays):
            resource.setrlimit(resource.RLIMIT_FSIZE, (65536, 65536))
            write_npz(path, arrays)
        recording.write_npz = write_on_a_full_disk
        sys.exit(cli.main(["run", "jelly-plane", *{SMALL!r}, "--duration", "0.5", "--out",
                           {str(good)!r}, "--quiet"]))
        """, tmp_path)
    out, err = process.communicate(timeout=300)
    assert (process.returncode, out) == (5, ""), err
    assert len(err.splitlines()) == 1, err
    assert err.startswith(f"springsim run: could not write {good}: File too large")
    assert good.read_bytes() == b"the previous, good file"
    assert os.listdir(tmp_path) == ["frames.npz"]


def test_ffmpeg_failing_on_a_full_disk_is_an_error_and_the_previous_mp4_stays(tmp_path):
    good = tmp_path / "movie.mp4"
    with FrameWriter(good, 12, 160, 96) as writer:
        for frame in noise_frames(3):
            writer.append(frame)
    before = good.read_bytes()
    process = run_python(f"""
        import resource
        import numpy as np
        from springsim.render.video import FrameWriter
        frames = np.random.default_rng(1).integers(0, 256, (40, 96, 160, 3), dtype=np.uint8)
        resource.setrlimit(resource.RLIMIT_FSIZE, (32768, 32768))   # ffmpeg inherits it
        with FrameWriter({str(good)!r}, 12, 160, 96) as writer:
            for frame in frames:
                writer.append(frame)
        """, tmp_path)
    out, err = process.communicate(timeout=300)
    assert process.returncode == 1
    assert f"springsim.errors.OutputFailed: could not write {good}: ffmpeg" in err
    assert good.read_bytes() == before
    assert os.listdir(tmp_path) == ["movie.mp4"]


def test_a_full_disk_during_render_keeps_the_previous_mp4_and_exits_5_with_one_line(tmp_path):
    """The issue's case: `springsim render --out x.mp4` on a full disk replaced a good MP4 with a
    truncated one and exited 0. The limit is set as ffmpeg starts, after the simulation."""
    good = tmp_path / "x.mp4"
    with FrameWriter(good, 12, 160, 96) as writer:
        writer.append(noise_frames(1)[0])
    before = good.read_bytes()
    process = run_python(f"""
        import resource, sys
        from springsim import cli
        from springsim.render import video
        start_ffmpeg = video.FfmpegPipe.__init__
        def on_a_full_disk(self, *args):
            resource.setrlimit(resource.RLIMIT_FSIZE, (8192, 8192))
            start_ffmpeg(self, *args)
        video.FfmpegPipe.__init__ = on_a_full_disk
        sys.exit(cli.main(["render", "jelly-plane", *{SMALL!r}, "--duration", "0.5", "--fps",
                           "24", "--width", "320", "--height", "180", "--out", {str(good)!r},
                           "--quiet"]))
        """, tmp_path)
    out, err = process.communicate(timeout=600)
    assert (process.returncode, out) == (5, ""), err
    assert len(err.splitlines()) == 1, err
    assert err.startswith(f"springsim render: could not write {good}: ffmpeg")
    assert good.read_bytes() == before
    assert os.listdir(tmp_path) == ["x.mp4"]


@pytest.mark.parametrize("suffix", [".gif", ".mp4", ""])
def test_a_writer_error_leaves_nothing_behind(tmp_path, suffix):
    with pytest.raises(RuntimeError, match="renderer broke"):
        with FrameWriter(tmp_path / f"movie{suffix}", 12, 64, 48) as writer:
            writer.append(noise_frames(1, 48, 64)[0])
            raise RuntimeError("renderer broke")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("suffix", [".gif", ".mp4"])
def test_a_planted_symbolic_link_is_never_followed(tmp_path, suffix):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    victim = elsewhere / "precious.txt"
    victim.write_text("keep me")
    folder = tmp_path / "out"
    folder.mkdir()
    target = folder / f"movie{suffix}"
    # the old writer's predictable temporary names, and the target itself
    for name in (f".{target.name}.partial-{os.getpid()}{suffix}",
                 f".{target.name}.partial-{os.getpid() + 1}{suffix}"):
        (folder / name).symlink_to(victim)
    target.symlink_to(victim)
    with FrameWriter(target, 12, 64, 48) as writer:
        for frame in noise_frames(2, 48, 64):
            writer.append(frame)
    assert victim.read_text() == "keep me"
    assert target.is_file() and not target.is_symlink() and target.stat().st_size > 100
    with atomic_output(folder / "data.bin") as file:
        file.write(b"new")
    assert victim.read_text() == "keep me"


def test_files_get_the_usual_mode_and_errors_name_the_target(tmp_path):
    mask = os.umask(0o022)
    try:
        with atomic_output(tmp_path / "a.bin") as file:
            file.write(b"x")
    finally:
        os.umask(mask)
    assert (tmp_path / "a.bin").stat().st_mode & 0o777 == 0o644
    with pytest.raises(OutputFailed, match=f"could not write {tmp_path / 'b.bin'}"):
        with atomic_output(tmp_path / "b.bin") as file:
            raise OSError(28, "No space left on device")
    assert os.listdir(tmp_path) == ["a.bin"]
    assert check_output_path("--out", tmp_path / "c.bin") == tmp_path / "c.bin"


def test_sigterm_while_writing_leaves_the_previous_file_and_no_temporary_one(tmp_path):
    good = tmp_path / "frames.npz"
    good.write_bytes(b"the previous, good file")
    process = run_python(f"""
        import sys, time
        import numpy as np
        from springsim import cli
        def slow_savez(file, **arrays):
            file.write(b"half of the frames")
            print("writing", flush=True)
            time.sleep(60)
        np.savez = slow_savez
        sys.exit(cli.main(["run", "jelly-plane", *{SMALL!r}, "--duration", "0.1", "--out",
                           {str(good)!r}, "--quiet"]))
        """, tmp_path)
    assert process.stdout.readline() == "writing\n"
    assert len(os.listdir(tmp_path)) == 2               # the staging folder exists now
    process.send_signal(signal.SIGTERM)
    out, err = process.communicate(timeout=60)
    assert (process.returncode, err) == (128 + signal.SIGTERM, "terminated\n")
    assert good.read_bytes() == b"the previous, good file"
    assert os.listdir(tmp_path) == ["frames.npz"]
