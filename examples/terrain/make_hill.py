"""Writes examples/terrain/hill.tif: a synthetic elevation model of a range in New Mexico's
Tularosa Basin (1200 m above the WGS 84 ellipsoid), 2.6 km square with posts 10 m apart, in UTM
zone 13N as real models come: a gently undulating floor, a hill 60 m high north-west of the
target, a lower rise to the north-east and a ridge 20 m high to the south-west. examples/range_terrain.json
stands on it.

Usage: /usr/bin/python3 examples/terrain/make_hill.py [OUTPUT]
"""
import math
import os
import sys

import numpy as np
from osgeo import gdal, osr

gdal.UseExceptions()
osr.UseExceptions()

SITE_LAT, SITE_LON, BASE_M = 32.9, -106.4, 1200.0
SPACING_M, POSTS = 10.0, 261


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "hill.tif")
    utm = osr.SpatialReference()
    utm.ImportFromEPSG(32613)
    wgs84 = osr.SpatialReference()
    wgs84.ImportFromEPSG(4326)
    wgs84.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    e0, n0, _ = osr.CoordinateTransformation(wgs84, utm).TransformPoint(SITE_LON, SITE_LAT)
    half = SPACING_M * POSTS / 2.0
    # Post centres, east (x) and north (y) of the site.
    offsets = (np.arange(POSTS) + 0.5) * SPACING_M - half
    east = offsets[np.newaxis, :]
    north = -offsets[:, np.newaxis]  # row 0 is the northern edge

    def bump(e, n, height, sigma):
        return height * np.exp(-((east - e) ** 2 + (north - n) ** 2) / (2.0 * sigma ** 2))

    def ridge(e, n, height, heading, half_length, half_width):
        along = (east - e) * math.cos(heading) + (north - n) * math.sin(heading)
        across = -(east - e) * math.sin(heading) + (north - n) * math.cos(heading)
        return height * np.exp(-along ** 2 / (2.0 * half_length ** 2)
                               - across ** 2 / (2.0 * half_width ** 2))

    heights = (BASE_M
               + 1.5 * np.sin(east / 170.0) * np.cos(north / 230.0)  # the basin's undulation
               + bump(-420.0, 470.0, 60.0, 150.0)                     # the hill, north-west
               + bump(500.0, 350.0, 30.0, 200.0)                      # a rise, north-east
               # a ridge 20 m high to the south-west, running north-west to south-east
               + ridge(-380.0, -420.0, 20.0, math.radians(-40.0), 260.0, 45.0))
    driver = gdal.GetDriverByName("GTiff")
    d = driver.Create(out, POSTS, POSTS, 1, gdal.GDT_Float32, ["COMPRESS=DEFLATE", "PREDICTOR=3"])
    d.SetGeoTransform((e0 - half, SPACING_M, 0.0, n0 + half, 0.0, -SPACING_M))
    d.SetProjection(utm.ExportToWkt())
    band = d.GetRasterBand(1)
    band.SetDescription("height above the WGS 84 ellipsoid")
    band.SetUnitType("m")
    band.WriteArray(heights.astype(np.float32))
    d = None
    print(f"{out}: {POSTS} x {POSTS} posts {SPACING_M:g} m apart, "
          f"{heights.min():.1f} to {heights.max():.1f} m")


main()
