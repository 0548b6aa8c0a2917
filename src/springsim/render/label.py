"""The simulated time written into the corner of a video frame."""
import numpy as np
from PIL import Image, ImageDraw, ImageFont

from .colors import LABEL_COLOR


def stamp_time(frame: np.ndarray, seconds: float) -> np.ndarray:
    """A copy of the (H, W, 3) frame with "t = 1.23 s" in its top-left corner."""
    image = Image.fromarray(frame)
    height = frame.shape[0]
    size = max(10, height // 24)
    try:
        font = ImageFont.load_default(size=size)
    except TypeError:  # Pillow without FreeType: the fixed bitmap font
        font = ImageFont.load_default()
    ImageDraw.Draw(image).text((size // 2, size // 3), f"t = {seconds:.2f} s", fill=LABEL_COLOR,
                               font=font)
    return np.asarray(image)
