"""Opens glint's VTK files in ParaView (pvpython, headless) and contours the irradiance at 10 %
of the peak: each volume file must give a non-empty surface, the target its incident power."""
import json
import sys

from paraview import servermanager
from paraview.simple import Contour, OpenDataFile

out = sys.argv[1]
summary = json.load(open(f"{out}/summary.json"))
level = 0.1 * summary["peak_irradiance_w_m2"]
assert level > 0.0

for name in ("irradiance.vti", "blocks.vtu"):
    reader = OpenDataFile(f"{out}/{name}")
    contour = Contour(Input=reader, ContourBy=["POINTS", "irradiance_w_m2"], Isosurfaces=[level])
    contour.UpdatePipeline()
    points = contour.GetDataInformation().GetNumberOfPoints()
    assert points > 0, f"{name}: empty contour at {level} W/m^2"
    print(f"{name}: contour at {level:.4g} W/m^2 has {points} points")

target = OpenDataFile(f"{out}/target.vtp")
target.UpdatePipeline()
data = servermanager.Fetch(target)
power = data.GetCellData().GetArray("incident_power_w")
assert data.GetNumberOfCells() > 0 and power is not None
total = sum(power.GetValue(i) for i in range(power.GetNumberOfTuples()))
assert total > 0.0, total
print(f"target.vtp: {data.GetNumberOfCells()} cells, {total:.4g} W incident")
