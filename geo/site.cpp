#include "geo/site.h"

#include "geo/backend.h"

namespace glint {

SiteFrame::SiteFrame(const SiteSpec& spec)
    : spec_(spec), map_(mapDefinition(spec)), conversions_(geoBackend().conversions(spec)) {}

SiteFrame::~SiteFrame() = default;

Geodetic SiteFrame::toGeodetic(const Vec3& local_m) const {
  const std::array<double, 3> g = conversions_->localToGeodetic(local_m);
  return {g[1], g[0], g[2]};
}

Vec3 SiteFrame::fromGeodetic(const Geodetic& g) const {
  return conversions_->geodeticToLocal(g.longitude_deg, g.latitude_deg, g.height_m);
}

MapPoint SiteFrame::toMap(const Vec3& local_m) const {
  const std::array<double, 3> g = conversions_->localToGeodetic(local_m);
  const std::array<double, 2> m = conversions_->geodeticToMap(g[0], g[1]);
  return {m[0], m[1]};
}

Vec3 SiteFrame::fromMap(const MapPoint& p, double height_m) const {
  const std::array<double, 2> g = conversions_->mapToGeodetic(p.easting_m, p.northing_m);
  return conversions_->geodeticToLocal(g[0], g[1], height_m);
}

}  // namespace glint
