#!/usr/bin/env python3
"""Draws one channel of a glint plane map (.exr) as a PNG, in metres along the plane's axes.

    /usr/bin/python3 examples/render_map.py out/cylinder_study/eye_level.exr \
        --channel coverage_probability --png coverage.png

Maps of `glint run` have irradiance_w_m2, hazard_ratio, level and status; maps of
`glint batch` have max_irradiance_w_m2, max_hazard_ratio and coverage_probability. Hazard
ratios are drawn on a log scale with the contour ratio = 1 (the MPE) in white; coverage on a
linear 0..1 scale with contours at 0.1, 0.5 and 0.9. Needs Debian's python3-openimageio and
python3-matplotlib.
"""
import argparse
import sys

import numpy as np
import OpenImageIO as oiio
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402


def read_map(path, channel):
    image = oiio.ImageInput.open(path)
    if image is None:
        sys.exit(f"render_map: cannot open {path}: {oiio.geterror()}")
    spec = image.spec()
    names = list(spec.channelnames)
    if channel not in names:
        sys.exit(f"render_map: {path} has no channel {channel} (it has {', '.join(names)})")
    c = names.index(channel)
    pixels = image.read_image(c, c + 1, "float")
    image.close()
    values = np.asarray(pixels, dtype=np.float64).reshape(spec.height, spec.width)
    pixel_m = spec.getattribute("glint_pixel_m")
    origin = spec.getattribute("glint_origin_m")
    u_axis = spec.getattribute("glint_u_axis")
    v_axis = spec.getattribute("glint_v_axis")
    if pixel_m is None:
        sys.exit(f"render_map: {path} is not a glint map (no glint_pixel_m in its header)")
    return values, float(pixel_m), origin, u_axis, v_axis


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("exr")
    parser.add_argument("--channel", default="hazard_ratio")
    parser.add_argument("--png", required=True)
    parser.add_argument("--title", default=None)
    args = parser.parse_args()

    values, pixel_m, origin, u_axis, v_axis = read_map(args.exr, args.channel)
    if not np.all(np.isfinite(values)):
        sys.exit("render_map: the map holds a value that is not finite")
    h, w = values.shape
    # Row 0 of the image is the plane's highest v: imshow's 'upper' origin puts it on top.
    extent = [0.0, (w - 1) * pixel_m, 0.0, (h - 1) * pixel_m]
    fig, ax = plt.subplots(figsize=(7.5, 6.5), dpi=110)
    if "coverage" in args.channel:
        im = ax.imshow(values, extent=extent, cmap="magma", vmin=0.0, vmax=1.0)
        levels = [0.1, 0.5, 0.9]
        label = "fraction of scenarios at or above the MPE"
    else:
        positive = values[values > 0]
        vmax = positive.max() if positive.size else 1.0
        vmin = max(vmax * 1e-4, positive.min()) if positive.size else 1e-4
        im = ax.imshow(np.where(values > 0, values, np.nan), extent=extent, cmap="inferno",
                       norm=LogNorm(vmin=vmin, vmax=vmax))
        ax.set_facecolor("black")
        levels = [1.0] if "ratio" in args.channel else []
        label = args.channel
    if levels and values.max() > min(levels):
        ys = np.linspace(extent[3], 0.0, h)
        xs = np.linspace(0.0, extent[1], w)
        ax.contour(xs, ys, values, levels=levels, colors="white", linewidths=0.8)
    fig.colorbar(im, ax=ax, label=label)
    o = [float(x) for x in origin]
    ax.set_xlabel(f"m along u = {tuple(round(float(x), 3) for x in u_axis)} from {tuple(o)}")
    ax.set_ylabel(f"m along v = {tuple(round(float(x), 3) for x in v_axis)}")
    ax.set_title(args.title or f"{args.exr}: {args.channel}")
    fig.tight_layout()
    fig.savefig(args.png)
    print(f"render_map: wrote {args.png} ({w} x {h} pixels of {pixel_m} m, "
          f"{args.channel} in [{values.min():.4g}, {values.max():.4g}])")


if __name__ == "__main__":
    main()
