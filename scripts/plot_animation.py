#!/usr/bin/python3
"""Animates the fine model and every method side by side: one panel per model, the body drawn
in a view plane, deformed and coloured by |u| on one colour scale, one frame per saved time.

Usage: /usr/bin/python3 scripts/plot_animation.py OUT.gif ANIMATION_DATA.bin

ANIMATION_DATA.bin is written by `coarsegrain simulate` (animation_data.bin): one line of JSON
(the header), then little-endian binary arrays:
  float32 rest[points][2]            rest positions in the view plane (axes header["axes"])
  int32   faces[faces][face_size]    polygons by point, back to front (none: draw the points)
  float32 frames[models][frames][points][3]
                                     per model and frame: the displacement in the view plane
                                     (2 values) and |u| (the full displacement's magnitude)
Header keys: format ("coarsegrain-animation"), version (1), scene, axes (two axis names),
dropped (the axis looked along, null in 2D), scale (the factor the displacement is drawn
with: 1 is true scale), models (names, "fine" first), times (one per frame), points, faces,
face_size.
"""
import json
import math
import os
import sys

import numpy as np

FRAME_MS = 100  # 10 frames per second


def fail(message):
    sys.exit(f"plot_animation: {message}")


def read(path):
    """(header, rest, faces, frames): frames is models x frames x points x 3."""
    try:
        with open(path, "rb") as f:
            header = json.loads(f.readline().decode("utf-8"))
            if header.get("format") != "coarsegrain-animation" or header.get("version") != 1:
                fail(f"{path}: not a coarsegrain-animation version 1 file")
            n, nf, k = header["points"], header["faces"], header["face_size"]
            models, times = header["models"], header["times"]
            rest = np.fromfile(f, dtype="<f4", count=2 * n)
            faces = np.fromfile(f, dtype="<i4", count=nf * k)
            count = len(models) * len(times) * n * 3
            frames = np.fromfile(f, dtype="<f4", count=count)
            extra = f.read(1)
    except (OSError, ValueError, KeyError, TypeError) as e:
        fail(f"cannot read {path}: {e}")
    if rest.size != 2 * n or faces.size != nf * k or frames.size != count or extra:
        fail(f"{path}: the arrays do not have the sizes the header gives")
    faces = faces.reshape(nf, k)
    if nf and (faces.min() < 0 or faces.max() >= n):
        fail(f"{path}: a face refers to a point that does not exist")
    if not models or not times or n == 0:
        fail(f"{path}: no model, frame or point to draw")
    frames = frames.reshape(len(models), len(times), n, 3)
    return header, rest.reshape(n, 2), faces, frames


def layout(count, aspect):
    """(columns, rows, panel width in inches) that make the panels largest in about 11 x 7.5
    inches."""
    best = None
    for cols in range(1, count + 1):
        rows = math.ceil(count / cols)
        width = min(11.0 / cols, 7.5 / rows * aspect, 5.5)
        if best is None or width > best[2] + 1e-9:
            best = (cols, rows, width)
    return best


def palette_image(cmap):
    """A 'P' image whose palette is 192 colours of the colour map, then 64 greys (the text and
    the white background): every frame is mapped to it, so the colours stay the same from frame
    to frame and the colour bar keeps its gradient."""
    from PIL import Image

    ramp = (np.asarray(cmap(np.linspace(0, 1, 192)))[:, :3] * 255).round()
    greys = np.repeat(np.linspace(0, 255, 64)[:, None], 3, axis=1).round()
    image = Image.new("P", (1, 1))
    image.putpalette(np.vstack([ramp, greys]).astype(np.uint8).ravel().tolist())
    return image


class Panel:
    """One model's drawing. Polygons are paths whose vertices are views of one array, so a
    frame updates them all with one array assignment (matplotlib keeps the float64 array a
    Path is given; if it copied, each frame would set the paths anew)."""

    def __init__(self, ax, rest, faces, cmap, norm, marker_size):
        from matplotlib.collections import PathCollection
        from matplotlib.path import Path

        self.faces = faces
        if len(faces):
            self.xy = np.zeros((len(faces), faces.shape[1], 2))
            paths = [Path(v, closed=False) for v in self.xy]
            self.shared = np.shares_memory(paths[0].vertices, self.xy)
            # Without antialiasing neighbouring polygons leave no seams between them, and the
            # flat colours compress well in the GIF.
            self.artist = PathCollection(paths, cmap=cmap, norm=norm, edgecolors="none",
                                         linewidths=0, antialiased=False)
            ax.add_collection(self.artist)
        else:
            self.artist = ax.scatter(rest[:, 0], rest[:, 1], c=np.zeros(len(rest)), cmap=cmap,
                                     norm=norm, s=marker_size, marker="s", linewidths=0)

    def update(self, xy, magnitude):
        """Points at xy (points x 2), coloured by magnitude (per point)."""
        from matplotlib.path import Path

        if not len(self.faces):
            self.artist.set_offsets(xy)
            self.artist.set_array(magnitude)
            return
        self.xy[...] = xy[self.faces]
        if not self.shared:
            self.artist.set_paths([Path(v, closed=False) for v in self.xy])
        self.artist.set_array(magnitude[self.faces].mean(axis=1))


