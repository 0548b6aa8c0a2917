"""The documentation's gallery: a short GIF and a still PNG of every built-in scene, made from the
scenes themselves with the headless renderer (``springsim render``, polyscope on EGL).

    .venv/bin/python scripts/make_gallery.py [--scenes NAME,...] [--out docs/images]

Each scene is simulated and drawn once, into a folder of PNG frames; the GIF
(``gallery-NAME.gif``) is made from those frames and the still (``gallery-NAME.png``) is the last
one. Sizes are kept modest (320 x 180 px, 10 frames per simulated
second, at most 3 s) so that the whole gallery stays around a few MB in the repository. The camera
is the default one (it frames what moves and follows it: the cape is seen from behind). The
gallery page (docs/gallery.md) is generated at every build of the site from the list of built-in
scenes and links these files, so a new scene without pictures fails the strict build.
"""
import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from PIL import Image

ROOT = Path(__file__).resolve().parents[1]
WIDTH, HEIGHT, FPS, LONGEST = 320, 180, 10, 3.0


def render_scene(name: str, duration: float, out: Path) -> None:
    with tempfile.TemporaryDirectory(prefix="springsim-gallery-") as folder:
        frames = Path(folder) / "frames"
        subprocess.run([sys.executable, "-m", "springsim", "render", name, "--out", str(frames),
                        "--duration", f"{duration:g}", "--fps", str(FPS), "--width", str(WIDTH),
                        "--height", str(HEIGHT), "--quiet"], check=True)
        images = [Image.open(path).convert("RGB") for path in sorted(frames.glob("*.png"))]
        if not images:
            raise SystemExit(f"springsim render wrote no frames for {name}")
        images[-1].save(out / f"gallery-{name}.png", optimize=True)
        # one shared palette keeps the GIF small and free of per-frame colour flicker
        palette = images[len(images) // 2].quantize(colors=64, method=Image.Quantize.MEDIANCUT)
        frames_p = [image.quantize(palette=palette, dither=Image.Dither.NONE) for image in images]
        frames_p[0].save(out / f"gallery-{name}.gif", save_all=True, append_images=frames_p[1:],
                         duration=int(1000 / FPS), loop=0, optimize=True)


def main() -> int:
    from springsim.presets import PRESETS, preset

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenes", default=",".join(PRESETS),
                        help="comma-separated built-in scenes (default: all)")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "images")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    for name in args.scenes.split(","):
        duration = min(preset(name).duration, LONGEST)
        started = time.perf_counter()
        render_scene(name, duration, args.out)
        print(f"{name}: {duration:g} s simulated, {time.perf_counter() - started:.0f} s wall",
              flush=True)
    total = sum(path.stat().st_size for path in args.out.glob("gallery-*"))
    print(f"{args.out}: {total / 1e6:.2f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
