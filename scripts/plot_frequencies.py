#!/usr/bin/python3
"""Plots each method's natural frequencies against the fine model's, mode by mode.

Usage: /usr/bin/python3 scripts/plot_frequencies.py OUT.png FREQUENCIES.csv

FREQUENCIES.csv is written by `coarsegrain modes --method ...` (frequencies.csv): columns mode,
fine_hz, then <method>_hz (the coarse mode paired with each fine mode by the modal assurance
criterion) and <method>_mac for each method, one row per fine mode. Left: paired coarse against
fine frequency (the diagonal is exact); right: the relative error per mode.
"""
import sys

import numpy as np
from plot_csv import read_table


def main(argv):
    if len(argv) != 2:
        sys.exit(__doc__)
    out, path = argv
    header, data = read_table(path, "plot_frequencies", ("mode", "fine_hz"))
    if header[:2] != ["mode", "fine_hz"]:
        sys.exit(f"plot_frequencies: {path}: the first columns must be 'mode', 'fine_hz'")
    mode, fine = data[:, 0], data[:, 1]
    methods = [c[:-3] for c in header[2:] if c.endswith("_hz")]

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    low, top = fine.min(), fine.max()
    for m in methods:
        hz = data[:, header.index(m + "_hz")]
        low, top = min(low, hz.min()), max(top, hz.max())
        left.loglog(fine, hz, "o", label=m, alpha=0.8)
        right.semilogy(mode, np.maximum(np.abs(hz - fine) / fine, 1e-16), "o-", label=m)
    left.loglog([low, top], [low, top], "k--", linewidth=1, label="exact")
    left.set_xlabel("fine frequency (Hz)")
    left.set_ylabel("paired coarse frequency (Hz)")
    left.legend(fontsize=8)
    right.set_xlabel("fine mode")
    right.set_ylabel("|f_coarse - f_fine| / f_fine")
    right.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1:])
