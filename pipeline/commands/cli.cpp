#include "pipeline/commands/cli.h"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "export/atomic_file.h"
#include "facets/integrator.h"
#include "glint/version.h"
#include "pipeline/base/edit_distance.h"
#include "pipeline/base/input_error.h"
#include "pipeline/base/memory_budget.h"
#include "pipeline/base/number_format.h"
#include "pipeline/commands/batch_command.h"
#include "pipeline/commands/cluster.h"
#include "pipeline/commands/fit_command.h"
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

// The options of `glint points`. CLI11 keeps pointers to these members, so an instance must
// stay where it was made until the command line is parsed and read.
struct PointsOptions {
  CLI::App* cmd = nullptr;
  PointsArgs args;
  // Options the scene already sets: taken only when given, which the CLI::Option* records.
  double tolerance = 0.0;
  CLI::Option* tolerance_opt = nullptr;
  int level = 0;
  CLI::Option* uniform_opt = nullptr;
  std::string normals;
  CLI::Option* normals_opt = nullptr;
  std::string scheme;
  CLI::Option* scheme_opt = nullptr;
  std::string memory;
  std::string time_series;
  CLI::Option* time_series_opt = nullptr;
};

void addPointsCommand(CLI::App& app, PointsOptions& o) {
  o.cmd = app.add_subcommand("points",
                             "Irradiance at observer points listed in a CSV file (header x,y,z)");
  o.cmd->add_option("scene", o.args.scene_path, "Scene file (JSON)")->required();
  o.cmd->add_option("--points", o.args.points_path, "Observer points: CSV with header x,y,z")
      ->required();
  o.cmd->add_option("-o,--out", o.args.out_path,
                    "Output CSV; '-' (the default) writes to standard output");
  o.tolerance_opt =
      o.cmd
          ->add_option("--tolerance", o.tolerance,
                       "Relative accuracy of each observer's total (overrides the scene)")
          ->check(finiteIn(1e-12, 0.999999));
  o.uniform_opt =
      o.cmd
          ->add_option("--uniform", o.level,
                       "Uniform twin instead of adaptive: every facet split to LEVEL (0-12)")
          ->check(CLI::Range(0, 12));
  o.normals_opt =
      o.cmd
          ->add_option("--normals", o.normals,
                       "Facet normals for the BRDF: surface (default) or flat (the paper's; "
                       "implies --scheme paper)")
          ->check(CLI::IsMember({"surface", "flat"}));
  o.scheme_opt =
      o.cmd
          ->add_option("--scheme", o.scheme,
                       "Integration scheme: lobe (the specular lobe in closed form about each "
                       "piece's specular point, the default), cubature (a degree-7 rule on the "
                       "exact surface) or paper (the paper's 1→4 one-point refinement); "
                       "overrides the scene")
          ->check(CLI::IsMember(integrationSchemeNames()));
  o.cmd->add_option("--threads", o.args.threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(1, 4096));
  o.cmd->add_flag("-q,--quiet", o.args.quiet, "No progress and no summary on standard error");
  o.cmd->add_option("--memory", o.memory, memoryHelp())->check(byteSize());
  o.time_series_opt = o.cmd->add_option(
      "--time-series", o.time_series,
      "With an engagement: every observer's irradiance samples to this CSV file "
      "(observer,time_s,irradiance_w_m2,pulse: the pulse rule 3 counted it in, 0 between)");
}

// The options of `glint run`; as PointsOptions, it must not move once its options are added.
struct RunOptions {
  CLI::App* cmd = nullptr;
  RunArgs args;
  std::string memory;
  std::string scheme;
  CLI::Option* scheme_opt = nullptr;
};

