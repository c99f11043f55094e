"""Draws a plane laid over the terrain, as glint run wrote it with a site: the ground's relief
(hill-shaded from each observer's height, band observer_z_m) under the hazard ratio (the aided
one where the scene has an optical aid), with the hazard zones outlined, on the site's UTM grid.

Usage: /usr/bin/python3 examples/render_terrain.py OUTPUT_FOLDER PLANE [--png FILE]
           [--mark X Y LABEL]... [--note TEXT]
(X, Y: a point of the site's local frame to mark, e.g. the target.)
"""
import argparse
import json
import os

import matplotlib
matplotlib.use("Agg")
import matplotlib.colors as colors
import matplotlib.pyplot as plt
import numpy as np
from osgeo import gdal

gdal.UseExceptions()


def bands(path):
    d = gdal.Open(path)
    out = {d.GetRasterBand(k).GetDescription(): d.GetRasterBand(k).ReadAsArray()
           for k in range(1, d.RasterCount + 1)}
    meta = d.GetMetadata()
    vec = lambda key: np.array([float(v) for v in meta[key].split()])
    return out, vec("GLINT_ORIGIN_M"), vec("GLINT_U_AXIS"), vec("GLINT_V_AXIS"), \
        float(meta["GLINT_PIXEL_M"])


def hillshade(z, pixel_m, azimuth_deg=315.0, altitude_deg=40.0):
    dy, dx = np.gradient(z, pixel_m)
    slope = np.arctan(np.hypot(dx, dy))
    aspect = np.arctan2(-dx, dy)
    az, alt = np.radians(azimuth_deg), np.radians(altitude_deg)
    return np.clip(np.sin(alt) * np.cos(slope)
                   + np.cos(alt) * np.sin(slope) * np.cos(az - aspect), 0.0, 1.0)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder")
    parser.add_argument("plane")
    parser.add_argument("--png", default=None)
    parser.add_argument("--mark", nargs=3, action="append", default=[],
                        metavar=("X", "Y", "LABEL"))
    parser.add_argument("--note", default="")
    args = parser.parse_args()
    b, origin, u, v, pixel_m = bands(os.path.join(args.folder, args.plane + ".tif"))
    summary = json.load(open(os.path.join(args.folder, "summary.json")))
    z = b["observer_z_m"]
    ratio = b.get("aided_hazard_ratio", b["hazard_ratio"])
    aided = "aided_hazard_ratio" in b
    h, w = z.shape
    # The plane's own coordinates, m along u and v from the site's origin: pixel (c, r) is
    # lattice point (c, h - 1 - r).
    u0, v0 = float(origin @ u), float(origin @ v)
    extent = (u0 - pixel_m / 2, u0 + (w - 0.5) * pixel_m, v0 - pixel_m / 2, v0 + (h - 0.5) * pixel_m)
    fig, ax = plt.subplots(figsize=(8, 7), dpi=100)
    ax.imshow(hillshade(z, pixel_m), cmap="gray", vmin=0, vmax=1, extent=extent, origin="upper")
    shown = np.ma.masked_less(ratio, 1e-2)
    image = ax.imshow(shown, cmap="inferno",
                      norm=colors.LogNorm(vmin=1e-2, vmax=max(1.0, float(ratio.max()))),
                      alpha=0.8, extent=extent, origin="upper")
    xs = u0 + np.arange(w) * pixel_m
    ys = v0 + (h - 1 - np.arange(h)) * pixel_m
    if ratio.max() >= 1.0:
        ax.contour(xs, ys, ratio, levels=[1.0], colors=["#00e5ff"], linewidths=1.2)
    if aided and b["hazard_ratio"].max() >= 1.0:
        ax.contour(xs, ys, b["hazard_ratio"], levels=[1.0], colors=["#00ff40"], linewidths=1.2)
    levels = ax.contour(xs, ys, z, levels=np.arange(np.floor(z.min() / 10) * 10, z.max(), 10),
                        colors="k", linewidths=0.3, alpha=0.5)
    ax.clabel(levels, fmt="%d m", fontsize=6)
    for x, y, label in args.mark:
        ax.plot(float(x), float(y), marker="^", color="#00e5ff", markersize=8)
        ax.annotate(label, (float(x), float(y)), xytext=(6, -12), textcoords="offset points",
                    color="white", fontsize=8)
    bar = fig.colorbar(image, ax=ax, shrink=0.8)
    bar.set_label(("aided " if aided else "") + "hazard ratio (irradiance / MPE)")
    site = summary["site"]
    ax.set_title(f"{args.plane} over the terrain ({site['map_crs']}){': ' + args.note if args.note else ''}\n"
                 f"cyan: {'aided ' if aided else ''}hazard ratio 1"
                 f"{', green: naked eye' if aided else ''}; contours: ground height (m, local)",
                 fontsize=9)
    ax.set_xlabel("m along u (local frame)")
    ax.set_ylabel("m along v (local frame)")
    fig.tight_layout()
    png = args.png or os.path.join(args.folder, args.plane + "_terrain.png")
    fig.savefig(png)
    print(f"{png}: {args.plane}, {w}x{h} pixels, largest {'aided ' if aided else ''}hazard ratio "
          f"{ratio.max():.3g}")


main()
