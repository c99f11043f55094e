"""Opens glint's VTK files in ParaView (pvpython, headless) and checks them against the scene
and the other outputs of the same run:
- irradiance.vti lies on the scene's lattice: origin at observers.min, spacing voxel_m, one
  point per lattice point of the summary;
- its irradiance equals the VDB's voxel for voxel at the peak and at sampled points (active
  and inactive), read with OpenVDB's Python module;
- irradiance.vthb, the adaptive field as an overlapping AMR read with every level, has one
  level per resolution of the octree's final blocks (blocks.vtu) and holds the VTI's values
  at its points;
- contours of the irradiance at 10 % of the peak and of the hazard ratio at 1 (the nominal
  hazard zone's surface) are non-empty in irradiance.vti and blocks.vtu;
- target.vtp's incident power sums to the beam power the target intercepts, computed here
  from the scene for a flat-top beam that covers each analytic object;
- far_field.vtp, the far field's hazard boundary, encloses the lit centre at the far radius or
  the NOHD beyond it, as the summary's far_field section says.
"""
import json
import math
import random
import sys

import pyopenvdb as vdb
from paraview import servermanager
from paraview.simple import Contour, IntegrateVariables, OpenDataFile

out = sys.argv[1]
summary = json.load(open(f"{out}/summary.json"))
scene = json.load(open(summary["scene_file"]))
box = summary["box"]
level = 0.1 * summary["peak_irradiance_w_m2"]
assert level > 0.0

# The example must be hazardous for the hazard contour to have a surface.
assert summary["hazard"]["peak_hazard_ratio"] > 1.0, summary["hazard"]

# --- The VTI's lattice is the scene's.
image_reader = OpenDataFile(f"{out}/irradiance.vti")
image_reader.UpdatePipeline()
image = servermanager.Fetch(image_reader)
voxel = scene["observers"]["voxel_m"]
assert abs(box["voxel_m"] - voxel) <= 1e-15 * voxel, (box["voxel_m"], voxel)
for a in range(3):
    assert abs(image.GetSpacing()[a] - voxel) <= 1e-12 * voxel, (image.GetSpacing(), voxel)
    want = scene["observers"]["min"][a]
    assert abs(image.GetOrigin()[a] - want) <= 1e-12 * max(1.0, abs(want)), (
        image.GetOrigin(), scene["observers"]["min"])
dims = image.GetDimensions()
assert list(dims) == box["lattice_points"], (dims, box["lattice_points"])
print(f"irradiance.vti: origin {image.GetOrigin()}, spacing {voxel} m, {dims} points")

# --- The VTI's irradiance is the VDB's, voxel for voxel (both float32).
grids, _ = vdb.readAll(f"{out}/irradiance.vdb")
irradiance_grid = {g.name: g for g in grids}["irradiance_w_m2"]
vdb_irradiance = irradiance_grid.getConstAccessor()
vti_irradiance = image.GetPointData().GetArray("irradiance_w_m2")


def vti_at(i, j, k):
    return vti_irradiance.GetValue(i + dims[0] * (j + dims[1] * k))


def index_of(position_m):
    return tuple(round((position_m[a] - box["min_m"][a]) / voxel) for a in range(3))


peak_ijk = index_of(summary["peak_at_m"])
rng = random.Random(7)
active_voxels = [v["min"] for v in irradiance_grid.citerOnValues() if v["min"] == v["max"]]
samples = [peak_ijk] + rng.sample(active_voxels, min(100, len(active_voxels)))
samples += [tuple(rng.randrange(dims[a]) for a in range(3)) for _ in range(100)]
active = 0
for ijk in samples:
    value, on = vdb_irradiance.probeValue(ijk)
    active += on
    expected = value if on else 0.0  # the VTI holds 0 where the VDB has no value
    assert vti_at(*ijk) == expected, (ijk, vti_at(*ijk), expected)
peak = summary["peak_irradiance_w_m2"]
assert abs(vti_at(*peak_ijk) - peak) <= 1e-6 * peak, (vti_at(*peak_ijk), peak)
print(f"irradiance.vti: {len(samples)} points equal the VDB's ({active} active), peak "
      f"{vti_at(*peak_ijk):.6g} W/m^2 at {peak_ijk}")

