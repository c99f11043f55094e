#!/usr/bin/env python3
"""Plots and RESULTS.md from the CSV files of bench/run_all.sh.

    python3 bench/report.py RESULTS_DIR bench/RESULTS.md ["the command that ran the suite"]
    python3 bench/report.py RESULTS_DIR bench/RESULTS.md "command" --surfaces-only
        (only the mesh-surface section, from RESULTS_DIR/surfaces.csv, with its own provenance)
    python3 bench/report.py RESULTS_DIR bench/RESULTS.md "command" --facets-only
        (only the facet side, from RESULTS_DIR's sweeps, its plot committed as figure4.png)

Writes RESULTS_DIR/facets.png (run time against error on the paper's 186 observers, adaptive
and uniform, one colour per sigma), RESULTS_DIR/field.png (evaluations against the finest
voxel size, adaptive field and dense twin, per scene), surfaces.png beside the report (mesh
surfaces: error against triangles, committed) and the Markdown report.
"""
import csv
import datetime
import math
import os
import platform
import shutil
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def rows(path):
    if not os.path.exists(path):
        return []
    with open(path) as f:
        lines = f.readlines()
    # Google Benchmark's CSV may start with context lines; the table starts at its header.
    start = next((i for i, l in enumerate(lines) if l.startswith(("name,", "scheme,", "scene,"))), 0)
    return list(csv.DictReader(lines[start:]))


def machine():
    model = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            model = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
    except (OSError, StopIteration):
        pass
    mem_gib = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip() or "unknown"
    return (f"{model}, {os.cpu_count()} cores, {mem_gib:.0f} GiB, {platform.system()} "
            f"{platform.release()}; glint commit {commit}; "
            f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC")


def g(x, digits=3):
    return f"{float(x):.{digits}g}"


def table_head(*columns):
    """The header and separator lines of a Markdown table."""
    return ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]


def save_plot(fig, ax, path):
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def kernel_section(out):
    k = rows(os.path.join(out, "kernel.csv"))
    if not k:
        return ["No kernel results."]
    lines = table_head("benchmark", "time per iteration", "reflection calculations per second")
    for r in k:
        rate = r.get("reflections_per_s", "")
        per = r.get("reflections_per_s_per_thread", "")
        extra = f" ({g(per)} per thread)" if per else ""
        lines.append(f"| `{r['name']}` | {g(r['real_time'])} {r['time_unit']} | {g(rate)}{extra} |")
    by = {r["name"].split("/")[1]: float(r["reflections_per_s"]) for r in k
          if r["name"].startswith("ObserversOnThreads/")}
    if "1" in by and "2" in by:
        lines.append("")
        lines.append(f"Two threads against one: {by['2'] / by['1']:.2f}x the throughput.")
    lines += ["", "The kernel is one reflection calculation (Eq. 1, clipped at the terminator) on "
              "level-4 sub-facets of the paper's cylinder; `AdaptiveObserver` includes the bounds "
              "and the refinement bookkeeping per calculation. Debian's Google Benchmark warns "
              "that the library was built as DEBUG: that concerns its own timing loop, glint is "
              "built Release. On this virtual machine repeated runs differ by up to 1.5x."]
    return lines


def saving_at_equal_error(a, uniform):
    """How many times fewer evaluations the adaptive row `a` needs than the uniform twin at
    the same max error: measured where a uniform level is as accurate, else a lower bound (the
    deepest level, still less accurate) and an estimate at the uniform twin's best rate."""
    ea, na = float(a["max_rel_error"]), float(a["evaluations_per_observer"])
    evals = lambda u: float(u["evaluations_per_observer"])  # noqa: E731
    good = [u for u in uniform if float(u["max_rel_error"]) <= ea]
    if good:
        u = min(good, key=evals)
        return (f"{evals(u) / na:.1f}x fewer evaluations than uniform level {u['parameter']}, "
                f"{float(u['seconds']) / float(a['seconds']):.1f}x faster")
    if not uniform:
        return "no uniform levels measured"
    by_level = sorted(uniform, key=lambda u: float(u["parameter"]))
    deep = by_level[-1]
    text = (f"no uniform level is as accurate; level {deep['parameter']} errs by "
            f"{g(deep['max_rel_error'])} with {evals(deep) / na:.1f}x the evaluations, so the "
            f"saving is more than that")
    e_deep = float(deep["max_rel_error"])
    if ea > 0 and e_deep > ea:
        # The uniform twin is a midpoint rule, second order in the sub-facet size: at best its
        # error falls as 1/N from the deepest level on. Pre-asymptotic, it falls slower.
        text += (f"; were its error to fall as 1/N (second order) from there, equal error "
                 f"would take about {evals(deep) * e_deep / ea / na:.2g}x")
    return text


