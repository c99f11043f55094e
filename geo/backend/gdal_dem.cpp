// An elevation model's posts over a window, read through GDAL and placed through PROJ.
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "geo/backend/gdal_errors.h"
#include "geo/backend/parts.h"
#include "geo/site.h"
#include "geo/terrain.h"

namespace glint {
namespace {

using detail::GdalErrors;

struct DatasetCloser {
  void operator()(GDALDataset* d) const { GDALClose(GDALDataset::ToHandle(d)); }
};

// Points along the rectangle's edges: the transforms bend straight lines, so the window that
// holds these holds the rectangle to well within a post.
std::vector<Vec3> outline(const HorizontalBox& b) {
  std::vector<Vec3> points;
  constexpr int kPerEdge = 16;
  for (int k = 0; k <= kPerEdge; ++k) {
    const double s = static_cast<double>(k) / kPerEdge;
    const double x = b.min_x + s * (b.max_x - b.min_x), y = b.min_y + s * (b.max_y - b.min_y);
    points.emplace_back(x, b.min_y, 0.0);
    points.emplace_back(x, b.max_y, 0.0);
    points.emplace_back(b.min_x, y, 0.0);
    points.emplace_back(b.max_x, y, 0.0);
  }
  return points;
}

}  // namespace

DemPosts gdalReadDem(const std::string& path, const SiteSpec& site_spec,
                     const HorizontalBox& region, std::size_t max_posts,
                     const std::function<void(std::size_t)>& before_reading) {
  const GdalErrors quiet;
  const auto fail = [&](const std::string& what) {
    throw std::runtime_error(GdalErrors::explain(path + ": " + what));
  };
  const std::unique_ptr<SiteConversions> site = projConversions(site_spec);
  std::unique_ptr<GDALDataset, DatasetCloser> d(
      GDALDataset::FromHandle(GDALOpen(path.c_str(), GA_ReadOnly)));
  if (!d) fail("cannot be read as an elevation model");
  std::array<double, 6> gt{};
  if (d->GetRasterCount() < 1) fail("has no band of heights");
  if (d->GetGeoTransform(gt.data()) != CE_None)
    fail("has no geotransform: glint cannot tell where its posts are");
  const OGRSpatialReference* dem_srs = d->GetSpatialRef();
  if (dem_srs == nullptr) fail("has no coordinate system: glint cannot place it on the Earth");
  OGRSpatialReference source(*dem_srs);
  source.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  OGRSpatialReference wgs84;
  wgs84.SetWellKnownGeogCS("WGS84");
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> to_wgs84(
      OGRCreateCoordinateTransformation(&source, &wgs84));
  std::unique_ptr<OGRCoordinateTransformation> from_wgs84(
      OGRCreateCoordinateTransformation(&wgs84, &source));
  if (!to_wgs84 || !from_wgs84) fail("its coordinate system cannot be converted to WGS 84");
  double inverse[6];
  if (!GDALInvGeoTransform(gt.data(), inverse)) fail("has a geotransform that cannot be inverted");

  // The window of posts about the region: pixel centres at (c + 0.5, r + 0.5).
  double c_lo = std::numeric_limits<double>::infinity(), c_hi = -c_lo, r_lo = c_lo, r_hi = -c_lo;
  for (const Vec3& p : outline(region)) {
    const std::array<double, 3> g = site->localToGeodetic(p);
    double x = g[0], y = g[1];
    if (!from_wgs84->Transform(1, &x, &y)) fail("cannot hold the scene's region");
    const double c = inverse[0] + x * inverse[1] + y * inverse[2];
    const double r = inverse[3] + x * inverse[4] + y * inverse[5];
    c_lo = std::min(c_lo, c), c_hi = std::max(c_hi, c);
    r_lo = std::min(r_lo, r), r_hi = std::max(r_hi, r);
  }
  const int width = d->GetRasterXSize(), height = d->GetRasterYSize();
  // The posts whose cells reach the region, and one more each side.
  const int c0 = static_cast<int>(std::floor(c_lo - 0.5)) - 1;
  const int c1 = static_cast<int>(std::ceil(c_hi - 0.5)) + 1;
  const int r0 = static_cast<int>(std::floor(r_lo - 0.5)) - 1;
  const int r1 = static_cast<int>(std::ceil(r_hi - 0.5)) + 1;
  if (c0 + 1 < 0 || r0 + 1 < 0 || c1 - 1 >= width || r1 - 1 >= height) {
    char extent[160];
    std::snprintf(extent, sizeof extent, "x %.0f to %.0f m, y %.0f to %.0f m", region.min_x,
                  region.max_x, region.min_y, region.max_y);
    fail(std::string("does not cover the scene's region (the laser, the objects, the box and the "
                     "planes with a margin: ") +
         extent + ")");
  }
  const int wc0 = std::max(c0, 0), wc1 = std::min(c1, width - 1);
  const int wr0 = std::max(r0, 0), wr1 = std::min(r1, height - 1);
  DemPosts posts;
  posts.columns = static_cast<std::size_t>(wc1 - wc0 + 1);
  posts.rows = static_cast<std::size_t>(wr1 - wr0 + 1);
  const std::size_t n = posts.columns * posts.rows;
  if (n > max_posts) {
    fail("its posts over the scene's region number " + std::to_string(n) + ", more than " +
         std::to_string(max_posts) + " (terrain.max_posts): crop or resample it");
  }
  if (before_reading) before_reading(n);
  std::vector<double> h(n);
  GDALRasterBand* band = d->GetRasterBand(1);
  if (band->RasterIO(GF_Read, wc0, wr0, static_cast<int>(posts.columns),
                     static_cast<int>(posts.rows), h.data(), static_cast<int>(posts.columns),
                     static_cast<int>(posts.rows), GDT_Float64, 0, 0) != CE_None)
    fail("cannot be read");
  int has_nodata = 0;
  const double nodata = band->GetNoDataValue(&has_nodata);
  posts.crs_name = source.GetName() != nullptr ? source.GetName() : "unnamed";
  posts.local_m.resize(n);
  posts.valid.assign(n, 0);
  for (std::size_t r = 0; r < posts.rows; ++r) {
    for (std::size_t c = 0; c < posts.columns; ++c) {
      const std::size_t k = r * posts.columns + c;
      const double z = h[k];
      if (!std::isfinite(z) || (has_nodata != 0 && z == nodata)) continue;
      const double pc = static_cast<double>(wc0) + static_cast<double>(c) + 0.5;
      const double pr = static_cast<double>(wr0) + static_cast<double>(r) + 0.5;
      double x = gt[0] + pc * gt[1] + pr * gt[2], y = gt[3] + pc * gt[4] + pr * gt[5];
      if (!to_wgs84->Transform(1, &x, &y)) fail("has a post PROJ cannot place");
      posts.local_m[k] = site->geodeticToLocal(x, y, z);
      posts.valid[k] = 1;
    }
  }
  return posts;
}

}  // namespace glint
