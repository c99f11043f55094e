#pragma once
/// @file
/// @brief The files `glint run` and a study's scenarios (`glint batch`) write, declared in one
/// list (run_outputs.cpp): each a name, the region it is written from, its writer and whether a
/// scenario writes it too. A new output is one writer and one line of that list; marked as a
/// scenario's, every scenario writes it by the same writer (its map is then the bytes glint run
/// writes of the scenario's scene), its result.json vouches for it and --fresh may remove it.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "export/atomic_file.h"
#include "export/exr_map.h"
#include "export/field_files.h"
#include "export/lattice_vdb.h"
#include "geo/site.h"
#include "hazard/hazard.h"
#include "observers/far_field.h"
#include "observers/field.h"
#include "observers/reach.h"
#include "pipeline/base/progress.h"
#include "pipeline/setup/reach_footprint.h"

namespace glint {

class FacetIntegrator;
class InputFiles;
class StagedAmr;
struct Scene;

/// @brief The observer box as its files are written from it.
struct BoxResults {
  ObserverField& field;  ///< the VDB, written last, takes its grids
  const FacetIntegrator& integrator;
  const RunInfo& info;
};

/// @brief One plane as its map is written from it.
struct PlaneResults {
  const ObserverField& field;
  const HazardSpec& hazard;
  const RunInfo& info;
  /// The scene's site and the plane's name, for the geo-referenced maps: RunOutputs fills them.
  const SiteFrame* site = nullptr;
  std::string plane_name;
};

/// @brief One plane's maps over an engagement as its file is written from them.
struct EngagementPlaneResults {
  const PlaneGrid& grid;
  const std::vector<ExrChannel>& channels;
  const RunInfo& info;
  /// The scene's site and the plane's name, for the geo-referenced maps: RunOutputs fills them.
  const SiteFrame* site = nullptr;
  std::string plane_name;
};

/// @brief The box's maps over an engagement as its file is written from them.
struct EngagementBoxResults {
  const FieldSpec& spec;
  const std::vector<LatticeChannel>& channels;
  const RunInfo& info;
};

/// @brief The far field as its files are written from it.
struct FarResults {
  const FarField& far;
  const HazardSpec& hazard;
  const RunInfo& info;
};

/// @brief The hazard reach as its files are written from it.
struct ReachResults {
  const NearReach& near;
  const FarField& far;
  const HazardSpec& hazard;
  const RunInfo& info;
  /// Its footprint on the ground (a scene with reach.footprint), and the site RunOutputs fills.
  const ReachFootprint* footprint = nullptr;
  const SiteFrame* site = nullptr;
  bool footprint_above_ellipsoid = false;  ///< its flight altitudes are above the ellipsoid
};

/// @brief What an output is written from: the run as a whole (summary.json), the box, each
/// plane, the far field, the reach, or an engagement's plane or box.
enum class OutputRegion { Run, Box, Plane, Far, Reach, EngagementPlane, EngagementBox };

/// @brief The largest memory one writer of a region's outputs takes besides the results it is
/// written from, and its file.
struct WriterScratch {
  std::uint64_t bytes = 0;
  std::string file;    ///< empty where the region writes nothing
  std::string advice;  ///< what lowers it where the region's size does not; else empty
};

/// @brief A floor under the memory the writers of @p region's outputs take besides the results
/// they are written from (the arrays each makes: a map's channels and their rows flipped for
/// the file, a resampled volume, a surface), reckoned from @p scene before anything is
/// computed: the largest of the outputs @p scene writes of @p region, since they are written
/// one at a time. @p lattice is the region's (the box's or the plane's; null for the others),
/// @p plane_name a plane's. Each output declares its own with its writer (run_outputs.cpp);
/// the libraries' own buffers (VTK's encoder, GDAL's cache) are not counted, so the run's
/// memory watch still guards. With @p scenario, of the outputs a study's scenario writes only
/// (ScenarioMaps).
WriterScratch writerScratch(const Scene& scene, OutputRegion region,
                            const FieldSpec* lattice = nullptr, const std::string& plane_name = "",
                            bool scenario = false);

/// @brief The outputs of one `glint run` (rank 0 writes; on other ranks nothing is opened): each
/// is opened before the work (so that an unwritable folder or a path that must not be replaced
/// stops the run at once), written from its region's results when that region is done (one
/// region's field in memory at a time), and all are committed together once every check has
/// passed, as one OutputSet: all appear, summary.json last, or none does and the folder is as
/// it was.
class RunOutputs {
 public:
  /// @brief Opens every output @p scene's run writes into @p dir (none unless @p writer).
  /// @throw OutputError for a path that is an input or not a regular file, or that cannot be
  /// created.
  RunOutputs(const Scene& scene, const std::filesystem::path& dir, const InputFiles& inputs,
             bool writer);
  ~RunOutputs();
  RunOutputs(const RunOutputs&) = delete;
  RunOutputs& operator=(const RunOutputs&) = delete;