# --- The AMR (irradiance.vthb): every level read (ParaView reads level 0 only unless told:
# DefaultNumberOfLevels), one per resolution of the octree, each holding the lattice's values.
amr_reader = OpenDataFile(f"{out}/irradiance.vthb")
amr_reader.DefaultNumberOfLevels = 64
amr_reader.UpdatePipeline()
# servermanager.Fetch cannot move an AMR to the client; the built-in session's reader holds it.
amr = amr_reader.GetClientSideObject().GetOutputDataObject(0)
assert amr.IsA("vtkOverlappingAMR"), amr.GetClassName()
block_voxels = round(box["block_m"] / voxel)
blocks_reader = OpenDataFile(f"{out}/blocks.vtu")
blocks_reader.UpdatePipeline()
blocks = servermanager.Fetch(blocks_reader)
finest = 0
for c in range(blocks.GetNumberOfCells()):
    b = blocks.GetCell(c).GetBounds()
    # A finest block (2 voxels a side) is written as its 8 voxels: an edge of 1 is one of 2.
    shortest = max(2, min(round((b[2 * a + 1] - b[2 * a]) / voxel) for a in range(3)))
    finest = max(finest, round(math.log2(block_voxels / shortest)))
assert amr.GetNumberOfLevels() == finest + 1, (amr.GetNumberOfLevels(), finest + 1)
assert amr.GetNumberOfLevels() >= 2, "the example must refine for the AMR to have levels"
compared = 0
for lev in range(amr.GetNumberOfLevels()):
    step = max(1, block_voxels >> (lev + 1))
    spacing = [0.0, 0.0, 0.0]
    amr.GetSpacing(lev, spacing)
    assert all(abs(h - step * voxel) <= 1e-12 * voxel for h in spacing), (lev, spacing)
    for b in range(amr.GetNumberOfDataSets(lev)):
        grid = amr.GetDataSet(lev, b)
        values = grid.GetPointData().GetArray("irradiance_w_m2")
        ratio = grid.GetPointData().GetArray("hazard_ratio")
        assert values is not None and ratio is not None, (lev, b)
        for p in rng.sample(range(grid.GetNumberOfPoints()), min(5, grid.GetNumberOfPoints())):
            ijk = index_of(grid.GetPoint(p))
            assert values.GetValue(p) == vti_at(*ijk), (lev, b, ijk, values.GetValue(p), vti_at(*ijk))
            compared += 1
# The peak is on the finest level that covers it, as on the VTI.
peak_found = False
for lev in range(amr.GetNumberOfLevels()):
    for b in range(amr.GetNumberOfDataSets(lev)):
        grid = amr.GetDataSet(lev, b)
        p = grid.FindPoint(summary["peak_at_m"])
        if p >= 0 and index_of(grid.GetPoint(p)) == peak_ijk:
            value = grid.GetPointData().GetArray("irradiance_w_m2").GetValue(p)
            assert value == vti_at(*peak_ijk), (lev, value, vti_at(*peak_ijk))
            peak_found = True
assert peak_found, "no AMR level has a point at the peak"
print(f"irradiance.vthb: {amr.GetNumberOfLevels()} levels "
      f"({[amr.GetNumberOfDataSets(lev) for lev in range(amr.GetNumberOfLevels())]} blocks), "
      f"{compared} points equal the VTI's, the peak included")

# --- Contours: the hazard zone's surface and the bright region.
for name in ("irradiance.vti", "blocks.vtu"):
    reader = OpenDataFile(f"{out}/{name}")
    for array, value, unit in (("irradiance_w_m2", level, "W/m^2"), ("hazard_ratio", 1.0, "")):
        contour = Contour(Input=reader, ContourBy=["POINTS", array], Isosurfaces=[value])
        contour.UpdatePipeline()
        points = contour.GetDataInformation().GetNumberOfPoints()
        assert points > 0, f"{name}: empty contour of {array} at {value} {unit}"
        print(f"{name}: contour of {array} at {value:.4g} {unit} has {points} points")


# --- The target receives the beam power it intercepts.
def unit(v):
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v]


