// The module's entry point: the one GeoBackend, built from PROJ's conversions and GDAL's
// readers and writers.
#include "geo/backend.h"
#include "geo/backend/parts.h"

namespace glint {
namespace {

class Backend final : public GeoBackend {
 public:
  std::unique_ptr<SiteConversions> conversions(const SiteSpec& site) const override {
    return projConversions(site);
  }
  DemPosts readDem(const std::string& path, const SiteSpec& site, const HorizontalBox& region,
                   std::size_t max_posts,
                   const std::function<void(std::size_t)>& before_reading) const override {
    return gdalReadDem(path, site, region, max_posts, before_reading);
  }
  std::string geoTiff(const GeoRaster& raster) const override { return gdalGeoTiff(raster); }
  std::string zones(const GeoZones& zones) const override { return gdalZones(zones); }
};

}  // namespace
}  // namespace glint

extern "C" const glint::GeoBackend* glintGeoBackend() {
  static const glint::Backend backend;
  return &backend;
}
