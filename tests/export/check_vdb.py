"""Reads glint's irradiance.vdb back with Debian's python3-openvdb and checks it against
summary.json: grid names, voxel size, active voxel count and metadata."""
import json
import sys

import pyopenvdb as vdb

out = sys.argv[1]
summary = json.load(open(f"{out}/summary.json"))
grids, meta = vdb.readAll(f"{out}/irradiance.vdb")
by_name = {g.name: g for g in grids}
assert set(by_name) == {"irradiance_w_m2", "hazard_ratio", "refinement_level", "status",
                        "irradiance_upper_w_m2"}, (
    by_name.keys())
voxel = summary["box"]["voxel_m"]
for g in grids:
    size = g.transform.voxelSize()
    assert all(abs(s - voxel) < 1e-12 * voxel for s in size), (g.name, size, voxel)
irr = by_name["irradiance_w_m2"]
assert irr.activeVoxelCount() == summary["memory"]["active_voxels"], (
    irr.activeVoxelCount(), summary["memory"]["active_voxels"])
lo, hi = irr.evalMinMax()
peak = summary["peak_irradiance_w_m2"]
assert abs(hi - peak) <= 1e-6 * peak, (hi, peak)  # the grid stores float32
assert lo >= 0.0, lo
for key in ("program", "scene_fnv1a64", "wavelength_nm", "power_w", "tolerance", "floor_w_m2",
            "evaluations", "irradiance_unit", "exposure_s", "mpe_w_m2", "mpe_rule"):
    assert key in meta, key
assert meta["evaluations"] == summary["evaluations"]
# The hazard ratio is irradiance / MPE voxel for voxel: same voxels, peak over MPE.
hazard = summary["hazard"]
assert meta["mpe_w_m2"] == hazard["mpe_w_m2"], (meta["mpe_w_m2"], hazard["mpe_w_m2"])
ratio = by_name["hazard_ratio"]
assert ratio.activeVoxelCount() == irr.activeVoxelCount()
_, ratio_hi = ratio.evalMinMax()
assert abs(ratio_hi - hazard["peak_hazard_ratio"]) <= 1e-6 * hazard["peak_hazard_ratio"], (
    ratio_hi, hazard["peak_hazard_ratio"])
print("vdb ok:", {g.name: g.activeVoxelCount() for g in grids})
