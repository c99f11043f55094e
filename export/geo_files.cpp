#include "export/geo_files.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "export/atomic_file.h"
#include "geo/backend.h"

namespace glint {
namespace {

// The local point at continuous pixel coordinates (c, r): corner (0, 0) is half a pixel before
// lattice point (0, height − 1).
Vec3 pixelPoint(const PlaneGrid& g, double c, double r) {
  return g.origin_m + (c - 0.5) * g.pixel_m * g.u_axis +
         (static_cast<double>(g.height) - 0.5 - r) * g.pixel_m * g.v_axis;
}

// @p values (the EXR's order: j × width + i) in GDAL's row order: row r is lattice row
// height − 1 − r.
template <typename T>
std::vector<T> gdalRows(const PlaneGrid& g, const std::vector<T>& values) {
  const auto w = static_cast<std::size_t>(g.width);
  std::vector<T> rows(values.size());
  for (int r = 0; r < g.height; ++r) {
    const auto j = static_cast<std::size_t>(g.height - 1 - r);
    std::copy_n(values.begin() + static_cast<std::ptrdiff_t>(j * w), w,
                rows.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(r) * w));
  }
  return rows;
}

std::string printed(const char* format, double x) {
  char text[64];
  std::snprintf(text, sizeof text, format, x);
  return text;
}

GeoRaster rasterOf(const PlaneGrid& g, const SiteFrame& site) {
  GeoRaster r;
  r.width = g.width;
  r.height = g.height;
  r.geotransform = placeOnMap(g, site).geotransform;
  r.epsg = site.mapEpsg();
  r.map_proj = site.mapProj();
  return r;
}

std::vector<std::pair<std::string, std::string>> metadata(const GeoInfo& info,
                                                          const SiteFrame& site) {
  const SiteSpec& s = site.spec();
  char where[200];
  std::snprintf(where, sizeof where,
                "latitude %.9f deg, longitude %.9f deg, height %.3f m, +x bearing %.6f deg",
                s.latitude_deg, s.longitude_deg, s.height_m, s.bearing_deg);
  return {{"GLINT_PROGRAM", info.program_version},
          {"GLINT_PLANE", info.plane_name},
          {"GLINT_MPE_RULE", info.mpe_rule},
          {"GLINT_WAVELENGTH_NM", printed("%.17g", info.wavelength_nm)},
          {"GLINT_MPE_W_M2", printed("%.17g", info.mpe_w_m2)},
          {"GLINT_SITE", where}};
}

// The module's bytes, or its failure as an OutputError naming the file's plane.
template <typename Make>
void writeBytes(std::ostream& out, const std::string& plane, Make make) {
  std::string bytes;
  try {
    bytes = make();
  } catch (const std::runtime_error& e) {
    throw OutputError("the geo-referenced map of plane " + plane + ": " + e.what());
  }
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

bool mappable(const Vec3& u_axis, const Vec3& v_axis) {
  const Vec3 n = glm::normalize(glm::cross(u_axis, v_axis));
  return std::abs(n.z) >= std::cos(kMaxMapTiltDeg * 3.14159265358979323846 / 180.0) - 1e-12;
}

GeoPlacement placeOnMap(const PlaneGrid& g, const SiteFrame& site) {
  const double w = g.width, h = g.height;
  const MapPoint o = site.toMap(pixelPoint(g, 0.0, 0.0));
  const MapPoint across = site.toMap(pixelPoint(g, w, 0.0));
  const MapPoint down = site.toMap(pixelPoint(g, 0.0, h));
  GeoPlacement p;
  p.geotransform = {
      o.easting_m,  (across.easting_m - o.easting_m) / w,   (down.easting_m - o.easting_m) / h,
      o.northing_m, (across.northing_m - o.northing_m) / w, (down.northing_m - o.northing_m) / h};
  const auto& gt = p.geotransform;
  for (const auto& [c, r] : {std::pair{w, h},
                             {0.5 * w, 0.5 * h},
                             {0.5 * w, 0.0},
                             {0.0, 0.5 * h},
                             {w, 0.5 * h},
                             {0.5 * w, h}}) {
    const MapPoint exact = site.toMap(pixelPoint(g, c, r));
    const double e = gt[0] + c * gt[1] + r * gt[2], n = gt[3] + c * gt[4] + r * gt[5];
    p.affine_error_m =
        std::max(p.affine_error_m, std::hypot(e - exact.easting_m, n - exact.northing_m));
  }
  return p;
}

void writeGeoTiff(std::ostream& out, const PlaneGrid& g, const std::vector<ExrChannel>& channels,
                  const std::vector<std::string>& units, const SiteFrame& site,
                  const GeoInfo& info) {
  const auto n = static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.height);
  if (units.size() != channels.size())
    throw std::invalid_argument("writeGeoTiff: one unit per channel");
  GeoRaster r = rasterOf(g, site);
  std::vector<std::vector<float>> rows;
  rows.reserve(channels.size());
  for (std::size_t b = 0; b < channels.size(); ++b) {
    const ExrChannel& c = channels[b];
    if (c.values == nullptr || c.values->size() != n)
      throw std::invalid_argument("writeGeoTiff: channel " + c.name +
                                  " must hold width × height values");
    rows.push_back(gdalRows(g, *c.values));
    r.band_names.push_back(c.name);
    r.band_units.push_back(units[b]);
  }
  for (const std::vector<float>& band : rows) r.bands.push_back(&band);
  r.metadata = metadata(info, site);
  r.metadata.emplace_back("GLINT_AFFINE_ERROR_M",
                          printed("%.3g", placeOnMap(g, site).affine_error_m));
  const auto vec = [](const Vec3& v) {
    char text[100];
    std::snprintf(text, sizeof text, "%.17g %.17g %.17g", v.x, v.y, v.z);
    return std::string(text);
  };
  r.metadata.emplace_back("GLINT_ORIGIN_M", vec(g.origin_m));
  r.metadata.emplace_back("GLINT_U_AXIS", vec(g.u_axis));
  r.metadata.emplace_back("GLINT_V_AXIS", vec(g.v_axis));
  r.metadata.emplace_back("GLINT_PIXEL_M", printed("%.17g", g.pixel_m));
  r.metadata.emplace_back("GLINT_ROWS",
                          "row r holds lattice row height - 1 - r, as the EXR map; each pixel "
                          "the square of side pixel_m about its lattice point, seen from above");
  writeBytes(out, info.plane_name, [&] { return geoBackend().geoTiff(r); });
}

void writeZones(std::ostream& out, VectorFormat format, const PlaneGrid& g,
                const std::vector<ZoneMask>& zones, const SiteFrame& site, const GeoInfo& info) {
  const auto n = static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.height);
  GeoZones z;
  z.grid = rasterOf(g, site);
  z.layer_name = info.plane_name + "_zones";
  z.kml = format == VectorFormat::Kml;
  z.pixel_area_m2 = g.pixel_m * g.pixel_m;
  z.properties = {{"plane", info.plane_name}, {"mpe_rule", info.mpe_rule}};
  for (const ZoneMask& zone : zones) {
    if (zone.inside.size() != n)
      throw std::invalid_argument("writeZones: zone " + zone.kind +
                                  " must hold width × height values");
    z.zones.push_back({zone.kind, zone.description, gdalRows(g, zone.inside)});
  }
  writeBytes(out, info.plane_name, [&] { return geoBackend().zones(z); });
}

}  // namespace glint