def facet_sections(out):
    lines, curves = [], []
    for sigma, paper in (("0.003", "~20x"), ("0.03", "~2x")):
        for normals in ("surface", "flat"):
            data = rows(os.path.join(out, f"facets_sigma{sigma}_{normals}.csv"))
            if not data:
                continue
            curves.append((sigma, normals, data))
            lines += [f"#### sigma = {sigma}, {normals} normals", ""]
            log = os.path.join(out, f"facets_sigma{sigma}_{normals}.log")
            if os.path.exists(log):
                with open(log) as f:
                    ref = [l.strip() for l in f if l.startswith("reference:")]
                if ref:
                    what = ref[-1][len("reference:"):].strip()
                    caveat = (": errors no larger than that change cannot be told apart from the "
                              "reference's own" if "change" in what else "")
                    lines += [f"Reference: {what}{caveat}.", ""]
            lines += table_head("scheme", "tolerance / level", "evaluations per observer",
                                "time (s)", "max error", "RMS error", "unconverged")
            for r in data:
                lines.append(f"| {r['scheme']} | {r['parameter']} | {g(r['evaluations_per_observer'], 4)} | "
                             f"{g(r['seconds'])} | {g(r['max_rel_error'])} | {g(r['rms_rel_error'])} | {r['unconverged']} |")
            lines.append("")
            uniform = [r for r in data if r["scheme"] == "uniform"]
            for a in (r for r in data if r["scheme"] == "adaptive"):
                lines.append(f"- tolerance {a['parameter']} (max error {g(a['max_rel_error'])}): "
                             + saving_at_equal_error(a, uniform) + f" (paper: {paper})")
            for l in (r for r in data if r["scheme"] == "lobe"):
                # The lobe scheme against the cheapest run of the paper's scheme as accurate.
                el = float(l["max_rel_error"])
                good = [a for a in data if a["scheme"] == "adaptive"
                        and float(a["max_rel_error"]) <= el]
                if good:
                    a = min(good, key=lambda r: float(r["seconds"]))
                    lines.append(f"- lobe scheme at tolerance {l['parameter']} (max error {g(el)}): "
                                 f"{float(a['evaluations_per_observer']) / float(l['evaluations_per_observer']):.1f}x "
                                 f"fewer evaluations and {float(a['seconds']) / float(l['seconds']):.1f}x "
                                 f"less time than the paper's scheme at {a['parameter']} "
                                 f"(max error {g(a['max_rel_error'])})")
                else:
                    lines.append(f"- lobe scheme at tolerance {l['parameter']} (max error {g(el)}): "
                                 "no run of the paper's scheme is as accurate")
            lines.append("")
    if curves:
        fig, ax = plt.subplots(figsize=(7, 5))
        colours = {"0.003": "tab:red", "0.03": "tab:blue"}
        for sigma, normals, data in curves:
            for scheme, marker in (("adaptive", "o"), ("lobe", "^"), ("uniform", "s")):
                pts = sorted((float(r["max_rel_error"]), float(r["seconds"]))
                             for r in data if r["scheme"] == scheme and float(r["max_rel_error"]) > 0)
                if pts:
                    ax.loglog([p[0] for p in pts], [p[1] for p in pts], marker=marker,
                              linestyle="-" if normals == "surface" else ":",
                              color=colours[sigma], label=f"{scheme}, sigma {sigma}, {normals}")
        ax.set_xlabel("max relative error over the 186 observers")
        ax.set_ylabel("wall time (s)")
        ax.set_title("Facet side: run time against error (paper's cylinder)")
        save_plot(fig, ax, os.path.join(out, "facets.png"))
    return lines


def hard_section(out):
    data = rows(os.path.join(out, "hard.csv"))
    if not data:
        return ["No hard-observer results."]
    lines = table_head("observers", "scheme", "converged", "evaluations: median, p99, max (mean)",
                       "time (s)", "worst error / allowed (converged)", "max error / peak",
                       "own estimate below the achieved error")
    for r in data:
        lines.append(f"| {r['scene']} | {r['scheme']} | {r['converged']} of {r['observers']} | "
                     f"{r['evaluations_median']}, {r['evaluations_p99']}, {r['evaluations_max']} "
                     f"({float(r['evaluations_mean']):.0f}) | {g(r['seconds'])} | "
                     f"{g(r['worst_error_over_allowed'])} | {g(r['max_rel_error'])} | "
                     f"{r['estimate_below_error']} |")
    return lines


