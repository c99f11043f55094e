#pragma once
/// @file
/// @brief The ground under a scene: a digital elevation model placed in the site's local frame
/// as the piecewise-linear surface through its posts, which both shadows (facets/occluder.h)
/// and carries observers at eye height (docs/terrain.md).

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "facets/occluder.h"
#include "facets/vec3.h"
#include "geo/site.h"

namespace glint {

/// @brief The local horizontal rectangle a terrain must cover (m, the site's frame).
struct HorizontalBox {
  double min_x = 0.0, min_y = 0.0, max_x = 0.0, max_y = 0.0;
};

/// @brief A digital elevation model in the site's frame.
///
/// Each post of the model (the centre of its pixel, as GDAL's geotransform places it, at the
/// height the band holds above the datum the site's height shares) is carried to the site's
/// local frame by PROJ; each cell of four valid posts becomes two triangles. That surface, and
/// no other, is what shadows and what observers stand on, so an observer at eye height is
/// never inside the ground that shadows it.
class Terrain {
 public:
  /// @brief Reads band 1 of @p dem_file (any raster GDAL reads with a geotransform and a
  /// coordinate system: a GeoTIFF in UTM or in latitude and longitude, ...), only the posts that
  /// cover @p region and one more on each side.
  /// @param max_posts refuse a window of more posts than this (`terrain.max_posts`).
  /// @param before_reading told the window's posts once they are known, before any height is
  /// read (or any of memoryBytes() allocated): the memory budget's check, which may throw.
  /// @throw std::runtime_error naming the file: unreadable, without a coordinate system or a
  /// geotransform, not covering the region, or too large.
  static std::shared_ptr<const Terrain> read(
      const std::filesystem::path& dem_file, const SiteFrame& site, const HorizontalBox& region,
      std::size_t max_posts, const std::function<void(std::size_t)>& before_reading = {});

  /// @brief Bytes a terrain over a window of @p window_posts posts holds for the whole run, or
  /// more: its triangles and heights, and their shares of the height queries' and the
  /// occluder's Embree scenes (docs/terrain.md, "Memory"). A floor, as the target's estimate is.
  static std::uint64_t memoryBytes(std::size_t window_posts);
  /// @brief memoryBytes() of this terrain's window.
  [[nodiscard]] std::uint64_t memoryBytes() const { return memoryBytes(window_posts_); }
  /// @brief The posts of the window read (columns × rows, holes included).
  [[nodiscard]] std::size_t windowPosts() const { return window_posts_; }

  ~Terrain();
  Terrain(const Terrain&) = delete;
  Terrain& operator=(const Terrain&) = delete;

  /// @brief The surface's triangles, for the occluder.
  [[nodiscard]] std::shared_ptr<const ShadowMesh> mesh() const { return mesh_; }

  /// @brief The height (local z, m) of the surface above local point (@p x_m, @p y_m): the
  /// highest of its triangles there, in double precision; none off the model or over a hole.
  [[nodiscard]] std::optional<double> surfaceZ(double x_m, double y_m) const;

  /// @brief Whether the surface leaves the segment from @p from_m to @p to_m clear (its ends'
  /// first and last millimetre aside: an end may stand on the ground).
  [[nodiscard]] bool segmentClear(const Vec3& from_m, const Vec3& to_m) const;

  [[nodiscard]] std::size_t posts() const { return posts_; }
  /// @brief The largest distance between neighbouring posts (m): the model's resolution.
  [[nodiscard]] double postSpacingM() const { return post_spacing_m_; }
  /// @brief What GDAL says the model's coordinate system is.
  [[nodiscard]] const std::string& crsName() const { return crs_name_; }

 private:
  Terrain();
  struct Heights;
  std::shared_ptr<ShadowMesh> mesh_;
  std::unique_ptr<Heights> heights_;  // an Embree scene for the vertical queries
  std::size_t posts_ = 0;
  std::size_t window_posts_ = 0;
  double post_spacing_m_ = 0.0;
  double min_z_ = 0.0, max_z_ = 0.0;  // the local heights the surface spans (m)
  std::string crs_name_;
};

}  // namespace glint
