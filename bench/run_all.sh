#!/usr/bin/env bash
# The whole benchmark suite: kernel throughput, the facet side (the paper's Figure 4, with the
# lobe scheme beside the paper's and the uniform twin), mesh surfaces against the exact shapes,
# and the observer side (adaptive field against its dense twin over tolerances and voxel sizes). Writes
# CSV files and PNG plots into OUT (default build/bench-results) and bench/RESULTS.md.
#
#   bash bench/run_all.sh [--quick | --field-one | --facets-only]
#
# Plots need Debian's python3-matplotlib, hence /usr/bin/python3 (not a python3 earlier on PATH).
# --quick runs two tolerances and the coarsest voxel size per scene (about 15 minutes on two
# cores); the full run takes about two hours. --field-one runs the facet side in full but the
# observer side on the cylinder quarter only (0.1 m with each scheme, 0.05 m against its dense
# twin, and the sampled rows), about 20 minutes. --facets-only runs the Figure 4 sweeps alone and
# replaces that section of bench/RESULTS.md (its plot committed as bench/figure4.png).
# Every other run ends with the sampled rows: the
# octree against anisotropic refinement at 0.05 m, and 0.025 m with the dense twin estimated.
# Run it on an otherwise idle machine, and build nothing meanwhile: it measures time, and a
# rebuilt library under a running benchmark ends it.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD:-build}
out=${OUT:-build/bench-results}
quick=0 field_one=0 facets_only=0
[[ "${1:-}" == "--quick" ]] && quick=1
[[ "${1:-}" == "--field-one" ]] && field_one=1
[[ "${1:-}" == "--facets-only" ]] && facets_only=1
command="bash bench/run_all.sh $*"
mkdir -p "$out"
cmake --build "$build" --target glint_kernel_bench glint_sweep glint_field_bench glint_hard_bench \
  glint_surface_bench >/dev/null

if [[ $facets_only == 0 ]]; then
  echo "== kernel throughput" >&2
  "$build/glint_kernel_bench" --benchmark_out="$out/kernel.csv" --benchmark_out_format=csv
fi

echo "== facet side: the paper's 186 observers (Figure 4)" >&2
# Loose tolerances too: the adaptive integration is far more accurate than its tolerance, and
# savings at equal error need adaptive runs whose error the uniform levels can reach.
tolerances=3e-1,1e-1,3e-2,1e-2,1e-3,1e-4
[[ $quick == 1 ]] && tolerances=1e-1,1e-2
for case in "cylinder 0.003" "cylinder_broad 0.03"; do
  set -- $case
  for normals in surface flat; do
    # The reference: the uniform twin at levels 7 and 8 (6 and 7 when quick), Richardson-
    # extrapolated; for the narrow lobe, whose uniform twin has not converged by level 8, the
    # adaptive integration at 1e-7 (and its uniform twin goes one level deeper).
    reference=(--reference-level 8)
    levels=2,3,4,5,6,7
    [[ $2 == 0.003 ]] && { reference=(--reference-tolerance 1e-7); levels=2,3,4,5,6,7,8; }
    [[ $quick == 1 ]] && { [[ $2 == 0.03 ]] && reference=(--reference-level 7); levels=3,5; }
    # The sweep's log names the reference and how settled it is: the report quotes it.
    # The lobe scheme (always on the exact surface) beside the paper's, with surface normals.
    lobe=()
    [[ $normals == surface ]] && lobe=(--lobe-tolerances "$tolerances")
    "$build/glint_sweep" "examples/$1.json" examples/cylinder_186.csv "${reference[@]}" \
      --tolerances "$tolerances" --levels "$levels" --normals "$normals" "${lobe[@]}" \
      --out "$out/facets_sigma$2_$normals.csv" 2>&1 |
      tee "$out/facets_sigma$2_$normals.log" >&2
  done
done

if [[ $facets_only == 1 ]]; then
  echo "== report (the facet side only)" >&2
  /usr/bin/python3 bench/report.py "$out" bench/RESULTS.md "$command" --facets-only
  exit 0
fi

