#!/usr/bin/env bash
# The whole benchmark suite: kernel throughput, the facet side (the paper's Figure 4) and the
# observer side (adaptive field against its dense twin over tolerances and voxel sizes). Writes
# CSV files and PNG plots into OUT (default build/bench-results) and bench/RESULTS.md.
#
#   bash bench/run_all.sh [--quick]
#
# Plots need Debian's python3-matplotlib, hence /usr/bin/python3 (not a python3 earlier on PATH).
# --quick runs one tolerance and the coarsest voxel size per scene (about 15 minutes on two
# cores); the full run takes a few hours. Run it on an otherwise idle machine: it measures time.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD:-build}
out=${OUT:-build/bench-results}
quick=0
[[ "${1:-}" == "--quick" ]] && quick=1
mkdir -p "$out"
cmake --build "$build" --target glint_kernel_bench glint_sweep glint_field_bench >/dev/null

echo "== kernel throughput" >&2
"$build/glint_kernel_bench" --benchmark_out="$out/kernel.csv" --benchmark_out_format=csv

echo "== facet side: the paper's 186 observers (Figure 4)" >&2
tolerances=1e-2,3e-3,1e-3,3e-4,1e-4
[[ $quick == 1 ]] && tolerances=1e-2,1e-3
for case in "cylinder 0.003" "cylinder_broad 0.03"; do
  set -- $case
  for normals in surface flat; do
    # The reference: the uniform twin at levels 7 and 8 (6 and 7 when quick), Richardson-
    # extrapolated; for the narrow lobe, whose uniform twin has not converged by level 8, the
    # adaptive integration at 1e-7.
    reference=(--reference-level 8)
    levels=2,3,4,5,6,7
    [[ $quick == 1 ]] && { reference=(--reference-level 7); levels=3,5; }
    [[ $2 == 0.003 ]] && reference=(--reference-tolerance 1e-7)
    "$build/glint_sweep" "examples/$1.json" examples/cylinder_186.csv "${reference[@]}" \
      --tolerances "$tolerances" --levels "$levels" --normals "$normals" \
      --out "$out/facets_sigma$2_$normals.csv"
  done
done

echo "== observer side: adaptive field against its dense twin" >&2
field="$out/field.csv"
rm -f "$field"
run_field() {  # scene voxel tolerance
  local csv="$out/field_row.csv"
  "$build/glint_field_bench" "$1" --voxel "$2" --tolerance "$3" --out "$csv" || true
  if [[ -f "$field" ]]; then tail -n +2 "$csv" >>"$field"; else cp "$csv" "$field"; fi
}
for tol in 0.01 0.03 0.003; do
  [[ $quick == 1 && $tol != 0.01 ]] && continue
  for voxel in 0.2 0.1 0.05; do
    [[ $quick == 1 && $voxel != 0.2 ]] && continue
    [[ $tol != 0.01 && $voxel == 0.05 ]] && continue  # the dense twin alone takes half an hour
    run_field bench/scenes/cylinder_quarter.json "$voxel" "$tol"
    run_field bench/scenes/sphere.json "$voxel" "$tol"
  done
  for voxel in 0.125 0.0625 0.03125; do
    [[ $quick == 1 && $voxel != 0.125 ]] && continue
    run_field examples/disk_glint.json "$voxel" "$tol"
  done
done

echo "== report" >&2
/usr/bin/python3 bench/report.py "$out" bench/RESULTS.md "bash bench/run_all.sh $*"
