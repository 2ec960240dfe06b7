#!/usr/bin/python3
"""Writes the composite pattern of examples/composite_stress (Chen et al. 2019, Fig. 16).

Usage: /usr/bin/python3 examples/composite_stress/make_pattern.py

pattern.png: 64 x 64 pixels, one per fine cell, black = stiff, white = soft. A soft matrix
holding 14 stiff round particles of radii 3 to 7 pixels at random (seed 16) non-overlapping
places, at least 2 pixels apart and from the edges and skins, between two stiff skins 4 pixels thick
along the top and bottom edges (where the scene clamps and pulls). The PNG is committed;
rerun only to change the pattern.
"""
import os

import numpy as np
from PIL import Image  # installed with matplotlib

N = 64
PARTICLES = 14
GAP = 2  # pixels between particles, and between a particle and an edge
SKIN = 4  # pixels of stiff material along the top and bottom edges


def particles(rng):
    """(x, y, r) of each particle, in pixels, placed by rejection sampling."""
    placed = []
    while len(placed) < PARTICLES:
        r = rng.uniform(3, 7)
        x = rng.uniform(r + GAP, N - r - GAP)
        y = rng.uniform(r + GAP + SKIN, N - r - GAP - SKIN)
        if all(np.hypot(x - a, y - b) > r + c + GAP for a, b, c in placed):
            placed.append((x, y, r))
    return placed


def pattern():
    """N x N intensities (row 0 at the top): 0 in the stiff phase, 255 in the soft matrix."""
    i, j = np.meshgrid(np.arange(N), np.arange(N), indexing="ij")
    x, y = j + 0.5, N - i - 0.5  # pixel centres, y up
    stiff = (i < SKIN) | (i >= N - SKIN)
    for a, b, r in particles(np.random.default_rng(16)):
        stiff |= np.hypot(x - a, y - b) < r
    return np.where(stiff, 0, 255).astype(np.uint8)


def main():
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "pattern.png")
    Image.fromarray(pattern(), mode="L").save(out)  # 8-bit grayscale
    print(out)


if __name__ == "__main__":
    main()
