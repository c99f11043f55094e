"""Opens glint's VTK files in ParaView (pvpython, headless) and contours the irradiance at 10 %
of the peak and the hazard ratio at 1 (the nominal hazard zone's surface): each volume file
must give non-empty surfaces, the target its incident power."""
import json
import sys

from paraview import servermanager
from paraview.simple import Contour, OpenDataFile

out = sys.argv[1]
summary = json.load(open(f"{out}/summary.json"))
level = 0.1 * summary["peak_irradiance_w_m2"]
assert level > 0.0

# The example must be hazardous for the hazard contour to have a surface.
assert summary["hazard"]["peak_hazard_ratio"] > 1.0, summary["hazard"]

for name in ("irradiance.vti", "blocks.vtu"):
    reader = OpenDataFile(f"{out}/{name}")
    for array, value, unit in (("irradiance_w_m2", level, "W/m^2"), ("hazard_ratio", 1.0, "")):
        contour = Contour(Input=reader, ContourBy=["POINTS", array], Isosurfaces=[value])
        contour.UpdatePipeline()
        points = contour.GetDataInformation().GetNumberOfPoints()
        assert points > 0, f"{name}: empty contour of {array} at {value} {unit}"
        print(f"{name}: contour of {array} at {value:.4g} {unit} has {points} points")

target = OpenDataFile(f"{out}/target.vtp")
target.UpdatePipeline()
data = servermanager.Fetch(target)
power = data.GetCellData().GetArray("incident_power_w")
assert data.GetNumberOfCells() > 0 and power is not None
total = sum(power.GetValue(i) for i in range(power.GetNumberOfTuples()))
assert total > 0.0, total
print(f"target.vtp: {data.GetNumberOfCells()} cells, {total:.4g} W incident")
