#pragma once
/// @file
/// @brief The scene file: laser, materials, objects and accuracy settings, loaded and
/// validated at the boundary (PHYSICS.md "Scene file", README "Scene file reference").

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "facets/beam.h"
#include "facets/patch.h"
#include "facets/vec3.h"
#include "pipeline/mpe.h"

namespace glint {

/// @brief The laser of a scene (key `laser`).
struct LaserSpec {
  Vec3 position_m{0.0};
  Vec3 direction{1.0, 0.0, 0.0};  ///< unit (the file's vector, normalised)
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

/// @brief The analytic shapes (`mesh` comes with glTF support).
enum class ShapeKind { Cylinder, Sphere, Disk };

/// @brief One object (key `objects/<i>`).
struct ObjectSpec {
  ShapeKind shape = ShapeKind::Sphere;
  Vec3 center_m{0.0};
  Vec3 axis{0.0, 0.0, 1.0};  ///< unit: cylinder `axis` or disk `normal`
  double radius_m = 0.0;
  double length_m = 0.0;       ///< cylinder only
  std::uint32_t material = 0;  ///< index into Scene::materials
  int segments = 16;           ///< coarse facets around the circumference
};

/// @brief Accuracy settings (key `accuracy`, all optional).
struct AccuracySpec {
  double tolerance = 1e-3;                   ///< relative accuracy of each observer's total
  std::optional<double> floor_w_m2;          ///< default: 1e-9 × the beam's peak irradiance
  int max_depth = 16;                        ///< deepest 1→4 subdivision level
  std::int64_t max_evaluations = 4'000'000;  ///< per observer
  NormalModel normals = NormalModel::Surface;
};

/// @brief The observer box of `glint run` (key `observers`; see FieldSpec for the meaning).
struct ObserversSpec {
  Vec3 min_m{0.0};
  Vec3 max_m{0.0};
  double voxel_m = 0.0;
  double block_m = 0.0;  ///< coarsest block edge: voxel_m × a power of two (default 16 voxels)
  double tolerance = 1e-2;
  std::optional<double> floor_w_m2;  ///< default: 1e-3 × the MPE (HazardSpec)
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
  double tolerance = 1e-2;
  std::optional<double> floor_w_m2;  ///< default: 1e-3 × the MPE
};

/// @brief The exposure the hazard is judged for and its MPE (README "Hazard").
struct HazardSpec {
  /// `laser.exposure_s`, by default 0.25 s (the aversion response) for 400–700 nm and 10 s
  /// beyond 700 nm, where nothing makes the eye turn away.
  double exposure_s = 0.25;
  bool exposure_default = true;  ///< exposure_s was not in the file
  Mpe mpe;
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
};

/// @brief Reads and validates a scene file.
/// @throw InputError naming the file and the JSON pointer of the first problem, e.g.
/// `scene.json: /materials/polished/sigma: must be > 0`.
Scene loadScene(const std::filesystem::path& path);

/// @brief Validates scene JSON text; @p source names it in messages.
/// @throw InputError as loadScene.
Scene parseScene(std::string_view json_text, const std::string& source);

}  // namespace glint