  /// @brief Every file the run writes, in the order summary.json lists them.
  [[nodiscard]] const std::vector<std::string>& names() const { return names_; }
  /// @brief The far field's files, as its entry in summary.json lists them.
  [[nodiscard]] const std::vector<std::string>& farNames() const { return far_names_; }

  void writeBox(BoxResults& box);
  void writePlane(std::size_t index, const PlaneResults& plane);
  void writeEngagementPlane(std::size_t index, const EngagementPlaneResults& plane);
  /// @brief Writes the box's maps over an engagement (rank 0; nothing on the others).
  void writeEngagementBox(const EngagementBoxResults& box);
  void writeFar(const FarResults& far);
  void writeReach(const ReachResults& reach);
  /// @brief Where a region's files show their progress while written (nullptr: nowhere): after
  /// its first second, "2/5 files of the hazard reach", as the computations do.
  void showProgress(std::ostream* err, bool terminal) {
    progress_to_ = err;
    terminal_ = terminal;
  }
  /// @brief Where summary.json is written (none unless a writer).
  [[nodiscard]] std::ostream* summary();

  /// @brief Moves every output over its final name, summary.json last (OutputSet::commit(),
  /// which calls @p after_first once the first is in place).
  /// @throw OutputError when one cannot be written; then none is in place.
  void commit(const std::function<void()>& after_first = {});

  /// @brief An entry of the list of outputs (run_outputs.cpp).
  struct Declared;

 private:
  /// The index in names_ of output @p d of plane @p plane (0 but for a plane's), if the scene
  /// has it.
  [[nodiscard]] std::optional<std::size_t> slotOf(const Declared& d, std::size_t plane) const;
  // The files of @p region (plane @p plane) counted in @p counter while they are written,
  // shown as @p noun where showProgress() asked for it.
  [[nodiscard]] std::unique_ptr<ProgressReporter> fileProgress(OutputRegion region,
                                                               std::size_t plane,
                                                               const std::string& noun,
                                                               const WorkCounter& counter) const;
  // Writes every file of @p region (plane @p plane) from @p results, in writing order, showing
  // their progress as @p noun (none where empty).
  template <class Results>
  void writeRegion(OutputRegion region, std::size_t plane, const Results& results,
                   const std::string& noun);

  std::filesystem::path dir_;
  bool writer_;
  std::vector<std::string> names_;
  std::vector<std::string> far_names_;
  OutputSet set_;  ///< every file, committed together
  // By the index of names_: each output's entry, its plane (a plane's) and its file in set_
  // (null for a staged folder, or when not the writer).
  std::vector<const Declared*> declared_;
  std::vector<std::size_t> planes_;
  std::vector<AtomicFile*> files_;
  std::unique_ptr<StagedAmr> amr_;
  std::vector<std::string> plane_names_;  ///< the scene's planes, by index
  std::ostream* progress_to_ = nullptr;
  bool terminal_ = false;
  std::unique_ptr<SiteFrame> site_;  ///< the scene's site, where it has one
};

/// @brief The maps one scenario of a study writes into its folder (glint batch): of each of
/// its regions, the outputs the list marks as a scenario's, by the run's writers. Each is
/// committed once written; the scenario's result.json, written last, vouches for them.
class ScenarioMaps {
 public:
  /// @brief The maps of a scenario of @p scene, into the scenario folder @p dir.
  ScenarioMaps(const Scene& scene, std::filesystem::path dir);

  /// @brief The maps a scenario writes, its box's then each plane's: those its result.json
  /// vouches for.
  [[nodiscard]] std::vector<std::string> names() const;
  /// @brief Writes the box's maps (the one that takes the field's grids last); returns their
  /// names.
  /// @throw OutputError when one cannot be written.
  std::vector<std::string> writeBox(BoxResults& box) const;
  /// @brief Writes the maps of the scene's plane @p index; returns their names.
  /// @throw OutputError when one cannot be written.
  std::vector<std::string> writePlane(std::size_t index, const PlaneResults& plane) const;
  /// @brief Writes the maps over time of the scene's plane @p index (an engagement's); returns
  /// their names.
  /// @throw OutputError when one cannot be written.
  std::vector<std::string> writeEngagementPlane(std::size_t index,
                                                const EngagementPlaneResults& plane) const;
  /// @brief Writes the box's maps over time (an engagement's); returns their names.
  /// @throw OutputError when one cannot be written.
  std::vector<std::string> writeEngagementBox(const EngagementBoxResults& box) const;

  /// @brief Every name glint writes in a scenario folder of a study of @p base: scene.json,
  /// result.json and the maps, a box's whether or not @p base has one (another study's
  /// scenarios may hold them) and a plane's for each of @p base's planes. All that --fresh and
  /// a failed run may remove.
  static std::vector<std::string> folderNames(const Scene& base);

 private:
  const Scene& scene_;
  std::filesystem::path dir_;
};

/// @brief The height of the far field's lat-long map (twice as wide): about as fine as the
/// cube faces' centres, at most 2048.
inline int farMapHeight(int face_pixels) { return face_pixels < 2048 ? face_pixels : 2048; }

/// @brief What an EXR map records of the run.
ExrInfo exrInfo(const RunInfo& info);

}  // namespace glint
