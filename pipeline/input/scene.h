#pragma once
/// @file
/// @brief The scene file: laser, materials, objects and accuracy settings, loaded and
/// validated at the boundary (docs/physics.md, "The minimal scene file"; docs/scene.md).

#include <cstdint>
#include <filesystem>
#include <glm/gtc/quaternion.hpp>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "facets/beam.h"
#include "facets/integrator.h"
#include "facets/material.h"
#include "facets/patch.h"
#include "facets/tessellate.h"
#include "facets/vec3.h"
#include "geo/site.h"
#include "geo/terrain.h"
#include "hazard/hazard.h"
#include "observers/exposure.h"
#include "observers/motion.h"
#include "pipeline/input/gltf_loader.h"

namespace glint {

class MemoryWatch;

/// @brief Where a mesh's model frame sits in the scene (key `transform`): a point p of the
/// model is at translation_m + rotation (scale ∘ p).
struct MeshTransform {
  Vec3 translation_m{0.0};
  glm::dquat rotation{1.0, 0.0, 0.0, 0.0};  ///< unit
  Vec3 scale{1.0};                          ///< per axis, non-zero; negative mirrors
};

/// @brief A mesh object's triangles and how they were read (key `objects/<i>` with shape
/// `mesh`).
struct MeshSpec {
  std::filesystem::path file;  ///< as resolved against the scene's folder
  MeshTransform transform;     ///< its translation_m is the object's centre
  MeshSurface surface = MeshSurface::PN;
  double crease_angle_deg = 30.0;  ///< for normals the file does not give
  /// Rotated and scaled, relative to transform.translation_m.
  std::shared_ptr<const TriangleMesh> mesh;
  std::size_t normals_computed = 0;    ///< triangle corners given crease-angle normals
  std::size_t primitives_skipped = 0;  ///< points and lines in the file
  std::size_t mirrored_instances = 0;  ///< node instances with a negative determinant
};

/// @brief One object (key `objects/<i>`): an analytic shape, which knows its tessellation and
/// its inside (facets/tessellate.h), or a mesh read from a glTF file.
struct ObjectSpec {
  std::variant<AnalyticShape, MeshSpec> shape;
  std::uint32_t material = 0;  ///< index into Scene::materials
  int segments = 16;           ///< an analytic shape's coarse facets around its circumference

