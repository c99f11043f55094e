#pragma once
/// @file
/// @brief Where a scene's local frame lies on the Earth (scene key `site`): the conversions
/// between glint's frame (metres, +z up), geodetic coordinates on WGS 84 and the projected map
/// the geo-referenced outputs are drawn in, all through PROJ.

#include <memory>
#include <string>

#include "facets/vec3.h"

namespace glint {

/// @brief The projected coordinate system of a site's maps.
enum class MapProjection {
  Utm,                      ///< the UTM zone of the site on WGS 84 (EPSG:326zz, 327zz south)
  LocalTransverseMercator,  ///< a transverse Mercator centred on the site, scale 1 there
};

/// @brief The site as a scene file gives it.
struct SiteSpec {
  double latitude_deg = 0.0;   ///< of the local origin, WGS 84, north positive
  double longitude_deg = 0.0;  ///< east positive
  /// Of the local origin above the WGS 84 ellipsoid; a terrain's heights must share its datum
  /// (a geoid's undulation moves everything alike and shifts nothing sideways).
  double height_m = 0.0;
  double bearing_deg = 0.0;  ///< of the local +x axis, clockwise from true north
  MapProjection projection = MapProjection::Utm;
};

/// @brief A point on the ellipsoid.
struct Geodetic {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double height_m = 0.0;  ///< above the ellipsoid
};

/// @brief A point of the projected map: easting and northing (m).
struct MapPoint {
  double easting_m = 0.0;
  double northing_m = 0.0;
};

/// @brief The site's frames and the exact conversions between them.
///
/// glint's frame is the local tangent frame at the site: +z along the ellipsoid's normal, +x at
/// the bearing given, +y 90° anticlockwise from it seen from above. The conversions are PROJ's
/// topocentric and cartesian ones (no flat-Earth approximation: 5 km off the origin the ground
/// is 2 m below the tangent plane, and so it is here).
/// Not thread-safe: each thread that converts needs its own SiteFrame.
class SiteFrame {
 public:
  /// @throw std::runtime_error when PROJ cannot build the conversions.
  explicit SiteFrame(const SiteSpec& spec);
  ~SiteFrame();
  SiteFrame(const SiteFrame&) = delete;
  SiteFrame& operator=(const SiteFrame&) = delete;

  [[nodiscard]] const SiteSpec& spec() const { return spec_; }

  [[nodiscard]] Geodetic toGeodetic(const Vec3& local_m) const;
  [[nodiscard]] Vec3 fromGeodetic(const Geodetic& g) const;
  /// @brief The map point below @p local_m (its height dropped along the ellipsoid's normal).
  [[nodiscard]] MapPoint toMap(const Vec3& local_m) const;
  /// @brief The local point at map point @p p and height @p height_m above the ellipsoid.
  [[nodiscard]] Vec3 fromMap(const MapPoint& p, double height_m) const;

  /// @brief The map's coordinate system as PROJ's definition string.
  [[nodiscard]] const std::string& mapProj() const { return map_proj_; }
  /// @brief Its EPSG code (UTM), or 0 for the local transverse Mercator.
  [[nodiscard]] int mapEpsg() const { return map_epsg_; }
  /// @brief A name for people, e.g. "WGS 84 / UTM zone 33N".
  [[nodiscard]] const std::string& mapName() const { return map_name_; }

 private:
  struct Proj;
  SiteSpec spec_;
  std::string map_proj_;
  int map_epsg_ = 0;
  std::string map_name_;
  std::unique_ptr<Proj> proj_;
};

}  // namespace glint
