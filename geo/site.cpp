#include "geo/site.h"

#include <proj.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace glint {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

std::string number(double x) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", x);
  return text;
}

// The UTM zone of a longitude, 1..60 (the regular zones: Norway's and Svalbard's exceptions
// only change which zone is customary there, not whether a zone is valid).
int utmZone(double longitude_deg) {
  const double lon = std::fmod(std::fmod(longitude_deg + 180.0, 360.0) + 360.0, 360.0);
  const int zone = static_cast<int>(std::floor(lon / 6.0)) + 1;
  return zone > 60 ? 60 : zone;
}

}  // namespace

// One context per frame, so that frames on different threads never share one.
struct SiteFrame::Proj {
  PJ_CONTEXT* context = nullptr;
  PJ* topocentric = nullptr;  // ENU (m) → longitude, latitude (degrees), height (m)
  PJ* map = nullptr;          // longitude, latitude (degrees) → easting, northing (m)

  ~Proj() {
    if (map != nullptr) proj_destroy(map);
    if (topocentric != nullptr) proj_destroy(topocentric);
    if (context != nullptr) proj_context_destroy(context);
  }

  PJ* create(const std::string& definition) const {
    PJ* p = proj_create(context, definition.c_str());
    if (p == nullptr) {
      throw std::runtime_error("PROJ cannot build \"" + definition + "\": " +
                               proj_context_errno_string(context, proj_context_errno(context)));
    }
    return p;
  }
};

SiteFrame::SiteFrame(const SiteSpec& spec) : spec_(spec), proj_(std::make_unique<Proj>()) {
  proj_->context = proj_context_create();
  if (proj_->context == nullptr) throw std::runtime_error("PROJ cannot create a context");
  // No network grids: the conversions are ellipsoidal and need none.
  proj_context_set_enable_network(proj_->context, 0);
  const std::string origin =
      " +lat_0=" + number(spec.latitude_deg) + " +lon_0=" + number(spec.longitude_deg);
  proj_->topocentric = proj_->create(
      "+proj=pipeline +step +inv +proj=topocentric" + origin + " +h_0=" + number(spec.height_m) +
      " +ellps=WGS84 +step +inv +proj=cart +ellps=WGS84 +step +proj=unitconvert +xy_in=rad "
      "+xy_out=deg");
  if (spec.projection == MapProjection::Utm) {
    const int zone = utmZone(spec.longitude_deg);
    const bool south = spec.latitude_deg < 0.0;
    map_proj_ = "+proj=utm +zone=" + std::to_string(zone) + (south ? " +south" : "") +
                " +datum=WGS84 +units=m +no_defs";
    map_epsg_ = (south ? 32700 : 32600) + zone;
    map_name_ = "WGS 84 / UTM zone " + std::to_string(zone) + (south ? "S" : "N");
  } else {
    map_proj_ = "+proj=tmerc" + origin + " +k=1 +x_0=0 +y_0=0 +datum=WGS84 +units=m +no_defs";
    map_name_ = "transverse Mercator centred on the site (WGS 84)";
  }
  proj_->map =
      proj_->create("+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad +step " +
                    map_proj_.substr(0, map_proj_.find(" +no_defs")));
}

SiteFrame::~SiteFrame() = default;

Geodetic SiteFrame::toGeodetic(const Vec3& p) const {
  // The local axes in east, north: +x at the bearing, +y a quarter turn anticlockwise.
  const double b = spec_.bearing_deg * kDegree;
  const double east = p.x * std::sin(b) - p.y * std::cos(b);
  const double north = p.x * std::cos(b) + p.y * std::sin(b);
  const PJ_COORD out = proj_trans(proj_->topocentric, PJ_FWD, proj_coord(east, north, p.z, 0.0));
  return {out.v[1], out.v[0], out.v[2]};
}

Vec3 SiteFrame::fromGeodetic(const Geodetic& g) const {
  const PJ_COORD enu = proj_trans(proj_->topocentric, PJ_INV,
                                  proj_coord(g.longitude_deg, g.latitude_deg, g.height_m, 0.0));
  const double b = spec_.bearing_deg * kDegree;
  const double east = enu.v[0], north = enu.v[1];
  return {east * std::sin(b) + north * std::cos(b), -east * std::cos(b) + north * std::sin(b),
          enu.v[2]};
}

MapPoint SiteFrame::toMap(const Vec3& local_m) const {
  const Geodetic g = toGeodetic(local_m);
  const PJ_COORD out =
      proj_trans(proj_->map, PJ_FWD, proj_coord(g.longitude_deg, g.latitude_deg, 0.0, 0.0));
  return {out.v[0], out.v[1]};
}

Vec3 SiteFrame::fromMap(const MapPoint& p, double height_m) const {
  const PJ_COORD g =
      proj_trans(proj_->map, PJ_INV, proj_coord(p.easting_m, p.northing_m, 0.0, 0.0));
  return fromGeodetic({g.v[1], g.v[0], height_m});
}

}  // namespace glint
