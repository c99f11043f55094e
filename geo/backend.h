#pragma once
/// @file
/// @brief glint's GDAL and PROJ half, a module loaded only by a scene with a `site`
/// (libglint_geo_gdal.so beside the program): linked in, those libraries and the hundred-odd they
/// pull in would cost every run some 45 MB of resident memory before its first byte of work.
/// The module sees only this header; it throws std::runtime_error with a full message.

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "facets/vec3.h"

namespace glint {

struct SiteSpec;
struct HorizontalBox;

/// @brief The conversions of one site's frames (PROJ). Not thread-safe.
class SiteConversions {
 public:
  virtual ~SiteConversions() = default;
  /// @brief Local (m) to longitude, latitude (degrees) and height above WGS 84 (m).
  virtual std::array<double, 3> localToGeodetic(const Vec3& local_m) const = 0;
  virtual Vec3 geodeticToLocal(double longitude_deg, double latitude_deg,
                               double height_m) const = 0;
  /// @brief Longitude, latitude (degrees) to the map's easting, northing (m), and back.
  virtual std::array<double, 2> geodeticToMap(double longitude_deg, double latitude_deg) const = 0;
  virtual std::array<double, 2> mapToGeodetic(double easting_m, double northing_m) const = 0;
};

/// @brief An elevation model's posts over a window, in the site's local frame.
struct DemPosts {
  std::size_t columns = 0, rows = 0;
  std::vector<Vec3> local_m;        ///< columns × rows, row-major
  std::vector<std::uint8_t> valid;  ///< 0 where the model has no height
  std::string crs_name;
};

/// @brief A map's bands and where they lie, for a GeoTIFF.
struct GeoRaster {
  int width = 0, height = 0;
  std::array<double, 6> geotransform{};
  int epsg = 0;          ///< the map's EPSG code, or 0: map_proj
  std::string map_proj;  ///< PROJ's definition of the map's coordinate system
  std::vector<std::string> band_names, band_units;
  std::vector<const std::vector<float>*> bands;  ///< each width × height, GDAL's row order
  std::vector<std::pair<std::string, std::string>> metadata;
};

/// @brief A map's zones, as polygons on the Earth.
struct GeoZones {
  GeoRaster grid;  ///< geotransform and coordinate system; no bands
  std::string layer_name;
  bool kml = false;            ///< KML, else GeoJSON (RFC 7946)
  double pixel_area_m2 = 0.0;  ///< the plane's own area of a pixel, for `area_m2`
  struct Zone {
    std::string kind, description;
    std::vector<std::uint8_t> inside;  ///< width × height, GDAL's row order
  };
  std::vector<Zone> zones;
  std::vector<std::pair<std::string, std::string>> properties;  ///< of every polygon
};

/// @brief GDAL's block cache while a map is written (bytes): enough for the tiles of a few rows
/// of the largest map, whatever its size (GDAL's own default, 5 % of the machine's memory, lies
/// outside what --memory counts).
inline constexpr std::int64_t kGdalBlockCacheBytes = std::int64_t{64} << 20;

/// @brief What the module does.
class GeoBackend {
 public:
  virtual ~GeoBackend() = default;
  virtual std::unique_ptr<SiteConversions> conversions(const SiteSpec& site) const = 0;
  /// @brief Band 1 of the model at @p path over the posts that cover @p region and one more on
  /// each side, in @p site's frame (DemPosts::local_m). @p before_reading, if given, is told
  /// the window's posts (columns × rows) before any height is read, and may throw.
  virtual DemPosts readDem(const std::string& path, const SiteSpec& site,
                           const HorizontalBox& region, std::size_t max_posts,
                           const std::function<void(std::size_t)>& before_reading) const = 0;
  /// @brief The bytes of a GeoTIFF of @p raster.
  virtual std::string geoTiff(const GeoRaster& raster) const = 0;
  /// @brief The bytes of the zones' GeoJSON or KML.
  virtual std::string zones(const GeoZones& zones) const = 0;
};

/// @brief The module, loaded on first use from beside the running program.
/// @throw std::runtime_error when it cannot be loaded, saying why.
const GeoBackend& geoBackend();

}  // namespace glint

/// The module's one entry point.
extern "C" const glint::GeoBackend* glintGeoBackend();