def draw(header, rest, faces, frames, out):
    import matplotlib.pyplot as plt
    from matplotlib import colors
    from PIL import Image

    models, times, scale = header["models"], header["times"], header["scale"]
    moved = rest[None, None] + scale * frames[..., :2]  # models x frames x points x 2
    lo, hi = moved.reshape(-1, 2).min(axis=0), moved.reshape(-1, 2).max(axis=0)
    span = np.maximum(hi - lo, 1e-12 * max(hi - lo))
    lo, hi = lo - 0.04 * span.max(), hi + 0.04 * span.max()
    aspect = (hi[0] - lo[0]) / (hi[1] - lo[1])
    cols, rows, width = layout(len(models), aspect)
    height = width / aspect
    title_h, top_h, bar_w = 0.3, 0.75, 1.3
    # At least 7 inches wide, for the title lines.
    fig_w, fig_h = max(cols * width + bar_w, 7.0), rows * (height + title_h) + top_h
    fig = plt.figure(figsize=(fig_w, fig_h), dpi=80)
    norm = colors.Normalize(0.0, max(float(frames[..., 2].max()), 1e-30))
    cmap = plt.get_cmap("viridis")
    marker_size = (72 * width * 1.2 / math.sqrt(len(rest))) ** 2  # squares about touching
    panels = []
    for i, name in enumerate(models):
        r, c = divmod(i, cols)
        y0 = 1 - (top_h + r * (height + title_h) + title_h + height) / fig_h
        ax = fig.add_axes([c * width / fig_w, y0, width / fig_w, height / fig_h])
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal")
        ax.set_axis_off()
        ax.set_title(name, fontsize=11, fontweight="bold" if name == "fine" else "normal")
        panels.append(Panel(ax, rest, faces, cmap, norm, marker_size))
    bar = fig.add_axes([(cols * width + 0.25) / fig_w, 0.12, 0.18 / fig_w, 0.7])
    fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cmap), cax=bar, label="|u|")
    axes = "-".join(header["axes"])
    view = f"{axes} plane" + (f" (looking along {header['dropped']})" if header["dropped"] else "")
    shown = "true scale" if scale == 1 else f"displacement drawn x{scale:.3g}"
    scene = os.path.basename(header.get("scene", ""))
    fig.text(0.01, 1 - 0.28 / fig_h, f"{scene}: {view}, {shown}", fontsize=11, va="center")
    clock = fig.text(0.01, 1 - 0.55 / fig_h, "", fontsize=11, va="center", family="monospace")

    # Everything but the bodies and the clock is drawn once; each frame draws those over it.
    for p in panels:
        p.artist.set_visible(False)
    fig.canvas.draw()
    background = fig.canvas.copy_from_bbox(fig.bbox)
    for p in panels:
        p.artist.set_visible(True)
    palette = palette_image(cmap)
    images = []
    for j, t in enumerate(times):
        fig.canvas.restore_region(background)
        for i, p in enumerate(panels):
            p.update(moved[i, j], frames[i, j, :, 2])
            p.artist.axes.draw_artist(p.artist)
        clock.set_text(f"t = {t:.4g}   (frame {j + 1} of {len(times)})")
        fig.draw_artist(clock)
        rgba = Image.frombuffer("RGBA", fig.canvas.get_width_height(), fig.canvas.buffer_rgba(),
                                "raw", "RGBA", 0, 1)
        images.append(rgba.convert("RGB").quantize(palette=palette, dither=Image.Dither.NONE))
    plt.close(fig)
    images[0].save(out, save_all=True, append_images=images[1:], duration=FRAME_MS, loop=0)


def main(argv):
    if len(argv) != 2:
        sys.exit(__doc__)
    out, path = argv
    header, rest, faces, frames = read(path)
    # Imported only once the input is known to be good: a bad file fails fast.
    import matplotlib

    matplotlib.use("Agg")
    draw(header, rest, faces, frames, out)


if __name__ == "__main__":
    main(sys.argv[1:])