  /// @brief The analytic shape, or null for a mesh.
  [[nodiscard]] const AnalyticShape* analytic() const { return std::get_if<AnalyticShape>(&shape); }
  /// @brief The mesh, or null for an analytic shape.
  [[nodiscard]] const MeshSpec* mesh() const { return std::get_if<MeshSpec>(&shape); }
  [[nodiscard]] MeshSpec* mesh() { return std::get_if<MeshSpec>(&shape); }
  /// @brief The shape's centre, or the mesh's translation (its model frame's origin).
  [[nodiscard]] Vec3 centre_m() const {
    const MeshSpec* m = mesh();
    return m ? m->transform.translation_m : centreOf(*analytic());
  }
};

/// @brief The observer box of `glint run` (key `observers`; see FieldSpec for the meaning).
struct ObserversSpec {
  Vec3 min_m{0.0};
  Vec3 max_m{0.0};
  double voxel_m = 0.0;
  double block_m = 0.0;  ///< coarsest block edge: voxel_m × a power of two (default 16 voxels)
  double tolerance = FieldSpec{}.tolerance;
  std::optional<double> floor_w_m2;  ///< default: HazardSpec::negligibleW_m2()
};

/// @brief A plane of observers (key `planes/<i>`): a ground plane, a slice at eye height, a
/// wall. Lattice point (i, j) lies at origin_m + pixel_m (i u_axis + j v_axis).
struct PlaneSpec {
  std::string name;  ///< names the output `<name>.exr`: letters, digits, '_' and '-'
  Vec3 origin_m{0.0};
  Vec3 u_axis{1.0, 0.0, 0.0};  ///< unit
  Vec3 v_axis{0.0, 1.0, 0.0};  ///< unit, perpendicular to u_axis
  double width_m = 0.0;        ///< extent along u_axis
  double height_m = 0.0;       ///< extent along v_axis
  double pixel_m = 0.0;
  double block_m = 0.0;  ///< coarsest square block: pixel_m × a power of two (default 16 px)
  double tolerance = FieldSpec{}.tolerance;
  std::optional<double> floor_w_m2;  ///< default: HazardSpec::negligibleW_m2()
  /// Key `above_terrain_m`: the plane (horizontal) is laid over the terrain, each observer this
  /// high above the ground below it (eye height); none: a flat plane.
  std::optional<double> above_terrain_m;
  /// With above_terrain_m: each lattice point's offset along the plane's normal, filled once
  /// the terrain is read.
  std::shared_ptr<const SurfaceOffsets> surface;
};

/// @brief The far field by direction (key `far_field`, all optional; observers/far_field.h).
struct FarFieldSettings {
  bool enabled = true;
  double tolerance = FarFieldSpec{}.tolerance;
  /// Lattice intervals per cube-face edge, a power of two in 16 .. 8192; default: the first
  /// that samples directions at most σ apart (σ the narrowest lobe), within 64 .. 4096.
  std::optional<int> face_pixels;
  std::optional<double> floor_w_sr;  ///< default: HazardSpec::negligibleW_m2() × far radius²
};

/// @brief What the footprint covers (scene key `reach.footprint`).
struct FootprintSpec {
  double radius_m = 2000.0;     ///< about the lit centre, along the ground
  double pixel_m = 0.0;         ///< 0: the radius over 512
  double above_ground_m = 1.7;  ///< eye height
  /// Flight altitudes at which the footprint is drawn too (m): above the ground (over the
  /// terrain, or the ellipsoid at the site's height without one), or above the ellipsoid.
  std::vector<double> flight_altitudes_m;
  bool altitudes_above_ellipsoid = false;
};

/// @brief The hazard reach without a box (key `reach`, all optional; observers/reach.h).
struct ReachSettings {
  /// Given: `reach.enabled` (true when the key is there without it); by default the reach
  /// runs only where there is no box or plane.
  std::optional<bool> enabled;
  int face_cells = 64;        ///< rays per cube-face edge, a multiple of 16 in 16 .. 512
  double layer_ratio = 1.02;  ///< between the radial layers, in (1, 1.5]
  /// Key `reach.footprint` (with a site): where the reach meets the ground, as polygons.
  std::optional<FootprintSpec> footprint;
};

/// @brief An engagement in time (key `engagement`; docs/engagement.md): the motion over its span
/// and how finely time is sampled.
struct EngagementSpec {
  MotionSpec motion;
  /// Its floor, unless given, HazardSpec::negligibleW_m2(); its tolerance the scene's accuracy's.
  ExposureOptions time;
  /// The longest exposure window judged: the span, or `laser.exposure_s` where shorter (the
  /// aversion response or the exposure the analyst assumes).
  double longest_window_s = 0.0;
};

/// @brief A validated scene: every number finite and in range, every reference resolved.
struct Scene {
  std::string source;  ///< the file name as given, for messages
  std::string description;
  /// Key `laser`: its position, direction, mean power (a pulse train's energy × repetition
  /// rate, a single pulse's energy / duration) and profile, attenuated by the `atmosphere`
  /// on its way out and back. Its wavelength and exposure are the hazard's.
  Beam laser;
  HazardSpec hazard;
  std::vector<Material> materials;          ///< key `materials`, in the order of their names
  std::vector<std::string> material_names;  ///< materials[i]'s key
  /// materials[i]'s measured table file (key `table`, as resolved), or empty.
  std::vector<std::filesystem::path> material_table_files;
  std::vector<ObjectSpec> objects;
  /// Key `accuracy`; the floor, unless given, 1e-9 × the beam's peak irradiance (far below
  /// any exposure limit, yet scaled to the scene); `paper` the scheme where `normals` is `flat`
  /// and no scheme is named, since flat facets are the paper scheme's model only.
  IntegratorOptions accuracy;
  std::optional<ObserversSpec> observers;  ///< `glint run` needs this or planes
  std::vector<PlaneSpec> planes;
  FarFieldSettings far_field;
  ReachSettings reach;
  std::optional<EngagementSpec> engagement;
  /// Key `site`: where the local frame lies on the Earth; with it every map of a plane flat
  /// enough is also written geo-referenced (export/geo_files.h).
  std::optional<SiteSpec> site;
  /// Key `terrain`: the elevation model under the site (`file`), read over the scene's region;
  /// it shadows the beam and the reflections, and carries the planes laid over it.
  std::shared_ptr<const Terrain> terrain;
  std::filesystem::path terrain_file;  ///< as resolved against the scene's folder