echo "== hard observers: each scheme against a brute-force reference" >&2
# Beam edge across a glint, near a sphere's terminator, grazing forward scatter, near field
# (bench/scenes/hard/, observers in the CSV beside each scene), at each scene's tolerance.
"$build/glint_hard_bench" bench/scenes/hard/*.json --schemes lobe,paper --out "$out/hard.csv" \
  2>&1 | tee "$out/hard.log" >&2

echo "== mesh surfaces against the shapes glint knows exactly" >&2
# Every surface model at each tessellation, beside the exact shape (about 15 minutes; --quick:
# coarser meshes and two sphere scenes).
surface_args=()
[[ $quick == 1 ]] && surface_args=(--quick)
"$build/glint_surface_bench" "${surface_args[@]}" --out "$out/surfaces.csv" 2>&1 |
  tee "$out/surfaces.log" >&2

echo "== observer side: adaptive field against its dense twin" >&2
field="$out/field.csv"
rm -f "$field"
run_field() {  # scene voxel tolerances: the dense twin once, the adaptive field per tolerance
  local csv="$out/field_row.csv"
  rm -f "$csv"
  "$build/glint_field_bench" "$1" --voxel "$2" --tolerance "$3" --out "$csv" || true
  [[ -f "$csv" ]] || return 0
  if [[ -f "$field" ]]; then tail -n +2 "$csv" >>"$field"; else cp "$csv" "$field"; fi
}
all=0.03,0.01,0.003
if [[ $field_one == 1 ]]; then
  run_field bench/scenes/cylinder_quarter.json 0.1 0.01
  run_field bench/scenes/cylinder_quarter.json 0.05 0.01
elif [[ $quick == 1 ]]; then
  run_field bench/scenes/cylinder_quarter.json 0.2 0.01
  run_field bench/scenes/sphere.json 0.2 0.01
  run_field examples/disk_glint.json 0.125 0.01
else
  for voxel in 0.125 0.0625 0.03125; do run_field examples/disk_glint.json "$voxel" "$all"; done
  for voxel in 0.2 0.1; do
    run_field bench/scenes/sphere.json "$voxel" "$all"
    run_field bench/scenes/cylinder_quarter.json "$voxel" "$all"
  done
  # The dense twin alone takes half an hour here: one tolerance, and last.
  run_field bench/scenes/cylinder_quarter.json 0.05 0.01
fi
# The same field with the paper's scheme (the lobe scheme is the default, issue 16), a table of
# its own beside the lobe scheme's row of the same scene, voxel and tolerance above.
paper_voxel=0.1
[[ $quick == 1 ]] && paper_voxel=0.2
"$build/glint_field_bench" bench/scenes/cylinder_quarter.json --voxel "$paper_voxel" \
  --tolerance 0.01 --scheme paper --out "$out/field_paper_scheme.csv" || true
echo "The cylinder quarter at $paper_voxel m, tolerance 0.01, with \`--scheme paper\` (both" \
  "fields), to set beside the default (lobe) scheme's row of the same scene, voxel and" \
  "tolerance above." >"$out/field_paper_scheme.md"

# Anisotropic refinement against the octree that halved every axis, and below 0.05 m, where
# the dense twin takes many minutes, its cost estimated from 2000 random lattice points and the
# field checked there and at every lattice point within a voxel of the cylinder's rims and
# shadow sides (issue 17, part 3).
sampled="$out/sampled_cylinder_quarter.csv"
rm -f "$sampled"
for args in "0.05 --isotropic" "0.05" "0.025"; do
  set -- $args
  "$build/glint_field_bench" bench/scenes/cylinder_quarter.json --voxel "$@" --tolerance 0.01 \
    --dense-sample 2000 --out "$out/sampled_row.csv" || true
  [[ -f "$out/sampled_row.csv" ]] || continue
  if [[ -f "$sampled" ]]; then tail -n +2 "$out/sampled_row.csv" >>"$sampled"
  else cp "$out/sampled_row.csv" "$sampled"; fi
  rm -f "$out/sampled_row.csv"
done
echo "\`glint_field_bench bench/scenes/cylinder_quarter.json --voxel V --tolerance 0.01" \
  "--dense-sample 2000 [--isotropic]\`: 'octree' halves every axis of a refined block (the" \
  "first versions), 'anisotropic' only the axes whose samples bend (the default)." \
  >"$out/sampled_cylinder_quarter.md"

echo "== report" >&2
/usr/bin/python3 bench/report.py "$out" bench/RESULTS.md "$command"