def field_section(out, name="field.csv", plot=True):
    data = rows(os.path.join(out, name))
    if not data:
        return ["No observer-field results."]
    lines = table_head("scene", "voxel (m)", "tolerance", "points",
                       "adaptive: evaluations, s, grids MB, peak RSS MB", "dense: evaluations, s",
                       "fewer evaluations / faster", "max error / allowed", "RMS error",
                       "volume >1 %, >10 %, >50 % (adaptive / dense)",
                       "hazard zone >MPE: dense m³, adaptive / dense")
    for r in data:
        ae, de = float(r["adaptive_evaluations"]), float(r["dense_evaluations"])
        at, dt = float(r["adaptive_seconds"]), float(r["dense_seconds"])
        lines.append(
            f"| {r['scene']} | {r['voxel_m']} | {r['tolerance']} | {r['lattice_points']} | "
            f"{g(ae)}, {g(at)}, {float(r['adaptive_grid_bytes']) / 1e6:.1f}, "
            f"{float(r['adaptive_peak_rss_bytes']) / 1e6:.0f} | {g(de)}, {g(dt)} | "
            f"{de / ae:.1f}x / {dt / at:.1f}x | {g(r['max_error_w_m2'])} / {g(r['allowed_error_w_m2'])} | "
            f"{g(r['rms_error_w_m2'])} | {float(r['volume_ratio_1pct']):.4f}, "
            f"{float(r['volume_ratio_10pct']):.4f}, {float(r['volume_ratio_50pct']):.4f} | "
            + (f"{g(r['dense_volume_above_mpe_m3'])}, {float(r['volume_ratio_mpe']):.4f} |"
               if r.get("volume_ratio_mpe") else "not measured |"))
    if not plot:
        return lines
    growth = []
    for scene in sorted({r["scene"] for r in data}):
        pts = sorted(((float(r["voxel_m"]), float(r["adaptive_evaluations"]),
                       float(r["dense_evaluations"])) for r in data
                      if r["scene"] == scene and float(r["tolerance"]) == 0.01), reverse=True)
        steps = [f"{a[0]:g} to {b[0]:g} m: dense {b[2] / a[2]:.1f}x, adaptive {b[1] / a[1]:.1f}x"
                 for a, b in zip(pts, pts[1:]) if a[1] > 0 and a[2] > 0]
        if steps:
            growth.append(f"- {scene}: " + "; ".join(steps))
    if growth:  # only where a scene ran at more than one voxel size
        lines += ["", "How cost grows as the finest voxel halves (tolerance 0.01; dense grows about "
                  "8x):", ""] + growth
    fig, ax = plt.subplots(figsize=(7, 5))
    for i, scene in enumerate(sorted({r["scene"] for r in data})):
        pts = sorted((float(r["voxel_m"]), float(r["adaptive_evaluations"]), float(r["dense_evaluations"]))
                     for r in data if r["scene"] == scene and float(r["tolerance"]) == 0.01)
        if not pts:
            continue
        colour = f"C{i}"
        ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", color=colour, label=f"{scene} adaptive")
        ax.loglog([p[0] for p in pts], [p[2] for p in pts], "s--", color=colour, label=f"{scene} dense")
    ax.set_xlabel("finest voxel (m)")
    ax.set_ylabel("reflection calculations")
    ax.set_title("Observer side: cost as the voxel halves (tolerance 0.01)")
    ax.invert_xaxis()
    save_plot(fig, ax, os.path.join(out, "field.png"))
    return lines


