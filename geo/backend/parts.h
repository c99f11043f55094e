#pragma once
// The module's parts, each in its own file.
#include <functional>
#include <memory>
#include <string>

#include "geo/backend.h"

namespace glint {

std::unique_ptr<SiteConversions> projConversions(const SiteSpec& site);  // proj_site.cpp
DemPosts gdalReadDem(const std::string& path, const SiteSpec& site, const HorizontalBox& region,
                     std::size_t max_posts,
                     const std::function<void(std::size_t)>& before_reading);  // gdal_dem.cpp
std::string gdalGeoTiff(const GeoRaster& raster);                              // gdal_maps.cpp
std::string gdalZones(const GeoZones& zones);                                  // gdal_maps.cpp

}  // namespace glint
