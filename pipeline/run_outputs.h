#pragma once
/// @file
/// @brief The files `glint run` writes, declared in one list (run_outputs.cpp): each is opened
/// before the work (so that an unwritable folder or a path that must not be replaced stops the
/// run at once), written from its region's results when that region is done (one region's
/// field in memory at a time), and all are committed together once every check has passed.
/// A new output is one writer and one line of that list; `glint batch` writes its scenarios'
/// maps with the same writers.

#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "export/exr_map.h"
#include "export/field_files.h"
#include "hazard/hazard.h"
#include "observers/far_field.h"
#include "observers/field.h"

namespace glint {

class AtomicFile;
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
};

/// @brief The far field as its files are written from it.
struct FarResults {
  const FarField& far;
  const HazardSpec& hazard;
  const RunInfo& info;
};

/// @brief The outputs of one `glint run` (rank 0 writes; on other ranks nothing is opened).
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
  void writeFar(const FarResults& far);
  /// @brief Where summary.json is written (none unless a writer).
  [[nodiscard]] std::ostream* summary();

  /// @brief Renames every output over its final name.
  /// @throw OutputError when one cannot be written.
  void commit();

  /// @brief An entry of the list of outputs (run_outputs.cpp).
  struct Declared;

 private:
  std::filesystem::path dir_;
  bool writer_;
  std::vector<std::string> names_;
  std::vector<std::string> far_names_;
  std::vector<const Declared*> declared_;  ///< by the index of names_ (null: a plane's map)
  std::vector<std::unique_ptr<AtomicFile>> files_;  ///< by the index of names_ (null: a folder)
  std::unique_ptr<StagedAmr> amr_;
  const Scene& scene_;
};

/// @brief The height of the far field's lat-long map (twice as wide): about as fine as the
/// cube faces' centres, at most 2048.
inline int farMapHeight(int face_pixels) { return face_pixels < 2048 ? face_pixels : 2048; }

/// @brief What an EXR map records of the run.
ExrInfo exrInfo(const RunInfo& info);

/// @brief A plane's map as `<plane>.exr` (glint run and a batch's scenarios): irradiance,
/// hazard ratios, levels and status. Returns the map (a batch adds its irradiance up).
PlaneMap writePlaneExr(std::ostream& out, const ObserverField& field, const HazardSpec& hazard,
                       const RunInfo& info);

}  // namespace glint