def sampled_section(out, name):
    """Rows of glint_field_bench --dense-sample: the twin's cost estimated from random points."""
    data = rows(os.path.join(out, name))
    if not data:
        return ["No sampled observer-field results."]
    lines = table_head("scene", "voxel (m)", "tolerance", "refinement", "points",
                       "adaptive: evaluations, s, peak RSS MB, peak RSS per active voxel (bytes)",
                       "dense (estimated): evaluations ± s.e., s",
                       "fewer evaluations (± s.e.)", "checked: random + feature points",
                       "max error / allowed")
    for r in data:
        ae = float(r["adaptive_evaluations"])
        de, se = float(r["dense_evaluations_estimate"]), float(r["dense_evaluations_se"])
        rss = float(r["adaptive_peak_rss_bytes"])
        active = float(r["active_voxels"])
        lines.append(
            f"| {r['scene']} | {r['voxel_m']} | {r['tolerance']} | "
            f"{'anisotropic' if r['anisotropic'] == 'yes' else 'octree'} | {r['lattice_points']} | "
            f"{g(ae)}, {g(r['adaptive_seconds'])}, {rss / 1e6:.0f}, "
            f"{rss / active if active > 0 else 0:.0f} | {g(de)} ± {g(se)}, "
            f"{g(r['dense_seconds_estimate'])} | {de / ae:.1f}x (± {se / ae:.1f}) | "
            f"{r['sample_points']} + {r['feature_points']} | "
            f"{g(r['max_error_w_m2'])} / {g(r['allowed_error_w_m2'])} |")
    return lines

SURFACE_MODELS = ["pn", "nagata", "quadric_fit", "pn_published", "flat"]


def surfaces_section(out, report_dir):
    """glint_surface_bench: mesh surfaces against the shapes glint knows exactly."""
    data = rows(os.path.join(out, "surfaces.csv"))
    if not data:
        return ["No mesh-surface results."]
    lines = []

    def select(**want):
        return [r for r in data if all(r[k] == v for k, v in want.items())]

    # The headline: every model on the first scene, exact normals.
    head = select(shape="sphere", scene="far", normals="exact")
    counts = sorted({int(r["triangles"]) for r in head})
    lines += ["### Every model on a sphere (sigma = 0.01, observers 2-45 m, exact normals)", "",
              "Max relative error over the observers above 1 % of the peak; the analytic sphere "
              "at the same tolerance for scale.", ""]
    models = [m for m in SURFACE_MODELS if any(r["surface"] == m for r in head)]
    lines += table_head("triangles", *[f"`{m}`" for m in models])
    for n in counts:
        cells = []
        for m in models:
            hit = [r for r in head if r["surface"] == m and int(r["triangles"]) == n]
            cells.append(g(hit[0]["max_rel_error"], 2) if hit else "")
        lines.append(f"| {n} | " + " | ".join(cells) + " |")
    analytic = select(shape="sphere", scene="far", surface="analytic")
    if analytic:
        lines += ["", f"The analytic sphere itself: {g(analytic[0]['max_rel_error'], 2)}."]
    lines.append("")

    # Every case: the three curved models side by side, max / median and the observed order.
    lines += ["### Every case: max / median error, and the observed order of the max", "",
              "Order between successive tessellations: log(e1/e2) / log(h1/h2), h the mean edge "
              "length. References: the exact shape at tolerance 1e-7 (sphere, cylinder, "
              "ellipsoid: glint's quadric facets), the brute force over the torus's own "
              "parametrisation. Errors below about 3e-5 are the integration's own (meshes at "
              "tolerance 1e-4), not the surface's: orders between such rows mean nothing.", ""]
    lines += table_head("shape", "scene (sigma)", "normals", "triangles", "h (m)",
                        *[f"`{m}`" for m in ("pn", "nagata", "quadric_fit")])
    cases = []
    for r in data:
        key = (r["shape"], r["scene"], r["normals"])
        if r["surface"] != "analytic" and key not in cases:
            cases.append(key)
    for shape, scene, normals in cases:
        group = select(shape=shape, scene=scene, normals=normals)
        for n in sorted({int(r["triangles"]) for r in group}):
            row_cells = []
            for m in ("pn", "nagata", "quadric_fit"):
                series = sorted((r for r in group if r["surface"] == m),
                                key=lambda r: int(r["triangles"]))
                hit = [r for r in series if int(r["triangles"]) == n]
                if not hit:
                    row_cells.append("")
                    continue
                r = hit[0]
                cell = f"{g(r['max_rel_error'], 2)} / {g(r['median_rel_error'], 2)}"
                k = series.index(r)
                if k > 0:
                    prev = series[k - 1]
                    e1, e2 = float(prev["max_rel_error"]), float(r["max_rel_error"])
                    h1, h2 = float(prev["edge_m"]), float(r["edge_m"])
                    if e1 > 0 and e2 > 0 and h1 > h2:
                        cell += f" ({math.log(e1 / e2) / math.log(h1 / h2):.1f})"
                row_cells.append(cell)
            sigma = group[0]["sigma"]
            h = next(r["edge_m"] for r in group if int(r["triangles"]) == n)
            lines.append(f"| {shape} | {scene} ({sigma}) | {normals} | {n} | {g(h, 3)} | "
                         + " | ".join(row_cells) + " |")
    lines.append("")

    # Cost per observer: the default surface against the exact shape, same run, same tolerance.
    lines += ["### Cost per observer: `pn` meshes beside the exact shape", "",
              "Evaluations and wall seconds per observer (2 threads), exact normals, at the "
              "tolerance of the run; the ratio is the mesh's time over the exact shape's.", ""]
    lines += table_head("shape", "scene", "exact shape: evaluations, s", "triangles",
                        "mesh: evaluations, s", "time ratio")
    for shape, scene, normals in cases:
        if normals != "exact":
            continue
        exact = select(shape=shape, scene=scene, surface="analytic")
        if not exact:
            continue
        x = exact[0]
        for r in sorted(select(shape=shape, scene=scene, normals="exact", surface="pn"),
                        key=lambda r: int(r["triangles"])):
            ratio = float(r["seconds_per_observer"]) / float(x["seconds_per_observer"])
            lines.append(f"| {shape} | {scene} | {g(x['evaluations_per_observer'], 4)}, "
                         f"{g(x['seconds_per_observer'])} | {r['triangles']} | "
                         f"{g(r['evaluations_per_observer'], 4)}, {g(r['seconds_per_observer'])} "
                         f"| {ratio:.2f}x |")
    lines.append("")

    # The plot, committed beside RESULTS.md.
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    panels = [("sphere", "far", "exact", "sphere, sigma 0.01, exact normals"),
              ("ellipsoid", "far", "exact", "ellipsoid, sigma 0.01, exact normals"),
              ("torus", "far", "exact", "torus, sigma 0.03, exact normals")]
    for ax, (shape, scene, normals, title) in zip(axes, panels):
        for m in SURFACE_MODELS:
            series = sorted(select(shape=shape, scene=scene, normals=normals, surface=m),
                            key=lambda r: int(r["triangles"]))
            series = [r for r in series if float(r["max_rel_error"]) > 0]
            if series:
                ax.loglog([int(r["triangles"]) for r in series],
                          [float(r["max_rel_error"]) for r in series], "o-", label=m)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("triangles")
        ax.set_ylabel("max relative error")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(report_dir, "surfaces.png"), dpi=110)
    plt.close(fig)
    lines += ["![max relative error against triangles per surface model](surfaces.png)", ""]
    return lines


