#include "facets/reflection.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace glint {
namespace {

// The largest angle by which a unit vector can turn when moved by a chord of length e from a
// vector of length `len` (for the sum ωi + ωo, whose parts each turn by known angles).
double turnAngle(double e, double len) { return e < len ? std::asin(e / len) : kPi; }

// The two culls of a patch whose normals lie within cone_rad of its axis, each from the axis's
// angle to a direction, shared by contributionBound() (which has the angles at hand) and
// lightVerdict() / mayFaceObserver(). Both are written so that a NaN answers "not culled":
// culling must be proven.
//
// No normal has cos θi > 0 when ωi itself turns by at most spread_rad over the patch.
bool facesAwayFromLaser(double angle_to_wi_rad, double cone_rad, double spread_rad) {
  return angle_to_wi_rad - cone_rad - spread_rad >= 0.5 * kPi;
}
// No point of the patch's ball faces any observer of theirs: max over both balls and the cone
// of n·(x_O − x) ≤ d cos(max(0, θ − cone)) + reach ≤ 0, d the centres' distance.
bool hiddenFromObserver(double angle_to_v_rad, double cone_rad, double d_m, double reach_m) {
  const double excess = angle_to_v_rad - cone_rad;
  return excess >= 0.5 * kPi && d_m * std::cos(excess) + reach_m <= 0.0;
}

// The half vector ωi + ωo at the patch's centre and how far its direction can turn over the
// patch and the observers' ball: ωo turns by at most eps_o = asin(reach/d), ωi by the beam's
// spread eps_i, and their sum moves by at most the two chords.
struct HalfVector {
  Vec3 h;
  double turn_rad;
};
HalfVector halfVector(const Vec3& wi, const Vec3& v, double d, double eps_i, double eps_o) {
  const Vec3 h = wi + v / d;
  const double chord = 2.0 * std::sin(0.5 * eps_o) + 2.0 * std::sin(0.5 * eps_i);
  return {h, turnAngle(chord, glm::length(h))};
}

// A lower bound of the angle between `direction` and every normal of the patch that is in
// both its band and its cone, 0 without a band. Latitude λ is taken about the band's axis and
// longitude about it too: the band holds latitudes [λ_lo, λ_hi], and the cone (radius c about
// g.normal, at latitude λ0) longitudes within L of g.normal's, sin L = sin c / cos λ0, when it
// leaves out the poles. The nearest point of that latitude–longitude box to the direction
// (latitude φ, longitude δ from g.normal's) lies on its nearer meridian, δ_min = max(0, δ − L)
// away, at the latitude of the box nearest to the great circle's closest approach; the
// haversine gives the distance without the cancellation of an arccosine near 0. For a
// cylinder's piece, whose band has no width, this is exactly the distance to its arc of
// normals.
double bandDistanceRad(const PatchGeometry& g, const Vec3& direction) {
  const NormalBand& band = g.band;
  if (band.axis == Vec3(0.0)) return 0.0;
  const double len = glm::length(direction);
  if (!(len > 0.0)) return 0.0;
  const Vec3& e = band.axis;
  const double sin_phi = std::clamp(glm::dot(direction, e) / len, -1.0, 1.0);
  const double phi = std::asin(sin_phi);
  const double lat_lo = std::asin(band.sin_lo), lat_hi = std::asin(band.sin_hi);
  double delta_min = 0.0;
  const double lat0 = std::asin(std::clamp(glm::dot(g.normal, e), -1.0, 1.0));
  if (g.cone_rad + std::abs(lat0) < 0.5 * kPi) {
    const double half_width = std::asin(std::min(1.0, std::sin(g.cone_rad) / std::cos(lat0)));
    const double delta =
        angleBetween(direction - glm::dot(direction, e) * e, g.normal - glm::dot(g.normal, e) * e);
    delta_min = std::max(0.0, delta - half_width);
  }
  // hav θ = hav(φ − λ) + cos φ cos λ hav δ, least over λ in the box at its ends or at the
  // latitude λ* where the meridian passes closest; any extra candidate only lowers it.
  const double cos_phi = std::cos(phi);
  const double lat_star =
      std::clamp(std::atan2(sin_phi, cos_phi * std::cos(delta_min)), lat_lo, lat_hi);
  const double hav_delta = std::pow(std::sin(0.5 * delta_min), 2);
  double hav = 1.0;
  for (const double lat : {lat_lo, lat_hi, lat_star}) {
    const double at =
        std::pow(std::sin(0.5 * (phi - lat)), 2) + cos_phi * std::cos(lat) * hav_delta;
    if (!(at >= 0.0)) return 0.0;  // a NaN proves nothing
    hav = std::min(hav, at);
  }
  return 2.0 * std::asin(std::sqrt(hav));
}

// The smallest angle between a normal of the patch and a direction within turn_rad of
// `direction` (at angle_to_normal from g.normal): the larger of what the cone and the band allow.
double minNormalAngle(const PatchGeometry& g, const Vec3& direction, double angle_to_normal,
                      double turn_rad) {
  return std::max(
      {0.0, angle_to_normal - (g.cone_rad + turn_rad), bandDistanceRad(g, direction) - turn_rad});
}

}  // namespace

