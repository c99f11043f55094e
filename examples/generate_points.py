#!/usr/bin/env python3
"""Writes the observer point files of the examples (run from anywhere; standard library only)."""
import math
import pathlib

HERE = pathlib.Path(__file__).resolve().parent


def write(name, points):
    with open(HERE / name, "w", encoding="ascii") as f:
        f.write("x,y,z\n")
        for p in points:
            f.write(",".join(f"{c:.6g}" for c in p) + "\n")


# The paper's case has 186 observers: six arcs of 31, at 3 m and 10 m from the cylinder axis and
# at heights -0.6, 0 and 0.6 m (within the cylinder's length, where the fan of reflected light
# passes). Azimuth runs from 0 deg (toward the laser: backscatter) to 180 deg (behind the target).
cylinder = []
for radius in (3.0, 10.0):
    for height in (-0.6, 0.0, 0.6):
        for k in range(31):
            a = math.radians(6.0 * k)
            cylinder.append((-radius * math.cos(a), radius * math.sin(a), height))
write("cylinder_186.csv", cylinder)

# Sphere: observers on a 20 m sphere every 15 deg from straight up (toward the laser) to 165 deg.
sphere = []
for k in range(12):
    polar = math.radians(15.0 * k)
    for azimuth_deg in (0.0, 120.0, 240.0):
        az = math.radians(azimuth_deg)
        sphere.append((20 * math.sin(polar) * math.cos(az), 20 * math.sin(polar) * math.sin(az),
                       20 * math.cos(polar)))
write("sphere_points.csv", sphere)

# Tilted disk: the specular direction of a beam along -z on the normal (0, 0.5, 0.866) is
# (0, 0.866, 0.5); observers at 10 m on a cross around it, 0.5 deg apart.
disk = []
spec = (0.0, math.sqrt(3) / 2, 0.5)
side = (1.0, 0.0, 0.0)
up = (0.0, -0.5, math.sqrt(3) / 2)
for k in range(-10, 11):
    for axis in (side, up):
        t = math.radians(0.5 * k)
        d = [math.cos(t) * s + math.sin(t) * a for s, a in zip(spec, axis)]
        disk.append(tuple(10.0 * c for c in d))
write("disk_points.csv", disk)