SURFACES_HEADING = "## Mesh surfaces against the shapes glint knows exactly (`glint_surface_bench`)"
SURFACES_ABOUT = ("Meshes of a sphere, an open cylinder, an ellipsoid and a torus "
                  "(tests/support/test_meshes.h) with exact, perturbed (turned by 0.5 (h/R)^2) and "
                  "computed (Max's weights) vertex normals, each surface model at each "
                  "tessellation, 100 observers where random lit points send their glint (turned by "
                  "1.5 sigma), at 2-45 m (the near scene: 5 cm), meshes and the exact shape at "
                  "tolerance 1e-4; `surfaces.png` is committed beside this file.")


def splice_section(report, heading, section, insert_before="## Observer side"):
    """Replaces the section under `heading` of an existing report (up to the next `## `) with
    `section`, or inserts it before the first line starting with `insert_before`."""
    with open(report) as f:
        text = f.read().split("\n")
    if heading in text:
        start = text.index(heading)
        end = next((i for i in range(start + 1, len(text)) if text[i].startswith("## ")),
                   len(text))
    else:
        start = end = next((i for i, l in enumerate(text) if l.startswith(insert_before)),
                           len(text))
    text[start:end] = section
    with open(report, "w") as f:
        f.write("\n".join(text))


def splice_surfaces(out, report, command):
    """Replaces (or inserts before the observer side) the mesh-surface section of an existing
    report, with its own provenance line: what a run of the surface bench alone updates."""
    section = [SURFACES_HEADING, "", f"Machine: {machine()}; produced by `{command}`.", "",
               SURFACES_ABOUT, ""]
    section += surfaces_section(out, os.path.dirname(os.path.abspath(report))) + [""]
    splice_section(report, SURFACES_HEADING, section)


FACETS_HEADING = "## Facet side: the paper's Figure 4 (`glint_sweep`, 186 observers)"
FACETS_ABOUT = ("Errors are relative to a reference: for sigma = 0.03 the uniform twin at levels 7 "
                "and 8, Richardson-extrapolated; for sigma = 0.003, whose uniform twin has not "
                "converged by level 8, the adaptive integration at tolerance 1e-7. Savings are at "
                "equal achieved max error: the cheapest uniform level at least as accurate as the "
                "adaptive run; where none is, a lower bound and an extrapolation, both labelled.")


