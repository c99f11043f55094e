// The site's frames against references worked without PROJ: the ellipsoid's closed forms on the
// equator, the meridian arc by quadrature for UTM's northing, and round trips.
#include "geo/site.h"

#include <gtest/gtest.h>

#include <cmath>

namespace glint {
namespace {

constexpr double kA = 6378137.0;            // WGS 84 semi-major axis (m)
constexpr double kF = 1.0 / 298.257223563;  // WGS 84 flattening
constexpr double kE2 = kF * (2.0 - kF);     // first eccentricity squared
constexpr double kDeg = 3.14159265358979323846 / 180.0;

// On the equator at longitude 0 the local east is geocentric +Y, north +Z and up +X: a point
// x metres east (bearing 90°) of a site at height 0 is at geocentric (a, x, 0), so its longitude
// is atan(x / a), its latitude 0 and its height hypot(a, x) − a, exactly.
TEST(SiteFrame, OnTheEquatorAPointEastIsWhereTheEllipsoidSaysExactly) {
  const SiteFrame site({0.0, 0.0, 0.0, 90.0, MapProjection::Utm});
  for (double x : {1.0, 1000.0, 20000.0}) {
    const Geodetic g = site.toGeodetic({x, 0.0, 0.0});
    EXPECT_NEAR(g.longitude_deg, std::atan(x / kA) / kDeg, 1e-12) << x << " m east";
    EXPECT_NEAR(g.latitude_deg, 0.0, 1e-12) << x << " m east";
    EXPECT_NEAR(g.height_m, std::hypot(kA, x) - kA, 1e-6) << x << " m east: the ground falls away";
  }
  // +y is a quarter turn anticlockwise from +x: with +x east, +y is north.
  EXPECT_GT(site.toGeodetic({0.0, 1000.0, 0.0}).latitude_deg, 0.0);
  EXPECT_NEAR(site.toGeodetic({0.0, 1000.0, 0.0}).longitude_deg, 0.0, 1e-12);
}

TEST(SiteFrame, LocalToGeodeticAndMapAndBackIsTheSamePoint) {
  const SiteFrame site({51.4779, -0.0015, 45.0, 33.0, MapProjection::Utm});
  for (const Vec3& p : {Vec3(0.0), Vec3(1000.0, -250.0, 3.0), Vec3(-4000.0, 3500.0, -80.0)}) {
    const Vec3 back = site.fromGeodetic(site.toGeodetic(p));
    EXPECT_NEAR(glm::length(back - p), 0.0, 1e-6) << p.x << "," << p.y << "," << p.z;
    const Vec3 via_map = site.fromMap(site.toMap(p), site.toGeodetic(p).height_m);
    EXPECT_NEAR(glm::length(via_map - p), 0.0, 1e-5) << p.x << "," << p.y << "," << p.z;
  }
  const Geodetic origin = site.toGeodetic(Vec3(0.0));
  EXPECT_NEAR(origin.latitude_deg, 51.4779, 1e-12);
  EXPECT_NEAR(origin.longitude_deg, -0.0015, 1e-12);
  EXPECT_NEAR(origin.height_m, 45.0, 1e-6);
  EXPECT_EQ(site.mapEpsg(), 32630) << "Greenwich's west side is UTM zone 30";
  EXPECT_EQ(site.mapName(), "WGS 84 / UTM zone 30N");
}

// The meridian arc from the equator to latitude φ, a (1 − e²) ∫ (1 − e² sin² t)^(-3/2) dt, by
// Simpson's rule on 2000 intervals (error far below a millimetre).
double meridianArcM(double latitude_deg) {
  const double phi = latitude_deg * kDeg;
  const int n = 2000;
  const double h = phi / n;
  double sum = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double s = std::sin(i * h);
    const double f = std::pow(1.0 - kE2 * s * s, -1.5);
    sum += (i == 0 || i == n ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0)) * f;
  }
  return kA * (1.0 - kE2) * sum * h / 3.0;
}

// On a zone's central meridian UTM's easting is 500 000 m and its northing 0.9996 times the
// meridian arc; a local transverse Mercator puts the site at (0, 0) with scale 1.
TEST(SiteFrame, OnTheCentralMeridianUtmIsTheScaledMeridianArc) {
  for (double lat : {0.0, 12.5, 45.0, 70.0}) {
    const SiteFrame site({lat, 9.0, 0.0, 0.0, MapProjection::Utm});  // zone 32's meridian
    const MapPoint p = site.toMap(Vec3(0.0));
    EXPECT_NEAR(p.easting_m, 500000.0, 1e-6) << lat;
    EXPECT_NEAR(p.northing_m, 0.9996 * meridianArcM(lat), 1e-3) << lat;
    EXPECT_EQ(site.mapEpsg(), 32632);
  }
  const SiteFrame south({-33.9, 18.4, 0.0, 0.0, MapProjection::Utm});
  EXPECT_EQ(south.mapEpsg(), 32734) << "Cape Town: zone 34 south";
  EXPECT_GT(south.toMap(Vec3(0.0)).northing_m, 6.0e6) << "the false northing of the south";

  const SiteFrame local({47.0, 8.0, 500.0, 0.0, MapProjection::LocalTransverseMercator});
  EXPECT_EQ(local.mapEpsg(), 0);
  const MapPoint o = local.toMap(Vec3(0.0));
  EXPECT_NEAR(o.easting_m, 0.0, 1e-6);
  EXPECT_NEAR(o.northing_m, 0.0, 1e-6);
  // 1 km north along the tangent plane 500 m above the ellipsoid: the map measures on the
  // ellipsoid, so the distance shrinks by M / (M + h), M the meridian's radius of curvature
  // (0.0785 m here); the arc's own shortening, d³ / 3M², is below 1e-5 m.
  const MapPoint north = local.toMap({1000.0, 0.0, 0.0});
  const double s47 = std::sin(47.0 * kDeg);
  const double m = kA * (1.0 - kE2) / std::pow(1.0 - kE2 * s47 * s47, 1.5);
  EXPECT_NEAR(north.easting_m, 0.0, 1e-6);
  EXPECT_NEAR(north.northing_m, 1000.0 * m / (m + 500.0), 2e-5);
}

}  // namespace
}  // namespace glint