void addRunCommand(CLI::App& app, RunOptions& o) {
  o.cmd = app.add_subcommand(
      "run",
      "The scene's hazard: its reach in every direction, and its box and planes where it has "
      "them (summary.json, maps, VDB and VTK files)");
  o.cmd->add_option("scene", o.args.scene_path, "Scene file (JSON)")->required();
  o.cmd->add_option("-o,--out", o.args.out_dir,
                    "Output folder (default: out/<scene name>, out/<scene name>_uniform)");
  o.cmd->add_flag("--uniform", o.args.uniform,
                  "The dense twin: evaluate every lattice point (for comparison)");
  o.cmd->add_option("--threads", o.args.threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(1, 4096));
  o.cmd->add_flag("-q,--quiet", o.args.quiet, "No progress and no summary on standard error");
  o.cmd->add_option("--memory", o.memory, memoryHelp())->check(byteSize());
  o.scheme_opt = o.cmd
                     ->add_option("--scheme", o.scheme,
                                  "Integration scheme (as for points); overrides the scene")
                     ->check(CLI::IsMember(integrationSchemeNames()));
}

// The options of `glint batch`; as PointsOptions, it must not move once its options are added.
struct BatchOptions {
  CLI::App* cmd = nullptr;
  BatchArgs args;
  std::string memory;
};

void addBatchCommand(CLI::App& app, BatchOptions& o) {
  o.cmd = app.add_subcommand(
      "batch",
      "A study: many scenarios of a base scene (poses, jitter, materials), aggregated into "
      "maximum-irradiance and coverage-probability maps; under mpirun, shared among the ranks");
  o.cmd->add_option("study", o.args.study_path, "Study file (JSON)")->required();
  o.cmd->add_option("-o,--out", o.args.out_dir, "Output folder (default: out/<study name>)");
  o.cmd->add_option("--threads", o.args.threads, "Worker threads per process (default: all cores)")
      ->check(CLI::Range(1, 4096));
  o.cmd->add_flag("--fresh", o.args.fresh,
                  "Discard the scenarios an earlier run left in the output folder");
  o.cmd->add_flag("-q,--quiet", o.args.quiet, "No progress and no summary on standard error");
  o.cmd->add_option("--memory", o.memory, memoryHelp())->check(byteSize());
}

// Progress redraws its line only on a terminal, and only on the real standard error (a stream
// a caller passes in is never one).
bool errorIsTerminal(const std::ostream& err) {
  return &err == &std::cerr && ::isatty(STDERR_FILENO) == 1;
}

// The parsed options of `glint points` as its arguments: the scene's settings overridden only
// by the options given.
PointsArgs pointsArgs(const PointsOptions& o) {
  PointsArgs points = o.args;
  if (*o.tolerance_opt) points.tolerance = o.tolerance;
  if (*o.uniform_opt) points.uniform_level = o.level;
  if (*o.normals_opt)
    points.normals = o.normals == "flat" ? NormalModel::Flat : NormalModel::Surface;
  if (*o.scheme_opt) points.scheme = integrationSchemeByName(o.scheme);
  if (!o.memory.empty()) points.memory_bytes = *parseByteSize(o.memory);
  if (*o.time_series_opt) points.time_series_path = o.time_series;
  return points;
}

RunArgs runArgs(const RunOptions& o, bool terminal) {
  RunArgs run = o.args;
  run.terminal = terminal;
  if (!o.memory.empty()) run.memory_bytes = *parseByteSize(o.memory);
  if (*o.scheme_opt) run.scheme = integrationSchemeByName(o.scheme);
  return run;
}

BatchArgs batchArgs(const BatchOptions& o, bool terminal) {
  BatchArgs batch = o.args;
  batch.terminal = terminal;
  if (!o.memory.empty()) batch.memory_bytes = *parseByteSize(o.memory);
  return batch;
}

int runPointsCommand(const PointsArgs& points, std::ostream& out, std::ostream& err) {
  Cluster cluster;
  if (cluster.size() > 1 && cluster.rank() == 0 && !points.quiet) {
    err << "glint points: " << cluster.size() << " MPI ranks share the observers\n";
  }
  return runOnCluster(
      cluster, err, [&] { runPoints(points, out, err, cluster.size() > 1 ? &cluster : nullptr); });
}

int runRunCommand(const RunArgs& run, std::ostream& err) {
  Cluster cluster;
  if (cluster.size() > 1 && cluster.rank() == 0 && !run.quiet) {
    err << "glint run: " << cluster.size() << " MPI ranks share the fields' points\n";
  }
  return runOnCluster(cluster, err,
                      [&] { runScene(run, err, cluster.size() > 1 ? &cluster : nullptr); });
}

