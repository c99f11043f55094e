"""A run with a site, read back by the GIS clients: gdalinfo and GDAL's Python bindings read
each plane's GeoTIFF with the site's UTM zone, the geotransform summary.json gives and the EXR
map's values; a lattice point whose latitude and longitude are worked here from the local frame
(by hand, without PROJ: the local tangent frame to Earth-centred coordinates to geodetic ones)
lands in its own pixel; ogrinfo reads the zone polygons of the GeoJSON and the KML, and every
hazardous pixel's centre lies inside a hazardous polygon while no other pixel's does.

Usage: /usr/bin/python3 check_geo.py GLINT SCENE OUTPUT_FOLDER
"""
import json
import math
import os
import shutil
import subprocess
import sys

import numpy as np
import OpenImageIO as oiio
from osgeo import gdal, ogr, osr

gdal.UseExceptions()
ogr.UseExceptions()
osr.UseExceptions()

A = 6378137.0
F = 1.0 / 298.257223563
E2 = F * (2.0 - F)


def geodetic_to_ecef(lat, lon, h):
    p, l = math.radians(lat), math.radians(lon)
    n = A / math.sqrt(1.0 - E2 * math.sin(p) ** 2)
    return ((n + h) * math.cos(p) * math.cos(l), (n + h) * math.cos(p) * math.sin(l),
            (n * (1.0 - E2) + h) * math.sin(p))


def ecef_to_geodetic(x, y, z):
    lon = math.atan2(y, x)
    p = math.hypot(x, y)
    lat = math.atan2(z, p * (1.0 - E2))
    for _ in range(10):  # fixed point on the latitude: converges to 1e-15 in a few steps
        n = A / math.sqrt(1.0 - E2 * math.sin(lat) ** 2)
        h = p / math.cos(lat) - n
        lat = math.atan2(z, p * (1.0 - E2 * n / (n + h)))
    n = A / math.sqrt(1.0 - E2 * math.sin(lat) ** 2)
    return math.degrees(lat), math.degrees(lon), p / math.cos(lat) - n


def local_to_geodetic(site, point):
    b = math.radians(site["bearing_deg"])
    x, y, z = point
    east, north, up = x * math.sin(b) - y * math.cos(b), x * math.cos(b) + y * math.sin(b), z
    p, l = math.radians(site["latitude_deg"]), math.radians(site["longitude_deg"])
    ox, oy, oz = geodetic_to_ecef(site["latitude_deg"], site["longitude_deg"], site["height_m"])
    dx = -math.sin(l) * east - math.sin(p) * math.cos(l) * north + math.cos(p) * math.cos(l) * up
    dy = math.cos(l) * east - math.sin(p) * math.sin(l) * north + math.cos(p) * math.sin(l) * up
    dz = math.cos(p) * north + math.sin(p) * up
    return ecef_to_geodetic(ox + dx, oy + dy, oz + dz)


def exr_channels(path):
    image = oiio.ImageInput.open(path)
    assert image, path
    spec = image.spec()
    pixels = image.read_image(oiio.FLOAT)
    image.close()
    return {name: pixels[:, :, k] for k, name in enumerate(spec.channelnames)}


