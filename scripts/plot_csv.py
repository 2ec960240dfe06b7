"""Reads the CSV tables coarsegrain writes (io::write_csv: a header row of column names, then
rows of numbers) for the plotting scripts beside this file, which import it.

Not a plot itself: `from plot_csv import read_table`.
"""
import sys

import numpy as np


def read_table(path, tool, required=()):
    """(header, data) of a table: the column names and a rows x columns array. Exits with
    "<tool>: <path>: ..." if the file cannot be read, lacks a required column or is not a table
    of numbers."""
    try:
        with open(path, encoding="utf-8") as f:
            header = f.readline().strip().split(",")
    except OSError as e:
        sys.exit(f"{tool}: cannot read {path}: {e}")
    missing = [c for c in required if c not in header]
    if missing:
        sys.exit(f"{tool}: {path}: missing column(s) {', '.join(missing)}")
    try:
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as e:
        sys.exit(f"{tool}: {path}: {e}")
    if data.shape[0] == 0 or data.shape[1] != len(header):
        sys.exit(f"{tool}: {path}: expected rows of {len(header)} numbers")
    return header, data
