#!/usr/bin/python3
"""Plots per-level diagnostics of material-adapted hierarchies (Chen et al. 2019, Figs. 8, 9).

Usage: /usr/bin/python3 scripts/plot_mra.py OUT.png A.csv [B.csv ...] [--cond COND.png]

Each CSV is a table mra_levels.csv (coarsegrain::mra::levels_table, one row per level).
OUT.png gets the homogenization error ||u^k - u||_A / ||g||_2 against the level (log y, Fig. 9), one line per
CSV labelled by its file name (by its folder's name if several files share one); --cond additionally writes cond(A^k) and cond(B^k) (Fig. 8).
"""
import os
import sys

import numpy as np

REQUIRED = ["level", "error_over_g", "cond_A", "cond_B"]


def read_csv(path):
    try:
        with open(path, encoding="utf-8") as f:
            lines = [line.strip() for line in f if line.strip()]
    except OSError as e:
        sys.exit(f"plot_mra: cannot read {path}: {e}")
    if len(lines) < 2:
        sys.exit(f"plot_mra: {path}: expected a header row and at least one level row")
    header = lines[0].split(",")
    missing = [c for c in REQUIRED if c not in header]
    if missing:
        sys.exit(f"plot_mra: {path}: missing column(s) {', '.join(missing)}")
    rows = []
    for n, line in enumerate(lines[1:], start=2):
        cells = line.split(",")
        if len(cells) != len(header):
            sys.exit(f"plot_mra: {path}:{n}: {len(cells)} fields, header has {len(header)}")
        try:
            rows.append([float(c) for c in cells])
        except ValueError as e:
            sys.exit(f"plot_mra: {path}:{n}: {e}")
    data = np.array(rows)
    return {name: data[:, i] for i, name in enumerate(header)}


def csv_label(path, paths):
    """The file name without extension, or its folder's name if several files share it."""
    names = [os.path.splitext(os.path.basename(p))[0] for p in paths]
    name = os.path.splitext(os.path.basename(path))[0]
    if names.count(name) > 1:
        return os.path.basename(os.path.dirname(os.path.abspath(path)))
    return name


def main(argv):
    args = list(argv)
    cond_png = None
    if "--cond" in args:
        i = args.index("--cond")
        if i + 1 >= len(args):
            sys.exit("plot_mra: --cond needs a file name")
        cond_png = args[i + 1]
        del args[i : i + 2]
    if len(args) < 2:
        sys.exit(__doc__)
    out, csvs = args[0], args[1:]
    tables = [(csv_label(p, csvs), read_csv(p)) for p in csvs]

    # Imported only once the input is known to be good: a bad CSV fails fast.
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker  # noqa: F401 (used as matplotlib.ticker)

    fig, ax = plt.subplots(figsize=(5, 4))
    for label, t in tables:
        # The finest level's error is 0 by construction: not drawable on a log axis.
        positive = t["error_over_g"] > 0
        ax.semilogy(t["level"][positive], t["error_over_g"][positive], "o-", label=label)
    ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
    ax.set_xlabel("level k")
    ax.set_ylabel(r"$\|u^k - u\|_A / \|g\|_2$")
    ax.set_title("Homogenization error")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)

    if cond_png:
        fig, ax = plt.subplots(figsize=(5, 4))
        for label, t in tables:
            ax.semilogy(t["level"], t["cond_A"], "o-", label=f"{label} A")
            finite = np.isfinite(t["cond_B"])
            ax.semilogy(t["level"][finite], t["cond_B"][finite], "s--", label=f"{label} B")
        ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
        ax.set_xlabel("level k")
        ax.set_ylabel("condition number")
        ax.legend()
        fig.tight_layout()
        fig.savefig(cond_png, dpi=120)
        plt.close(fig)


if __name__ == "__main__":
    main(sys.argv[1:])
