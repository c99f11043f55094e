#include "pipeline/commands/cli.h"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <functional>
#include <iostream>
#include <string>

#include "export/atomic_file.h"
#include "facets/integrator.h"
#include "glint/version.h"
#include "pipeline/base/input_error.h"
#include "pipeline/base/memory_budget.h"
#include "pipeline/base/number_format.h"
#include "pipeline/commands/batch_command.h"
#include "pipeline/commands/cluster.h"
#include "pipeline/commands/points_command.h"
#include "pipeline/commands/run_command.h"

namespace glint {
namespace {

// How an exception that ends a command is reported: its exit status and the message's kind.
struct Failure {
  ExitStatus status;
  const char* kind;
};
Failure failureOf(const std::exception& e) {
  if (dynamic_cast<const InputError*>(&e) != nullptr ||
      dynamic_cast<const OutputError*>(&e) != nullptr) {
    return {kExitBadInput, "error: "};
  }
  return {kExitInternalError, "internal error: "};
}

// `glint points`, `glint batch` or `glint run` (@p work) on one process or as one rank of an
// MPI job. Alone,
// errors go to the caller's handler; as a rank, an error on one rank ends them all
// (MPI_Abort): the others would wait for it for ever.
int runOnCluster(Cluster& cluster, std::ostream& err, const std::function<void()>& work) {
  if (cluster.size() == 1) {
    work();
    return kExitSuccess;
  }
  const std::string who = " (rank " + std::to_string(cluster.rank()) + ")";
  try {
    work();
    return kExitSuccess;
  } catch (const std::exception& e) {
    const Failure f = failureOf(e);
    err << "glint" << who << ": " << f.kind << e.what() << "\n" << std::flush;
    cluster.abort(f.status);
    return f.status;
  }
}

// A real number in [lo, hi], checked as the scene's numbers are: CLI::Range lets NaN through
// (every comparison with it is false) and prints its bounds as %f (1e-12 as 0.000000).
CLI::Validator finiteIn(double lo, double hi) {
  const std::string range = "[" + formatNumber("%g", lo) + ", " + formatNumber("%g", hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        std::size_t used = 0;
        double x = 0.0;
        try {
          x = std::stod(text, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used == 0 || used != text.size() || !std::isfinite(x)) {
          return "must be a finite number in " + range + ", not '" + text + "'";
        }
        if (!(x >= lo && x <= hi)) return "must lie in " + range + ", not " + text;
        return {};
      },
      "FLOAT in " + range);
}

// A memory size ("512M", "4G", bytes), checked and converted at the boundary.
CLI::Validator byteSize() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (!parseByteSize(text))
          return "must be a memory size such as 512M, 4G or 16GiB, not '" + text + "'";
        return {};
      },
      "SIZE");
}

std::string memoryHelp() {
  return "Memory budget, e.g. 4G (default: 3/4 of this machine's, " +
         formatBytes(static_cast<double>(defaultMemoryBudgetBytes())) +
         "); a region needing more is refused before it starts, a run passing it stops";
}

}  // namespace

