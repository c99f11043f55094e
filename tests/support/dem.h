#pragma once
// Writes small elevation models for the tests through GDAL: a GeoTIFF in the site's map
// coordinates whose posts' heights a function of their local position gives.
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <filesystem>
#include <functional>
#include <stdexcept>
#include <vector>

#include "geo/site.h"

namespace glint::test {

/// @brief A width × height DEM of posts @p spacing_m apart on @p site's map, its top-left
/// post's cell corner at map point @p corner, each post's height above the ellipsoid
/// @p height(x, y) at its local (x, y) (the map's rows run south from the corner).
inline void writeDem(const std::filesystem::path& path, const SiteFrame& site,
                     const MapPoint& corner, double spacing_m, int width, int height,
                     const std::function<double(double, double)>& height_m) {
  GDALAllRegister();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  GDALDataset* d = driver->Create(path.c_str(), width, height, 1, GDT_Float32, nullptr);
  if (d == nullptr) throw std::runtime_error("cannot write " + path.string());
  double gt[6] = {corner.easting_m, spacing_m, 0.0, corner.northing_m, 0.0, -spacing_m};
  d->SetGeoTransform(gt);
  OGRSpatialReference srs;
  if (site.mapEpsg() > 0) {
    srs.importFromEPSG(site.mapEpsg());
  } else {
    srs.importFromProj4(site.mapProj().c_str());
  }
  d->SetSpatialRef(&srs);
  std::vector<float> values(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) {
      const MapPoint p{gt[0] + (c + 0.5) * spacing_m, gt[3] - (r + 0.5) * spacing_m};
      const Vec3 local = site.fromMap(p, 0.0);
      values[static_cast<std::size_t>(r) * static_cast<std::size_t>(width) +
             static_cast<std::size_t>(c)] = static_cast<float>(height_m(local.x, local.y));
    }
  if (d->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, width, height, values.data(), width, height,
                                    GDT_Float32, 0, 0) != CE_None)
    throw std::runtime_error("cannot write the heights of " + path.string());
  GDALClose(GDALDataset::ToHandle(d));
}

/// @brief A DEM in latitude and longitude (EPSG:4326): posts @p step_deg apart, the top-left
/// post's cell corner at (@p west_deg, @p north_deg), heights @p height_m(latitude, longitude).
inline void writeGeographicDem(const std::filesystem::path& path, double west_deg, double north_deg,
                               double step_deg, int width, int height,
                               const std::function<double(double, double)>& height_m) {
  GDALAllRegister();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  GDALDataset* d = driver->Create(path.c_str(), width, height, 1, GDT_Float32, nullptr);
  if (d == nullptr) throw std::runtime_error("cannot write " + path.string());
  double gt[6] = {west_deg, step_deg, 0.0, north_deg, 0.0, -step_deg};
  d->SetGeoTransform(gt);
  OGRSpatialReference srs;
  srs.importFromEPSG(4326);
  d->SetSpatialRef(&srs);
  std::vector<float> values(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c) {
      values[static_cast<std::size_t>(r) * static_cast<std::size_t>(width) +
             static_cast<std::size_t>(c)] =
          static_cast<float>(
              height_m(north_deg - (r + 0.5) * step_deg, west_deg + (c + 0.5) * step_deg));
    }
  if (d->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, width, height, values.data(), width, height,
                                    GDT_Float32, 0, 0) != CE_None)
    throw std::runtime_error("cannot write the heights of " + path.string());
  GDALClose(GDALDataset::ToHandle(d));
}

}  // namespace glint::test
