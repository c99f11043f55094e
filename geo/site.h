#pragma once
/// @file
/// @brief Where a scene's local frame lies on the Earth (scene key `site`): the conversions
/// between glint's frame (metres, +z up), geodetic coordinates on WGS 84 and the projected map
/// the geo-referenced outputs are drawn in, all through PROJ.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "facets/vec3.h"

namespace glint {

class SiteConversions;  // geo/backend.h

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

/// @brief A site's map: its coordinate system as PROJ defines it, its EPSG code (0 for the local
/// transverse Mercator) and a name for people, e.g. "WGS 84 / UTM zone 33N".
struct MapDefinition {
  std::string proj;
  int epsg = 0;
  std::string name;
};

/// @brief The map of @p site: the UTM zone of its longitude (the regular zones: Norway's and
/// Svalbard's exceptions only change which zone is customary there, not whether one is valid),
/// north or south by its latitude; or a transverse Mercator centred on it.
inline MapDefinition mapDefinition(const SiteSpec& site) {
  char number[2][40];
  std::snprintf(number[0], sizeof number[0], "%.17g", site.latitude_deg);
  std::snprintf(number[1], sizeof number[1], "%.17g", site.longitude_deg);
  if (site.projection == MapProjection::LocalTransverseMercator) {
    return {std::string("+proj=tmerc +lat_0=") + number[0] + " +lon_0=" + number[1] +
                " +k=1 +x_0=0 +y_0=0 +datum=WGS84 +units=m +no_defs",
            0, "transverse Mercator centred on the site (WGS 84)"};
  }
  const double lon = std::fmod(std::fmod(site.longitude_deg + 180.0, 360.0) + 360.0, 360.0);
  const int zone = std::min(60, static_cast<int>(std::floor(lon / 6.0)) + 1);
  const bool south = site.latitude_deg < 0.0;
  const std::string z = std::to_string(zone);
  return {"+proj=utm +zone=" + z + (south ? " +south" : "") + " +datum=WGS84 +units=m +no_defs",
          (south ? 32700 : 32600) + zone, "WGS 84 / UTM zone " + z + (south ? "S" : "N")};
}

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
  /// @throw std::runtime_error when the geo module cannot be loaded or PROJ cannot build the
  /// conversions.
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
  [[nodiscard]] const std::string& mapProj() const { return map_.proj; }
  /// @brief Its EPSG code (UTM), or 0 for the local transverse Mercator.
  [[nodiscard]] int mapEpsg() const { return map_.epsg; }
  /// @brief A name for people, e.g. "WGS 84 / UTM zone 33N".
  [[nodiscard]] const std::string& mapName() const { return map_.name; }

 private:
  SiteSpec spec_;
  MapDefinition map_;
  std::unique_ptr<SiteConversions> conversions_;  // PROJ's, from the geo module
};

}  // namespace glint