double minHalfVectorAngle(const PatchGeometry& g, const Vec3& observer_m, const Beam& beam,
                          double observer_radius_m) {
  const Vec3 v = observer_m - g.centre_m;
  const double d = glm::length(v);
  const double reach = g.radius_m + observer_radius_m;
  if (!(d > reach)) return 0.0;
  const HalfVector hv = halfVector(beam.at(g.centre_m).toward_laser, v, d,
                                   beam.directionSpreadInBall(g.radius_m), std::asin(reach / d));
  return minNormalAngle(g, hv.h, angleBetween(g.normal, hv.h), hv.turn_rad);
}

ContributionBound contributionBound(const PatchGeometry& g, const Vec3& observer_m,
                                    const Beam& beam, const Material& material,
                                    const ResolutionLimits& limits, double observer_radius_m) {
  const Vec3 v = observer_m - g.centre_m;
  const double d = glm::length(v);
  // Every patch point lies within g.radius_m of its centre and every observer within
  // observer_radius_m of observer_m: the two balls merge into one for the distances and angles.
  const double reach = g.radius_m + observer_radius_m;
  if (!(d > reach)) {
    const double inf = std::numeric_limits<double>::infinity();
    return {inf, inf, inf};
  }
  const double e_max = beam.maxIrradianceInBall(g.centre_m, g.radius_m);
  if (e_max == 0.0 || g.area_bound_m2 == 0.0) return {0.0, 0.0, 0.0};
  const double eps_i = beam.directionSpreadInBall(g.radius_m);
  const Vec3 wi = beam.at(g.centre_m).toward_laser;
  const double angle_i = angleBetween(g.normal, wi), angle_o = angleBetween(g.normal, v);
  // The kernel is cut at the terminator and the horizon: a patch none of whose normals can
  // see both the laser and the observer sends nothing. Without this, pieces along a line
  // where the lobe peaks at grazing incidence (the silhouette seen in forward scatter) keep
  // their whole lobe as their bound however thin they become, and are split to the depth limit.
  if (facesAwayFromLaser(angle_i, g.cone_rad, eps_i) ||
      hiddenFromObserver(angle_o, g.cone_rad, d, reach)) {
    return {0.0, 0.0, 0.0};
  }

  const double eps_o = std::asin(reach / d);
  const auto [h, h_turn] = halfVector(wi, v, d, eps_i, eps_o);
  const double spread = g.cone_rad + h_turn;

  const double theta_n = angleBetween(g.normal, h);
  auto tan2 = [](double theta) {
    return theta < 0.5 * kPi ? std::tan(theta) * std::tan(theta)
                             : std::numeric_limits<double>::infinity();
  };
  const double theta_n_min = minNormalAngle(g, h, theta_n, h_turn);
  const double tan2_min = tan2(theta_n_min);
  const double d_min = d - reach;
  const double scale = e_max * g.area_bound_m2 / (d_min * d_min);
  // Each directional term at its largest beyond θN_min; the sample resolves them only where it
  // resolves every one (the narrowest decides).
  const auto for_each_lobe = [&material](const auto& fn) {
    if (material.specular_reflectance > 0.0) fn(material.specular_reflectance, material.lobe);
    for (const SpecularLobe& l : material.more_lobes) {
      if (l.reflectance > 0.0) fn(l.reflectance, l.shape);
    }
  };
  double specular = 0.0;
  double narrowest_rad = std::numeric_limits<double>::infinity();
  for_each_lobe([&](double reflectance, const Beckmann& shape) {
    specular += scale * 0.25 * reflectance * shape.maxXiBeyond(tan2_min);
    narrowest_rad = std::min(narrowest_rad, shape.widthRad());
  });
  // The least angles of incidence and reflection over the piece: ABg and a table vanish at
  // grazing, and their bounds must too, or a flat facet seen edge-on (every piece straddling
  // the horizon) keeps its whole bound however finely it is split.
  const double theta_i_min = std::max(0.0, angle_i - g.cone_rad - eps_i);
  const double theta_o_min = std::max(0.0, angle_o - g.cone_rad - eps_o);
  if (material.abg && material.abg->a_per_sr > 0.0) {
    specular +=
        scale * material.abg->maxBeyond(tan2_min, std::cos(theta_i_min), std::cos(theta_o_min));
    narrowest_rad = std::min(narrowest_rad, material.abg->widthBeyondRad(theta_n_min));
  }
  if (material.table) {
    // The largest angles of incidence and reflection over the piece: away from grazing, the
    // table's grazing cells do not count.
    specular += scale *
                material.table->maxBeyond(tan2_min, angle_i + g.cone_rad + eps_i,
                                          angle_o + g.cone_rad + eps_o) *
                material.table->grazingFactor(theta_i_min, theta_o_min);
    narrowest_rad = std::min(narrowest_rad, material.table->widthRad());
  }
  // A reflectance of 0 contributes 0 even where the scale overflowed (∞ · 0 would be NaN).
  const double diffuse =
      material.diffuse_reflectance > 0.0 ? scale * material.diffuse_reflectance / kPi : 0.0;

  // Both terms are smooth in a patch that is small against the distance, free of beam edges
  // and narrow against a Gaussian beam's width; the specular term also varies on the scale of the
  // lobe's width. Where cos θi or cos θr may change sign the kernel clips the facet, and there the
  // lobe must be nearly flat too.
  const bool smooth = reach <= limits.near_field * d &&
                      (limits.clips_beam_edges || !beam.edgeMayCrossBall(g.centre_m, g.radius_m)) &&
                      !beam.profileMayBendInBall(g.centre_m, g.radius_m);
  const bool may_be_clipped = std::abs(angle_i - 0.5 * kPi) <= g.cone_rad + eps_i ||
                              std::abs(angle_o - 0.5 * kPi) <= g.cone_rad + eps_o;
  const auto flat_where_clipped = [&] {
    // ABg and a table need no flatness: f_r cos θi cos θr is bounded and vanishes at the cut,
    // as the Lambertian term does, so the clipped kernel stays continuous for the rule (a lobe's
    // ρ Ξ / 4 does not vanish there: the kernel jumps at the cut).
    bool flat = true;
    const double tan2_far = tan2(theta_n + spread);
    for_each_lobe([&](double, const Beckmann& shape) {
      flat = flat && shape.logRatio(tan2_min, tan2_far) <= limits.clipped_log_variation;
    });
    return flat;
  };
  const bool specular_smooth =
      smooth && spread <= limits.lobe * narrowest_rad && (!may_be_clipped || flat_where_clipped());
  ContributionBound b;
  b.upper_w_m2 = specular + diffuse;
  b.unresolved_w_m2 = (specular_smooth ? 0.0 : specular) + (smooth ? 0.0 : diffuse);
  b.specular_w_m2 = specular;
  // A bound is only useful if it fails safe: a NaN (from a NaN in the geometry, or an
  // overflowing beam power meeting a zero) would compare false against every threshold and
  // could be read as "nothing here". It becomes +∞, which every caller refines.
  if (!(b.upper_w_m2 >= 0.0) || !(b.unresolved_w_m2 >= 0.0) || !(b.specular_w_m2 >= 0.0)) {
    const double inf = std::numeric_limits<double>::infinity();
    return {inf, inf, inf};
  }
  return b;
}