int runBatchCommand(const BatchArgs& batch, std::ostream& err) {
  Cluster cluster;
  return runOnCluster(cluster, err, [&] { runBatch(batch, cluster, err); });
}

void addFitCommand(CLI::App& app, CLI::App*& cmd, FitArgs& args, bool& no_abg, bool& no_diffuse) {
  cmd = app.add_subcommand(
      "fit",
      "Fit Beckmann lobes, ABg scatter and a Lambertian part to a measured BRDF table (CSV), "
      "least squares on log f; prints the material and the fit's error as JSON");
  cmd->add_option("table", args.table_path,
                  "The table (CSV: theta_i_deg,theta_o_deg,"
                  "delta_phi_deg,brdf_per_sr)")
      ->required();
  cmd->add_option("--lobes", args.model.lobes, "Beckmann lobes to fit (0 to 4; default 2)")
      ->check(CLI::Range(0, 4));
  cmd->add_flag("--no-abg", no_abg, "Fit no ABg term");
  cmd->add_flag("--no-diffuse", no_diffuse, "Fit no Lambertian part");
}

// A first word that is no command ("glint rn x.json"): CLI11 would read it as a stray argument
// and say only that a subcommand is required. Empty where the word is an option or a command.
std::string unknownCommand(const CLI::App& app, int argc, const char* const* argv) {
  if (argc < 2 || argv[1][0] == '-') return {};
  const std::string word = argv[1];
  std::string names, nearest;
  const std::vector<const CLI::App*> commands = app.get_subcommands({});
  for (std::size_t k = 0; k < commands.size(); ++k) {
    const std::string& name = commands[k]->get_name();
    if (name == word) return {};
    names += (k == 0 ? "" : k + 1 == commands.size() ? " or " : ", ") + name;
    if (nearest.empty() && likelyMisspelling(word, name)) nearest = name;
  }
  return "unknown command \"" + word + "\"" +
         (nearest.empty() ? std::string() : " (did you mean \"" + nearest + "\"?)") +
         "; the commands are " + names + " (glint --help)";
}

}  // namespace

int runGlint(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  CLI::App app{
      "glint: where laser light reflected off a shiny target can hurt an eye.\n"
      "Adaptive facet reflection modelling (Bailey et al., AFRL 2010) and beyond.",
      "glint"};
  app.set_version_flag("--version", std::string("glint ") + GLINT_VERSION);
  app.require_subcommand(1);
  PointsOptions points;
  addPointsCommand(app, points);
  RunOptions run;
  addRunCommand(app, run);
  BatchOptions batch;
  addBatchCommand(app, batch);
  CLI::App* fit_cmd = nullptr;
  FitArgs fit;
  bool no_abg = false, no_diffuse = false;
  addFitCommand(app, fit_cmd, fit, no_abg, no_diffuse);

  if (const std::string unknown = unknownCommand(app, argc, argv); !unknown.empty()) {
    err << "glint: error: " << unknown << "\n";
    return kExitBadInput;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version are successes; everything else is a usage error.
    return app.exit(e, out, err) == 0 ? kExitSuccess : kExitBadInput;
  }

  try {
    if (app.got_subcommand(points.cmd)) {
      PointsArgs args = pointsArgs(points);
      args.terminal = errorIsTerminal(err);
      return runPointsCommand(args, out, err);
    }
    if (app.got_subcommand(run.cmd)) return runRunCommand(runArgs(run, errorIsTerminal(err)), err);
    if (app.got_subcommand(batch.cmd)) {
      return runBatchCommand(batchArgs(batch, errorIsTerminal(err)), err);
    }
    if (app.got_subcommand(fit_cmd)) {
      fit.model.abg = !no_abg;
      fit.model.diffuse = !no_diffuse;
      runFit(fit, out, err);
      return kExitSuccess;
    }
    return kExitSuccess;
  } catch (const std::exception& e) {
    const Failure f = failureOf(e);
    err << "glint: " << f.kind << e.what() << "\n";
    return f.status;
  }
}

}  // namespace glint