def intercepted_power_w(scene):
    laser = scene["laser"]
    beam = laser["beam"]
    assert beam["profile"] == "flat_top" and not beam.get("divergence_rad"), (
        "this check knows the intercepted power of a collimated flat-top beam only")
    e0 = laser["power_w"] / (math.pi * beam["radius_m"] ** 2)
    d = unit(laser["direction"])
    total = 0.0
    for obj in scene["objects"]:
        centre = obj["center"]
        rel = [centre[a] - laser["position"][a] for a in range(3)]
        along = sum(rel[a] * d[a] for a in range(3))
        off_axis = math.sqrt(max(0.0, sum(x * x for x in rel) - along * along))
        if obj["shape"] == "disk":
            cos_t = abs(sum(x * y for x, y in zip(unit(obj["normal"]), d)))
            area, reach = math.pi * obj["radius"] ** 2 * cos_t, obj["radius"]
        elif obj["shape"] == "sphere":
            area, reach = math.pi * obj["radius"] ** 2, obj["radius"]
        elif obj["shape"] == "cylinder":
            cos_a = sum(x * y for x, y in zip(unit(obj["axis"]), d))
            area = 2.0 * obj["radius"] * obj["length"] * math.sqrt(max(0.0, 1.0 - cos_a * cos_a))
            reach = math.hypot(obj["radius"], 0.5 * obj["length"])
        else:
            raise AssertionError(f"no closed form for a {obj['shape']}")
        assert off_axis + reach <= beam["radius_m"], "the beam must cover the object"
        total += e0 * area
    return total


target = OpenDataFile(f"{out}/target.vtp")
target.UpdatePipeline()
data = servermanager.Fetch(target)
power = data.GetCellData().GetArray("incident_power_w")
assert data.GetNumberOfCells() > 0 and power is not None
total = math.fsum(power.GetValue(i) for i in range(power.GetNumberOfTuples()))
expected = intercepted_power_w(scene)
# The facets carry the exact quadric: their areas converge to the surface's, and a flat disk's
# are exact; 1e-9 leaves room for rounding over the cells.
assert abs(total - expected) <= 1e-9 * expected, (total, expected)
print(f"target.vtp: {data.GetNumberOfCells()} cells, {total:.10g} W incident, "
      f"{expected:.10g} W intercepted by the scene's objects")

# --- The far field's hazard boundary (far_field.vtp): a closed surface around the lit centre,
# each point at its direction's NOHD where that lies beyond the far radius, else at the far
# radius toward it (which only grows into the beam's forward cone).
far = summary["far_field"]
surface_reader = OpenDataFile(f"{out}/far_field.vtp")
surface_reader.UpdatePipeline()
surface = servermanager.Fetch(surface_reader)
arrays = surface.GetPointData()
nohd, beyond = arrays.GetArray("nohd_m"), arrays.GetArray("beyond_far_radius")
assert nohd is not None and beyond is not None and arrays.GetArray("intensity_w_sr") is not None
assert surface.GetNumberOfPoints() > 0 and surface.GetNumberOfCells() > 0
centre, r_far = far["centre_m"], far["far_radius_m"]
largest_nohd = 0.0
for p in range(surface.GetNumberOfPoints()):
    x = surface.GetPoint(p)
    r = math.dist(x, centre)
    assert r >= (1.0 - 1e-6) * r_far, (p, r, r_far)
    if beyond.GetValue(p):
        assert abs(r - nohd.GetValue(p)) <= 1e-6 * r, (p, r, nohd.GetValue(p))
    largest_nohd = max(largest_nohd, nohd.GetValue(p))
# The map's own maximum covers every direction the surface samples.
assert largest_nohd <= (1.0 + 1e-6) * far["max_nohd_m"] + 1e-9, (largest_nohd, far["max_nohd_m"])
# Closed around the centre: at least the area of the sphere of the far radius, less the
# polygonal surface's own shortfall (its cells are a few degrees across).
integrated = IntegrateVariables(Input=surface_reader)
integrated.UpdatePipeline()
area = servermanager.Fetch(integrated).GetCellData().GetArray("Area").GetValue(0)
assert area >= 0.99 * 4.0 * math.pi * r_far ** 2, (area, 4.0 * math.pi * r_far ** 2)
print(f"far_field.vtp: {surface.GetNumberOfPoints()} points, area {area:.4g} m^2 around the "
      f"lit centre at far radius {r_far:.4g} m, largest NOHD {largest_nohd:.4g} m")