ClippedTriangle clipTriangle(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  // Sutherland–Hodgman in the (λ1, λ2) plane of the unit triangle, one half-plane at a time.
  struct P {
    double s, t, fa, fb;  // position and the two functions there
  };
  std::array<P, 8> poly{{{0, 0, a[0], b[0]}, {1, 0, a[1], b[1]}, {0, 1, a[2], b[2]}}};
  int n = 3;
  auto clip = [&](bool first) {
    std::array<P, 8> out;
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const P& p = poly[i];
      const P& q = poly[(i + 1) % n];
      const double fp = first ? p.fa : p.fb, fq = first ? q.fa : q.fb;
      if (fp > 0.0) out[m++] = p;
      if ((fp > 0.0) != (fq > 0.0)) {
        const double t = fp / (fp - fq);
        out[m++] = {p.s + t * (q.s - p.s), p.t + t * (q.t - p.t), p.fa + t * (q.fa - p.fa),
                    p.fb + t * (q.fb - p.fb)};
      }
    }
    poly = out;
    n = m;
  };
  clip(true);
  clip(false);
  if (n < 3) return {0.0, Vec3(1.0 / 3.0)};
  // Shoelace area and centroid; the unit triangle has area ½.
  double area2 = 0.0, cs = 0.0, ct = 0.0;
  for (int i = 0; i < n; ++i) {
    const P& p = poly[i];
    const P& q = poly[(i + 1) % n];
    const double cross = p.s * q.t - q.s * p.t;
    area2 += cross;
    cs += (p.s + q.s) * cross;
    ct += (p.t + q.t) * cross;
  }
  if (!(area2 > 0.0)) return {0.0, Vec3(1.0 / 3.0)};
  const double s = cs / (3.0 * area2), t = ct / (3.0 * area2);
  return {std::min(area2, 1.0), Vec3(1.0 - s - t, s, t)};
}

bool mayFaceObserver(const PatchGeometry& g, const Vec3& observer_m, double observer_radius_m) {
  const Vec3 v = observer_m - g.centre_m;
  const double d = glm::length(v);
  const double reach = g.radius_m + observer_radius_m;
  if (!(d > reach)) return true;
  return !hiddenFromObserver(angleBetween(g.normal, v), g.cone_rad, d, reach);
}

LightVerdict lightVerdict(const PatchGeometry& g, const Beam& beam) {
  if (beam.maxIrradianceInBall(g.centre_m, g.radius_m) == 0.0) return LightVerdict::OutsideBeam;
  const double angle_i = angleBetween(g.normal, beam.at(g.centre_m).toward_laser);
  return facesAwayFromLaser(angle_i, g.cone_rad, beam.directionSpreadInBall(g.radius_m))
             ? LightVerdict::FacesAway
             : LightVerdict::MayBeLit;
}

}  // namespace glint