def splice_facets(out, report, command):
    """Replaces the facet-side section of an existing report with one from RESULTS_DIR's sweeps,
    with its own provenance line, and commits its plot beside the report as figure4.png: what a
    run of the sweeps alone (run_all.sh --facets-only) updates."""
    section = [FACETS_HEADING, "", f"Machine: {machine()}; produced by `{command}`.", "",
               FACETS_ABOUT, ""]
    section += facet_sections(out)
    plot = os.path.join(out, "facets.png")
    if os.path.exists(plot):
        shutil.copyfile(plot, os.path.join(os.path.dirname(os.path.abspath(report)), "figure4.png"))
        section += ["Run time against the largest error over the 186 observers, each scheme and "
                    "lobe width (the seed paper's Figure 4 is not in its extracted text; its "
                    "stated saving, about 20x at sigma = 0.003 and 2x at 0.03, is quoted in the "
                    "notes above):", "", "![run time against error](figure4.png)", ""]
    splice_section(report, FACETS_HEADING, section, insert_before="## Hard observers")


def main():
    if "--facets-only" in sys.argv:
        args = [a for a in sys.argv[1:] if a != "--facets-only"]
        splice_facets(args[0], args[1], args[2] if len(args) > 2 else "glint_sweep")
        return
    if "--surfaces-only" in sys.argv:
        args = [a for a in sys.argv[1:] if a != "--surfaces-only"]
        splice_surfaces(args[0], args[1], args[2] if len(args) > 2 else "glint_surface_bench")
        return
    out, report = sys.argv[1], sys.argv[2]
    command = sys.argv[3] if len(sys.argv) > 3 else "bash bench/run_all.sh"
    text = ["# Benchmark results", "",
            f"Machine: {machine()}.", "",
            f"Produced by `{command}` (CSV files and the plots `facets.png`, "
            f"`field.png` in `{out}`; the plots are not committed). Times are wall-clock on all "
            "cores unless a row says otherwise.", "",
            "## Kernel throughput (`glint_kernel_bench`, Google Benchmark)", ""]
    text += kernel_section(out) + [""]
    text += [FACETS_HEADING, "", FACETS_ABOUT, ""]
    text += facet_sections(out)
    text += ["## Hard observers (`glint_hard_bench`, bench/scenes/hard/)", "",
             "Each class at its scene's tolerance (1e-3, floor 1e-9 x the beam's peak "
             "irradiance), each scheme against the tests' brute force (nested adaptive "
             "Gauss-Kronrod in the shape's own parametrisation, tests/support/brute_force.h). "
             "Allowed error: tolerance x reference + floor + the reference's own error. "
             "What each class is: the `description` of its scene.", ""]
    text += hard_section(out) + [""]
    text += [SURFACES_HEADING, "", SURFACES_ABOUT, ""]
    text += surfaces_section(out, os.path.dirname(os.path.abspath(report))) + [""]
    text += ["## Observer side: adaptive field against its dense twin (`glint_field_bench`)", "",
             "Same lattice, same integrator; the dense twin runs once per scene and voxel size. "
             "Allowed error: tolerance x peak + floor. Peak RSS is the process's resident set "
             "during the adaptive field (the dense twin's grids included).", ""]
    text += field_section(out) + [""]
    # Further runs of glint_field_bench beside the suite's (field_<what>.csv), each its own table.
    for extra in sorted(f for f in os.listdir(out) if f.startswith("field_") and f.endswith(".csv")
                        and f != "field_row.csv"):
        text += [f"### `{extra}`", ""]
        about = os.path.join(out, extra[:-4] + ".md")  # what produced it, written beside it
        if os.path.exists(about):
            with open(about) as f:
                text += [f.read().strip(), ""]
        text += field_section(out, extra, plot=False) + [""]
    for extra in sorted(f for f in os.listdir(out) if f.startswith("sampled_") and f.endswith(".csv")):
        text += [f"### `{extra}`: the dense twin estimated from random lattice points", ""]
        about = os.path.join(out, extra[:-4] + ".md")
        if os.path.exists(about):
            with open(about) as f:
                text += [f.read().strip(), ""]
        text += sampled_section(out, extra) + [""]
    with open(report, "w") as f:
        f.write("\n".join(text))


if __name__ == "__main__":
    main()
