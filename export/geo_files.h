#pragma once
/// @file
/// @brief Maps a GIS can place: a plane's map as a GeoTIFF in the site's projected coordinate
/// system, and its hazard zones as polygons in GeoJSON (RFC 7946) and KML, through GDAL.

#include <array>
#include <ostream>
#include <string>
#include <vector>

#include "export/exr_map.h"
#include "geo/site.h"

namespace glint {

/// @brief Where a plane's pixels lie on the site's map.
struct GeoPlacement {
  /// GDAL's affine geotransform: pixel corner (c, r) at easting gt[0] + c gt[1] + r gt[2],
  /// northing gt[3] + c gt[4] + r gt[5]. Row r is lattice row height − 1 − r (as in the EXR),
  /// pixel (c, r) the square of side pixel_m about its lattice point, seen from above.
  std::array<double, 6> geotransform{};
  /// The largest distance (m) between where the affine map puts a pixel's corner or centre and
  /// where PROJ puts it, over the map's corners, edges' midpoints and centre.
  double affine_error_m = 0.0;
};

/// @brief The steepest plane a map is drawn for: its normal within 60° of the vertical. A
/// steeper plane (a wall) seen from above is a sliver, and a map of it would mislead.
inline constexpr double kMaxMapTiltDeg = 60.0;

/// @brief Whether a plane of axes @p u_axis, @p v_axis (in the site's local frame, +z up) is
/// flat enough for a map (kMaxMapTiltDeg).
bool mappable(const Vec3& u_axis, const Vec3& v_axis);

/// @brief The placement of @p grid's pixels on @p site's map.
/// @pre mappable(grid.u_axis, grid.v_axis)
GeoPlacement placeOnMap(const PlaneGrid& grid, const SiteFrame& site);

/// @brief Text every geo-referenced file carries as metadata (GDAL metadata items, and the
/// properties of each polygon).
struct GeoInfo {
  std::string program_version;
  std::string plane_name;
  std::string mpe_rule;  ///< the standard, table and row the MPE came from
  double wavelength_nm = 0.0;
  double mpe_w_m2 = 0.0;
};

/// @brief Writes @p grid's @p channels (width × height floats each, in the EXR's row order: index
/// j × width + i for lattice point (i, j)) as a Float32 GeoTIFF, one band per channel named by
/// the channel, in @p site's map coordinates. Units name each band's unit ("W/m^2", "1", ...),
/// one per channel.
/// @throw OutputError when GDAL fails.
void writeGeoTiff(std::ostream& out, const PlaneGrid& grid, const std::vector<ExrChannel>& channels,
                  const std::vector<std::string>& units, const SiteFrame& site,
                  const GeoInfo& info);

/// @brief One kind of zone on a plane's map: the lattice points where @p inside is nonzero.
struct ZoneMask {
  std::string kind;                   ///< e.g. "hazardous": the polygons' `kind` property
  std::string description;            ///< what the zone means, for people
  std::vector<unsigned char> inside;  ///< width × height, the EXR's row order
};

enum class VectorFormat { GeoJson, Kml };

/// @brief Writes the zones of @p grid as polygons on the Earth (WGS 84 longitude and latitude):
/// each zone the union of the pixels (squares of side pixel_m about the lattice points) inside
/// it, so that no hazardous lattice point lies outside its zone. Each polygon carries the
/// properties `kind`, `description`, `plane`, `mpe_rule` and `area_m2` (in the map's plane).
/// @throw OutputError when GDAL fails.
void writeZones(std::ostream& out, VectorFormat format, const PlaneGrid& grid,
                const std::vector<ZoneMask>& zones, const SiteFrame& site, const GeoInfo& info);

}  // namespace glint
