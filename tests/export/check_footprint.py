"""The reach's footprint against the plane beside it: a run of tests/data/site_footprint.json has
an eye-level plane 0.5 m up and the reach's footprint on the ground at the same height; every
pixel of the plane whose hazard ratio reaches 1 must have its lattice point inside the
footprint's `reach` polygons (ogrinfo reads both of its files; GDAL's Python module does the
geometry). The footprint is the reach's upper envelope, so it may be larger, never smaller.

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
    layer = zones.GetLayer(0)
    reach = ogr.Geometry(ogr.wkbMultiPolygon)
    for feature in layer:
        if feature.GetField("kind") == "reach":
            reach.AddGeometry(feature.GetGeometryRef())
    reach = reach.UnionCascaded()
    assert not reach.IsEmpty(), "the footprint is empty"

    d = gdal.Open(os.path.join(out, "eye_level.tif"))
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
            assert reach.Contains(point), f"hazardous pixel ({row}, {col}) outside the footprint"
    assert hazardous > 0, "the plane must have a hazard zone"
    plane_area = hazardous * summary["planes"][0]["pixel_m"] ** 2
    print(f"{hazardous} hazardous pixels of eye_level ({plane_area:g} m²), each inside the "
          f"reach's footprint of {footprint['area_m2']:g} m²")
    print("footprint: OK")


main()