def main():
    glint, scene, out = sys.argv[1:4]
    if os.path.isdir(out):
        shutil.rmtree(out)
    subprocess.run([glint, "run", scene, "-o", out, "--quiet"], check=True)
    summary = json.load(open(os.path.join(out, "summary.json")))
    site = summary["site"]
    assert site["map_epsg"] == 32613, site  # 106.4° W: UTM zone 13 north
    scene_json = json.load(open(scene))
    checked = 0
    for plane, spec in zip(summary["planes"], scene_json["planes"]):
        name = spec["name"]
        if not plane["map"]["written"]:
            assert name == "wall", plane  # a vertical plane has no map
            assert not os.path.exists(os.path.join(out, name + ".tif"))
            continue
        tif = os.path.join(out, name + ".tif")
        info = json.loads(subprocess.run(["gdalinfo", "-json", tif], check=True,
                                         capture_output=True, text=True).stdout)
        assert "UTM zone 13N" in info["coordinateSystem"]["wkt"], info["coordinateSystem"]
        gt = plane["map"]["geotransform"]
        assert np.allclose(info["geoTransform"], gt, rtol=0, atol=1e-6), (info["geoTransform"], gt)
        bands = [b.get("description") for b in info["bands"]]
        assert bands[:2] == ["hazard_ratio", "irradiance_w_m2"] and bands[-1] == "status", bands
        assert "IEC" not in info["metadata"][""]["GLINT_MPE_RULE"]
        assert plane["map"]["affine_error_m"] < 1e-3, plane["map"]  # 20 m: far below a pixel

        d = gdal.Open(tif)
        srs = osr.SpatialReference(wkt=d.GetProjection())
        assert srs.GetAuthorityCode(None) == "32613", srs.GetAuthorityCode(None)
        exr = exr_channels(os.path.join(out, name + ".exr"))
        for k, band in enumerate(["hazard_ratio", "irradiance_w_m2", "status"]):
            values = d.GetRasterBand(k + 1 if band != "status" else d.RasterCount).ReadAsArray()
            assert np.array_equal(values, exr[band]), band + ": the GeoTIFF differs from the EXR"
        ratio = d.GetRasterBand(1).ReadAsArray()
        height, width = ratio.shape

        # Lattice points by latitude and longitude worked here, to UTM through GDAL, to a pixel
        # through the inverse geotransform: each must land in its own pixel, row height-1-j.
        wgs84 = osr.SpatialReference()
        wgs84.ImportFromEPSG(4326)
        wgs84.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
        srs.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
        to_map = osr.CoordinateTransformation(wgs84, srs)
        inverse = gdal.InvGeoTransform(d.GetGeoTransform())
        pixel = spec["pixel_m"]
        peak = np.unravel_index(np.argmax(ratio), ratio.shape)
        lattice = [(0, 0), (width - 1, height - 1), (width - 1, 0), (17, 43),
                   (int(peak[1]), height - 1 - int(peak[0]))]
        for i, j in lattice:
            local = [spec["origin"][a] + i * pixel * spec["u_axis"][a] + j * pixel * spec["v_axis"][a]
                     for a in range(3)]
            lat, lon, _ = local_to_geodetic(site, local)
            e, n, _ = to_map.TransformPoint(lon, lat)
            col, row = gdal.ApplyGeoTransform(inverse, e, n)
            assert (math.floor(col), math.floor(row)) == (i, height - 1 - j), (i, j, col, row)
            # ... and near its centre: within a hundredth of a pixel.
            assert abs(col - (i + 0.5)) < 0.01 and abs(row - (height - 1 - j + 0.5)) < 0.01
            checked += 1
        print(f"{name}: {width}x{height} pixels, peak hazard ratio {ratio.max():.3g}, "
              f"{len(lattice)} geographic points in their pixels")

        # The zones: ogrinfo reads both files; in the GeoJSON every hazardous pixel's centre is
        # inside a hazardous polygon and no other pixel's is.
        for suffix in ("_zones.geojson", "_zones.kml"):
            listing = subprocess.run(["ogrinfo", "-ro", "-al", "-so",
                                      os.path.join(out, name + suffix)],
                                     check=True, capture_output=True, text=True).stdout
            assert "Feature Count" in listing, listing
        zones = ogr.Open(os.path.join(out, name + "_zones.geojson"))
        layer = zones.GetLayer(0)
        hazardous = ogr.Geometry(ogr.wkbMultiPolygon)
        for feature in layer:
            if feature.GetField("kind") == "hazardous":
                hazardous.AddGeometry(feature.GetGeometryRef())
        hazardous = hazardous.UnionCascaded()
        to_wgs84 = osr.CoordinateTransformation(srs, wgs84)
        count = 0
        for row in range(height):
            for col in range(width):
                x, y = gdal.ApplyGeoTransform(d.GetGeoTransform(), col + 0.5, row + 0.5)
                lon, lat, _ = to_wgs84.TransformPoint(x, y)
                point = ogr.Geometry(ogr.wkbPoint)
                point.AddPoint_2D(lon, lat)
                inside = hazardous.Contains(point)
                assert inside == bool(ratio[row, col] >= 1.0), (row, col, ratio[row, col])
                count += inside
        assert count > 0, "the test scene must have a hazard zone on " + name
        print(f"{name}: {count} hazardous pixels, each inside the hazardous polygons, no other")
    assert checked > 0
    print("geo-referenced maps: OK")


main()
