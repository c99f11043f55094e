"""The reach's footprint against the planes beside it: a run of tests/data/site_footprint.json has
an eye-level plane 0.5 m up with the reach's footprint at the same height (`reach`), and a plane
0.9 m up with the footprint at that altitude given above the ellipsoid (`reach_at_1200.9m`, the
site being at 1200 m). Every pixel of a plane
whose hazard ratio reaches 1 must have its lattice point inside the footprint's polygons drawn at
its height (ogrinfo reads both of its files; GDAL's Python module does the geometry). The
footprint is the reach's upper envelope, so it may be larger, never smaller.

Usage: /usr/bin/python3 check_footprint.py GLINT SCENE OUTPUT_FOLDER
"""
import json
import os
import shutil
import subprocess
import sys

from osgeo import gdal, ogr, osr

gdal.UseExceptions()
ogr.UseExceptions()
osr.UseExceptions()


def check_plane(out, zones, plane, kind):
    """Asserts every hazardous pixel of @plane lies inside the zones of @kind; their count."""
    layer = zones.GetLayer(0)
    layer.ResetReading()
    reach = ogr.Geometry(ogr.wkbMultiPolygon)
    for feature in layer:
        if feature.GetField("kind") == kind:
            reach.AddGeometry(feature.GetGeometryRef())
    reach = reach.UnionCascaded()
    assert not reach.IsEmpty(), f"the footprint's {kind} is empty"

    d = gdal.Open(os.path.join(out, plane + ".tif"))
    ratio = d.GetRasterBand(1).ReadAsArray()
    srs = osr.SpatialReference(wkt=d.GetProjection())
    srs.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    wgs84 = osr.SpatialReference()
    wgs84.ImportFromEPSG(4326)
    wgs84.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    to_wgs84 = osr.CoordinateTransformation(srs, wgs84)
    hazardous = 0
    for row in range(ratio.shape[0]):
        for col in range(ratio.shape[1]):
            if ratio[row, col] < 1.0:
                continue
            hazardous += 1
            x, y = gdal.ApplyGeoTransform(d.GetGeoTransform(), col + 0.5, row + 0.5)
            lon, lat, _ = to_wgs84.TransformPoint(x, y)
            point = ogr.Geometry(ogr.wkbPoint)
            point.AddPoint_2D(lon, lat)
            assert reach.Contains(point), \
                f"hazardous pixel ({row}, {col}) of {plane} outside the footprint's {kind}"
    assert hazardous > 0, f"{plane} must have a hazard zone"
    return hazardous


def main():
    glint, scene, out = sys.argv[1:4]
    if os.path.isdir(out):
        shutil.rmtree(out)
    subprocess.run([glint, "run", scene, "-o", out, "--quiet"], check=True)
    summary = json.load(open(os.path.join(out, "summary.json")))
    footprint = summary["hazard_reach"]["footprint"]
    for name in ("reach_footprint.geojson", "reach_footprint.kml"):
        listing = subprocess.run(["ogrinfo", "-ro", "-al", "-so", os.path.join(out, name)],
                                 check=True, capture_output=True, text=True).stdout
        assert "Feature Count" in listing, listing
    # The data source must outlive its layer (GDAL's Python bindings do not keep it alive).
    zones = ogr.Open(os.path.join(out, "reach_footprint.geojson"))
    for plane, kind in (("eye_level", "reach"), ("aloft", "reach_at_1200.9m")):
        inside = check_plane(out, zones, plane, kind)
        pixel_m = next(p["pixel_m"] for p in summary["planes"] if p["name"] == plane)
        print(f"{inside} hazardous pixels of {plane} ({inside * pixel_m ** 2:g} m²), each inside "
              f"the footprint's `{kind}` polygons")
    print(f"footprint at eye height: {footprint['area_m2']:g} m², at 1200.9 m above the "
          f"ellipsoid: {footprint['altitudes'][0]['area_m2']:g} m²")
    print("footprint: OK")


main()
