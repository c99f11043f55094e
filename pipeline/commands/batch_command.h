#pragma once
/// @file
/// @brief `glint batch`: a study's scenarios run one after another (each with TBB inside), or
/// shared among the ranks of an MPI job, and aggregated into maximum-irradiance and coverage
/// maps (docs/batch.md).

#include <cstdint>
#include <ostream>
#include <string>

namespace glint {

class Cluster;

/// @brief The arguments of `glint batch`.
struct BatchArgs {
  std::string study_path;
  std::string out_dir;  ///< empty: out/<study file stem>
  int threads = 0;      ///< per process; 0: all cores
  bool fresh = false;   ///< discard the results of an earlier run in out_dir
  bool quiet = false;
  bool terminal = false;
  std::uint64_t memory_bytes = 0;  ///< the memory budget per process; 0: the default
};

/// @brief Runs the study. Each scenario leaves scenarios/sNNNNNN/ (its scene.json, maps and
/// result.json, written last, with checksums of its figures and of those files); a later run
/// in the same folder redoes only the scenarios without a result that matches its checksums.
/// Rank 0 then writes scenarios.csv, the aggregated `<plane>.exr` and `box.vdb`, and
/// summary.json, each whole or not at all, the same bytes on any number of ranks (summary.json
/// aside: it records the ranks and the wall time). Rank 0 holds the folder's FolderLock for the
/// whole run; a run that fails removes the folders it made unless a scenario in them finished.
/// @throw InputError, OutputError on bad input, an unwritable folder, a folder another process
/// holds, or an output folder holding another study's results (without `fresh`).
void runBatch(const BatchArgs& args, Cluster& cluster, std::ostream& err);

}  // namespace glint