int runGlint(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  CLI::App app{
      "glint: where laser light reflected off a shiny target can hurt an eye.\n"
      "Adaptive facet reflection modelling (Bailey et al., AFRL 2010) and beyond.",
      "glint"};
  app.set_version_flag("--version", std::string("glint ") + GLINT_VERSION);
  app.require_subcommand(1);

  PointsArgs points;
  CLI::App* points_cmd = app.add_subcommand(
      "points", "Irradiance at observer points listed in a CSV file (header x,y,z)");
  points_cmd->add_option("scene", points.scene_path, "Scene file (JSON)")->required();
  points_cmd->add_option("--points", points.points_path, "Observer points: CSV with header x,y,z")
      ->required();
  points_cmd->add_option("-o,--out", points.out_path,
                         "Output CSV; '-' (the default) writes to standard output");
  double tolerance = 0.0;
  CLI::Option* tolerance_opt =
      points_cmd
          ->add_option("--tolerance", tolerance,
                       "Relative accuracy of each observer's total (overrides the scene)")
          ->check(finiteIn(1e-12, 0.999999));
  int level = 0;
  CLI::Option* uniform_opt =
      points_cmd
          ->add_option("--uniform", level,
                       "Uniform twin instead of adaptive: every facet split to LEVEL (0-12)")
          ->check(CLI::Range(0, 12));
  std::string normals;
  CLI::Option* normals_opt =
      points_cmd
          ->add_option("--normals", normals,
                       "Facet normals for the BRDF: surface (default) or flat (the paper's; "
                       "implies --scheme paper)")
          ->check(CLI::IsMember({"surface", "flat"}));
  std::string scheme;
  CLI::Option* scheme_opt =
      points_cmd
          ->add_option("--scheme", scheme,
                       "Integration scheme: lobe (the specular lobe in closed form about each "
                       "piece's specular point, the default), cubature (a degree-7 rule on the "
                       "exact surface) or paper (the paper's 1→4 one-point refinement); "
                       "overrides the scene")
          ->check(CLI::IsMember(integrationSchemeNames()));
  points_cmd->add_option("--threads", points.threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(1, 4096));
  points_cmd->add_flag("-q,--quiet", points.quiet, "No progress and no summary on standard error");
  std::string points_memory;
  points_cmd->add_option("--memory", points_memory, memoryHelp())->check(byteSize());
  std::string time_series;
  CLI::Option* time_series_opt = points_cmd->add_option(
      "--time-series", time_series,
      "With an engagement: every observer's irradiance samples to this CSV file "
      "(observer,time_s,irradiance_w_m2,pulse: the pulse rule 3 counted it in, 0 between)");

  RunArgs run;
  CLI::App* run_cmd = app.add_subcommand(
      "run", "The hazard volume over the scene's observer box: VDB, VTK files and a summary");
  run_cmd->add_option("scene", run.scene_path, "Scene file (JSON) with an `observers` section")
      ->required();
  run_cmd->add_option("-o,--out", run.out_dir,
                      "Output folder (default: out/<scene name>, out/<scene name>_uniform)");
  run_cmd->add_flag("--uniform", run.uniform,
                    "The dense twin: evaluate every lattice point (for comparison)");
  run_cmd->add_option("--threads", run.threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(1, 4096));
  run_cmd->add_flag("-q,--quiet", run.quiet, "No progress and no summary on standard error");
  std::string run_memory;
  run_cmd->add_option("--memory", run_memory, memoryHelp())->check(byteSize());
  std::string run_scheme;
  CLI::Option* run_scheme_opt =
      run_cmd
          ->add_option("--scheme", run_scheme,
                       "Integration scheme (as for points); overrides the scene")
          ->check(CLI::IsMember(integrationSchemeNames()));

  BatchArgs batch;
  CLI::App* batch_cmd = app.add_subcommand(
      "batch",
      "A study: many scenarios of a base scene (poses, jitter, materials), aggregated into "
      "maximum-irradiance and coverage-probability maps; under mpirun, shared among the ranks");
  batch_cmd->add_option("study", batch.study_path, "Study file (JSON)")->required();
  batch_cmd->add_option("-o,--out", batch.out_dir, "Output folder (default: out/<study name>)");
  batch_cmd
      ->add_option("--threads", batch.threads, "Worker threads per process (default: all cores)")
      ->check(CLI::Range(1, 4096));
  batch_cmd->add_flag("--fresh", batch.fresh,
                      "Discard the scenarios an earlier run left in the output folder");
  batch_cmd->add_flag("-q,--quiet", batch.quiet, "No progress and no summary on standard error");
  std::string batch_memory;
  batch_cmd->add_option("--memory", batch_memory, memoryHelp())->check(byteSize());

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version are successes; everything else is a usage error.
    return app.exit(e, out, err) == 0 ? kExitSuccess : kExitBadInput;
  }

  try {
    if (app.got_subcommand(points_cmd)) {
      if (*tolerance_opt) points.tolerance = tolerance;
      if (*uniform_opt) points.uniform_level = level;
      if (*normals_opt)
        points.normals = normals == "flat" ? NormalModel::Flat : NormalModel::Surface;
      if (*scheme_opt) points.scheme = integrationSchemeByName(scheme);
      if (!points_memory.empty()) points.memory_bytes = *parseByteSize(points_memory);
      if (*time_series_opt) points.time_series_path = time_series;
      points.terminal = &err == &std::cerr && ::isatty(STDERR_FILENO) == 1;
      Cluster cluster;
      if (cluster.size() > 1 && cluster.rank() == 0 && !points.quiet) {
        err << "glint points: " << cluster.size() << " MPI ranks share the observers\n";
      }
      return runOnCluster(cluster, err, [&] {
        runPoints(points, out, err, cluster.size() > 1 ? &cluster : nullptr);
      });
    }
    if (app.got_subcommand(run_cmd)) {
      run.terminal = &err == &std::cerr && ::isatty(STDERR_FILENO) == 1;
      if (!run_memory.empty()) run.memory_bytes = *parseByteSize(run_memory);
      if (*run_scheme_opt) run.scheme = integrationSchemeByName(run_scheme);
      Cluster cluster;
      if (cluster.size() > 1 && cluster.rank() == 0 && !run.quiet) {
        err << "glint run: " << cluster.size() << " MPI ranks share the fields' points\n";
      }
      return runOnCluster(cluster, err,
                          [&] { runScene(run, err, cluster.size() > 1 ? &cluster : nullptr); });
    }
    if (app.got_subcommand(batch_cmd)) {
      batch.terminal = &err == &std::cerr && ::isatty(STDERR_FILENO) == 1;
      if (!batch_memory.empty()) batch.memory_bytes = *parseByteSize(batch_memory);
      Cluster cluster;
      return runOnCluster(cluster, err, [&] { runBatch(batch, cluster, err); });
    }
    return kExitSuccess;
  } catch (const std::exception& e) {
    const Failure f = failureOf(e);
    err << "glint: " << f.kind << e.what() << "\n";
    return f.status;
  }
}

}  // namespace glint
