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
#include <vector>

#include "facets/beam.h"
#include "facets/integrator.h"  // IntegrationScheme, IntegratorOptions (the defaults)
#include "facets/patch.h"
#include "facets/tessellate.h"
#include "facets/vec3.h"
#include "hazard/hazard.h"
#include "pipeline/gltf_loader.h"

namespace glint {

/// @brief The laser of a scene (key `laser`).
struct LaserSpec {
  Vec3 position_m{0.0};
  Vec3 direction{1.0, 0.0, 0.0};  ///< unit (the file's vector, normalised)
  /// Mean power over the exposure: a pulse train's energy × repetition rate, a single pulse's
  /// energy / duration (`power_w`, or from `pulse`).
  double power_w = 0.0;
  double wavelength_nm = 0.0;
  std::optional<double> exposure_s;  ///< as in the file; HazardSpec has the one in use
  BeamProfile profile = BeamProfile::FlatTop;
  double radius_m = 0.0;        ///< flat_top `radius_m` or gaussian `w_m`
  double divergence_rad = 0.0;  ///< full angle
};

/// @brief One named material (key `materials/<name>`).
struct MaterialSpec {
  std::string name;
  double specular_reflectance = 0.0;
  double diffuse_reflectance = 0.0;
  double sigma = 0.0;
};

/// @brief The analytic shapes and triangle meshes from glTF files.
enum class ShapeKind { Cylinder, Sphere, Disk, Mesh };

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
  MeshTransform transform;
  MeshSurface surface = MeshSurface::PN;
  double crease_angle_deg = 30.0;  ///< for normals the file does not give
  /// Rotated and scaled, relative to transform.translation_m (the object's centre_m).
  std::shared_ptr<const TriangleMesh> mesh;
  std::size_t normals_computed = 0;    ///< triangle corners given crease-angle normals
  std::size_t primitives_skipped = 0;  ///< points and lines in the file
  std::size_t mirrored_instances = 0;  ///< node instances with a negative determinant
};

/// @brief One object (key `objects/<i>`).
struct ObjectSpec {
  ShapeKind shape = ShapeKind::Sphere;
  Vec3 center_m{0.0};
  Vec3 axis{0.0, 0.0, 1.0};  ///< unit: cylinder `axis` or disk `normal`
  double radius_m = 0.0;
  double length_m = 0.0;         ///< cylinder only
  std::uint32_t material = 0;    ///< index into Scene::materials
  int segments = 16;             ///< coarse facets around the circumference
  std::optional<MeshSpec> mesh;  ///< mesh only; centre_m is its translation

  /// @brief The analytic shape this object is, which knows its tessellation, its count of
  /// coarse facets and where observers are inside it (facets/tessellate.h); nothing for a mesh.
  [[nodiscard]] std::optional<AnalyticShape> analytic() const;
};

/// @brief Accuracy settings (key `accuracy`, all optional).
struct AccuracySpec {
  // The defaults are the integrator's own (facets/integrator.h).
  double tolerance = IntegratorOptions{}.tolerance;  ///< relative accuracy of each total
  std::optional<double> floor_w_m2;               ///< default: 1e-9 × the beam's peak irradiance
  int max_depth = IntegratorOptions{}.max_depth;  ///< deepest 1→4 subdivision level
  std::int64_t max_evaluations = IntegratorOptions{}.max_evaluations;  ///< per observer
  NormalModel normals = NormalModel::Surface;
  bool occlusion = true;  ///< occlusion rays where the target can shadow itself
  /// `lobe` (the default), `cubature` or `paper` (integrator.h); `paper` where `normals` is
  /// `flat` and no scheme is named, since flat facets are the paper scheme's model only.
  IntegrationScheme scheme = IntegrationScheme::Lobe;
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

/// @brief A validated scene: every number finite and in range, every reference resolved.
struct Scene {
  std::string source;  ///< the file name as given, for messages
  std::string description;
  LaserSpec laser;
  HazardSpec hazard;
  std::vector<MaterialSpec> materials;
  std::vector<ObjectSpec> objects;
  AccuracySpec accuracy;
  std::optional<ObserversSpec> observers;  ///< `glint run` needs this or planes
  std::vector<PlaneSpec> planes;
  FarFieldSettings far_field;

  /// @brief Whether any object is a mesh (whose surface is a model, not the shape itself).
  [[nodiscard]] bool hasMeshes() const {
    for (const ObjectSpec& o : objects) {
      if (o.mesh) return true;
    }
    return false;
  }
};

/// @brief Reads and validates a scene file, and the mesh files it names. With
/// @p memory_budget_bytes > 0 (`--memory`), a mesh whose target would need more
/// (meshMemoryFloorBytes()) is refused before it is decoded.
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
/// moves and turns objects, turns the laser, changes materials) by the scene file's own rules.
/// @throw InputError naming scene.source and the JSON pointer, as parseScene() words it.
void recheckScene(const Scene& scene);

/// @brief Applies the command line's overrides of @p accuracy (`--normals`, `--scheme`) under the
/// scene file's rule: flat normals are the paper scheme's model only, so flat normals without a
/// named scheme select it, and flat normals with another scheme are refused.
/// @throw InputError naming @p source and `--scheme paper`.
void overrideAccuracy(AccuracySpec& accuracy, std::optional<NormalModel> normals,
                      std::optional<IntegrationScheme> scheme, const std::string& source);

/// @brief The rotation R = Rz(yaw) Ry(pitch) Rx(roll), angles in degrees (the convention of
/// studies and of a mesh's `yaw_pitch_roll_deg`).
glm::dquat yawPitchRoll(double yaw_deg, double pitch_deg, double roll_deg);

}  // namespace glint