  /// @brief Whether `glint run` computes the hazard reach: asked for, or, unless refused,
  /// where there is no box or plane.
  [[nodiscard]] bool wantsReach() const {
    return reach.enabled.value_or(!observers && planes.empty());
  }

  /// @brief Whether any object is a mesh (whose surface is a model, not the shape itself).
  [[nodiscard]] bool hasMeshes() const {
    for (const ObjectSpec& o : objects) {
      if (o.mesh()) return true;
    }
    return false;
  }
};

/// @brief The lattice of @p plane, its geometry only (no accuracy): its axes u, v and normal,
/// its extent and pixel, its coarsest blocks and its surface over the terrain.
FieldSpec planeLattice(const PlaneSpec& plane);

/// @brief The memory the scene's terrain holds for the whole run (Terrain::memoryBytes()), 0
/// without one.
std::uint64_t terrainMemoryBytes(const Scene& scene);

/// @brief "the terrain (N posts)", for the memory messages; empty without one.
std::string terrainMemoryWhat(const Scene& scene);

/// @brief Tells @p watch what the scene's terrain holds (MemoryWatch::noteHeld()), if it has
/// one, so that a stop it caused names it.
void noteTerrain(MemoryWatch& watch, const Scene& scene);

/// @brief Reads and validates a scene file, and the mesh files it names. With
/// @p memory_budget_bytes > 0 (`--memory`), a mesh whose target would need more
/// (meshMemoryFloorBytes()) is refused before it is decoded, and a terrain whose posts over the
/// scene's region would need more, with the target (Terrain::memoryBytes()), before they are read.
/// @throw InputError naming the file and the JSON pointer of the first problem, e.g.
/// `scene.json: /materials/polished/sigma: must be > 0`.
Scene loadScene(const std::filesystem::path& path, std::uint64_t memory_budget_bytes = 0);

/// @brief Validates scene JSON text; @p source names it in messages, and mesh `file`s are
/// relative to @p folder (default: the folder of @p source) and loaded within @p mesh_limits
/// and @p memory_budget_bytes (as loadScene()).
/// @throw InputError as loadScene.
Scene parseScene(std::string_view json_text, const std::string& source,
                 const std::optional<std::filesystem::path>& folder = std::nullopt,
                 const GltfLimits& mesh_limits = {}, std::uint64_t memory_budget_bytes = 0);

/// @brief Checks the values of @p scene that code may change after parsing (a study's scenario
/// moves and turns objects, turns the laser, changes materials) by the rules the scene file's
/// reader applies to them.
/// @throw InputError naming scene.source and the JSON pointer, as parseScene() words it.
void recheckScene(const Scene& scene);

/// @brief Applies the command line's overrides of @p accuracy (`--normals`, `--scheme`) under the
/// scene file's rule: flat normals are the paper scheme's model only, so flat normals without a
/// named scheme select it, and flat normals with another scheme are refused.
/// @throw InputError naming @p source and `--scheme paper`.
void overrideAccuracy(IntegratorOptions& accuracy, std::optional<NormalModel> normals,
                      std::optional<IntegrationScheme> scheme, const std::string& source);

}  // namespace glint
