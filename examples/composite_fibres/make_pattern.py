#!/usr/bin/python3
"""Writes the fibre composite of examples/composite_fibres (Chen et al. 2019, Fig. 16, second
object).

Usage: /usr/bin/python3 examples/composite_fibres/make_pattern.py

pattern.png: 64 x 64 pixels, one per fine cell, black = stiff, white = soft. A soft matrix
holding 12 stiff straight fibres 3 pixels wide and 16 to 28 pixels long, all inclined at 35
degrees to the x axis, at random (seed 16) places at least 2 pixels apart and from the edges and
skins, between two stiff skins 4 pixels thick along the top and bottom edges (where the scene
clamps and pulls). Unlike the round particles of examples/composite_stress, the fibres make the
square anisotropic: a vertical pull also shears it. The PNG is committed; rerun only to change
the pattern.
"""
import os

import numpy as np
from PIL import Image  # installed with matplotlib

N = 64
FIBRES = 12
WIDTH = 3.0  # pixels
ANGLE = np.radians(35.0)
GAP = 2  # pixels between fibres, and between a fibre and an edge or a skin
SKIN = 4  # pixels of stiff material along the top and bottom edges


def fibre_mask(x, y, cx, cy, length, grow):
    """Pixels within `grow` of the fibre centred at (cx, cy) (a 3-pixel-wide segment)."""
    ux, uy = np.cos(ANGLE), np.sin(ANGLE)
    along = (x - cx) * ux + (y - cy) * uy
    across = -(x - cx) * uy + (y - cy) * ux
    return (np.abs(along) <= length / 2 + grow) & (np.abs(across) <= WIDTH / 2 + grow)


def pattern():
    """N x N intensities (row 0 at the top): 0 in the stiff phase, 255 in the soft matrix."""
    i, j = np.meshgrid(np.arange(N), np.arange(N), indexing="ij")
    x, y = j + 0.5, N - i - 0.5  # pixel centres, y up
    inside = (x > GAP) & (x < N - GAP) & (y > SKIN + GAP) & (y < N - SKIN - GAP)
    fibres = np.zeros((N, N), dtype=bool)
    rng = np.random.default_rng(16)
    placed = 0
    while placed < FIBRES:
        length = rng.uniform(16, 28)
        cx, cy = rng.uniform(0, N), rng.uniform(SKIN, N - SKIN)
        grown = fibre_mask(x, y, cx, cy, length, GAP)
        if (grown & ~inside).any() or (grown & fibres).any():
            continue
        fibres |= fibre_mask(x, y, cx, cy, length, 0.0)
        placed += 1
    stiff = fibres | (i < SKIN) | (i >= N - SKIN)
    return np.where(stiff, 0, 255).astype(np.uint8)


def main():
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "pattern.png")
    Image.fromarray(pattern(), mode="L").save(out)  # 8-bit grayscale
    print(out)


if __name__ == "__main__":
    main()
