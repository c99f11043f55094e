#!/usr/bin/env bash
# The hazard reach against the observer box, side by side in one run (docs/measured.md, "The
# reach without a box"): glint run of a scene with its box, then of the same scene with the box
# taken out (the reach only), each timed with its peak resident memory.
# Usage: bench/reach_vs_box.sh [SCENE] [GLINT]   (default: examples/range_2km.json build/glint)
set -euo pipefail
scene=${1:-examples/range_2km.json}
glint=${2:-build/glint}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 - "$scene" "$work/reach.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
s.pop("observers", None)
s.pop("planes", None)
s.pop("reach", None)  # no box or plane: the reach runs by default
json.dump(s, open(sys.argv[2], "w"))
PY
cp "$scene" "$work/box.json"
python3 - "$work/box.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
s.pop("reach", None)  # the box alone
json.dump(s, open(sys.argv[1], "w"))
PY
run() {  # name scene
  /usr/bin/time -f "%e %M" -o "$work/$1.time" "$glint" run "$2" -o "$work/$1" -q
  read -r seconds kb < "$work/$1.time"
  echo "$1 $seconds $kb"
}
box=$(run box "$work/box.json")
reach=$(run reach "$work/reach.json")
python3 - "$work" "$box" "$reach" <<'PY'
import json, math, sys
work, box, reach = sys.argv[1], sys.argv[2].split(), sys.argv[3].split()
b = json.load(open(f"{work}/box/summary.json"))
r = json.load(open(f"{work}/reach/summary.json"))["hazard_reach"]
zone = b["hazard"]["nominal_hazard_zone"]
p = r["farthest_point_m"]
print(f"box:   {float(box[1]):8.1f} s {int(box[2]) / 1024:8.0f} MB  reach "
      f"{zone['farthest_from_target_m']:.4g} m from the target centre")
print(f"reach: {float(reach[1]):8.1f} s {int(reach[2]) / 1024:8.0f} MB  reach "
      f"{r['distance_m']:.5g} m from the lit centre, {math.hypot(*p):.5g} m from the origin, "
      f"closed {r['closed']}, from the {r['from']}")
print(f"time ratio reach / box: {float(reach[1]) / float(box[1]):.3f}")
PY
