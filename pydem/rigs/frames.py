"""The hopper rig's frames as seed 001 sees them: each rendered frame centre-cropped to 224 x 224
and greyed (the seed's pre-processing, done once here as a documented, tested step instead of
keeping the raw 420 x 230 RGB frames), and what a grey frame's levels mean. The study that reads
the frames (pydem.seed001) stores them; the rig only draws them.

Grey: ITU-R BT.601 luma, round(0.299 R + 0.587 G + 0.114 B) — what PIL's convert("L") gives."""
from __future__ import annotations

import numpy as np

CROP = 224

# What a grey frame's levels mean (libdem's DEM_COLOR_GREY, as the hopper rig draws its frames):
# coarse spheres (material 0) at 70 and fine ones (material 2) at 110, each shaded by 0.45-1
# across its disk; walls drawn at 40, background 255. A pixel brighter than 70 can only be a
# fine sphere, one darker than 0.45 x 110 only a coarse one (or a wall): each band covers a
# fixed share of its species' disks, so its pixel count follows that species' visible area.
FINE_GREYS = (71, 110)
COARSE_GREYS = (32, 49)
WALL_GREY = 40


def crop_grey(rgb: np.ndarray, size: int = CROP) -> np.ndarray:
    """(H, W, 3) uint8 -> (size, size) uint8: the centre crop (the extra row/column of an odd
    margin dropped at the end), then BT.601 luma rounded to the nearest integer."""
    h, w = rgb.shape[:2]
    if rgb.ndim != 3 or rgb.shape[2] != 3 or h < size or w < size:
        raise ValueError(f"crop_grey: an (H >= {size}, W >= {size}, 3) image is needed, got {rgb.shape}")
    top, left = (h - size) // 2, (w - size) // 2
    c = rgb[top:top + size, left:left + size].astype(np.float64)
    return np.rint(c @ np.array([0.299, 0.587, 0.114])).clip(0, 255).astype(np.uint8)
