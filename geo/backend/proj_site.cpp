// The site's conversions through PROJ: the local tangent frame, WGS 84 and the map.
#include <proj.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "geo/backend.h"
#include "geo/site.h"

namespace glint {
namespace {

std::string number(double x) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", x);
  return text;
}

constexpr double kDegree = 3.14159265358979323846 / 180.0;

// One context per site, so that sites on different threads never share one.
class ProjSite final : public SiteConversions {
 public:
  explicit ProjSite(const SiteSpec& spec) : bearing_rad_(spec.bearing_deg * kDegree) {
    context_ = proj_context_create();
    if (context_ == nullptr) throw std::runtime_error("PROJ cannot create a context");
    // No network grids: the conversions are ellipsoidal and need none.
    proj_context_set_enable_network(context_, 0);
    const std::string origin =
        " +lat_0=" + number(spec.latitude_deg) + " +lon_0=" + number(spec.longitude_deg);
    topocentric_ = create(
        "+proj=pipeline +step +inv +proj=topocentric" + origin + " +h_0=" + number(spec.height_m) +
        " +ellps=WGS84 +step +inv +proj=cart +ellps=WGS84 +step +proj=unitconvert +xy_in=rad "
        "+xy_out=deg");
    const std::string map = mapDefinition(spec).proj;
    map_ = create("+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad +step " +
                  map.substr(0, map.find(" +no_defs")));
  }
  ~ProjSite() override {
    if (map_ != nullptr) proj_destroy(map_);
    if (topocentric_ != nullptr) proj_destroy(topocentric_);
    if (context_ != nullptr) proj_context_destroy(context_);
  }
  ProjSite(const ProjSite&) = delete;
  ProjSite& operator=(const ProjSite&) = delete;

  std::array<double, 3> localToGeodetic(const Vec3& p) const override {
    // The local axes in east, north: +x at the bearing, +y a quarter turn anticlockwise.
    const double b = bearing_rad_;
    const double east = p.x * std::sin(b) - p.y * std::cos(b);
    const double north = p.x * std::cos(b) + p.y * std::sin(b);
    const PJ_COORD out = proj_trans(topocentric_, PJ_FWD, proj_coord(east, north, p.z, 0.0));
    return {out.v[0], out.v[1], out.v[2]};
  }
  Vec3 geodeticToLocal(double lon, double lat, double h) const override {
    const PJ_COORD enu = proj_trans(topocentric_, PJ_INV, proj_coord(lon, lat, h, 0.0));
    const double b = bearing_rad_;
    const double east = enu.v[0], north = enu.v[1];
    return {east * std::sin(b) + north * std::cos(b), -east * std::cos(b) + north * std::sin(b),
            enu.v[2]};
  }
  std::array<double, 2> geodeticToMap(double lon, double lat) const override {
    const PJ_COORD out = proj_trans(map_, PJ_FWD, proj_coord(lon, lat, 0.0, 0.0));
    return {out.v[0], out.v[1]};
  }
  std::array<double, 2> mapToGeodetic(double e, double n) const override {
    const PJ_COORD g = proj_trans(map_, PJ_INV, proj_coord(e, n, 0.0, 0.0));
    return {g.v[0], g.v[1]};
  }

 private:
  PJ* create(const std::string& definition) const {
    PJ* p = proj_create(context_, definition.c_str());
    if (p == nullptr) {
      throw std::runtime_error("PROJ cannot build \"" + definition + "\": " +
                               proj_context_errno_string(context_, proj_context_errno(context_)));
    }
    return p;
  }

  double bearing_rad_;
  PJ_CONTEXT* context_ = nullptr;
  PJ* topocentric_ = nullptr;  // ENU (m) → longitude, latitude (degrees), height (m)
  PJ* map_ = nullptr;          // longitude, latitude (degrees) → easting, northing (m)
};

}  // namespace

std::unique_ptr<SiteConversions> projConversions(const SiteSpec& site) {
  return std::make_unique<ProjSite>(site);
}

}  // namespace glint
