#include "observers/motion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace glint {
namespace {

constexpr double kDegree = kPi / 180.0;

// The segment [keys[k], keys[k+1]] that holds t (the last one at and after the last key).
template <class Key>
std::size_t segmentOf(const std::vector<Key>& keys, double t) {
  const auto after = std::upper_bound(keys.begin(), keys.end(), t,
                                      [](double v, const Key& k) { return v < k.time_s; });
  const auto k = static_cast<std::size_t>(after - keys.begin());
  return k == 0 ? 0 : std::min(k - 1, keys.size() - 2);
}

// The Catmull–Rom tangent (per second) of a keyed value at key i: central differences in
// time, one-sided at the ends.
template <class Get>
Vec3 tangent(const std::vector<PoseKey>& keys, std::size_t i, Get get) {
  const std::size_t lo = i == 0 ? 0 : i - 1;
  const std::size_t hi = std::min(i + 1, keys.size() - 1);
  return (get(keys[hi]) - get(keys[lo])) / (keys[hi].time_s - keys[lo].time_s);
}

// A keyed value at t: held before the first key and after the last.
template <class Get>
Vec3 interpolate(const std::vector<PoseKey>& keys, PoseInterpolation how, double t, Get get) {
  if (keys.size() == 1 || t <= keys.front().time_s) return get(keys.front());
  if (t >= keys.back().time_s) return get(keys.back());
  const std::size_t k = segmentOf(keys, t);
  const double dt = keys[k + 1].time_s - keys[k].time_s;
  const double s = (t - keys[k].time_s) / dt;
  const Vec3 p0 = get(keys[k]), p1 = get(keys[k + 1]);
  if (how == PoseInterpolation::Linear) return p0 + s * (p1 - p0);
  const double s2 = s * s, s3 = s2 * s;
  const Vec3 m0 = tangent(keys, k, get), m1 = tangent(keys, k + 1, get);
  return (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * dt * m0 + (-2 * s3 + 3 * s2) * p1 +
         (s3 - s2) * dt * m1;
}

// A bound of |d value/dt| on segment k, per component: linear, the chord's slope; a spline, from
// dp/dt = (6s² − 6s)(p0 − p1)/dt + (3s² − 4s + 1) m0 + (3s² − 2s) m1, whose three weights are
// at most 1.5, 1 and 1 in magnitude over s ∈ [0, 1].
template <class Get>
Vec3 rateBound(const std::vector<PoseKey>& keys, PoseInterpolation how, std::size_t k, Get get) {
  const double dt = keys[k + 1].time_s - keys[k].time_s;
  const Vec3 chord = glm::abs(get(keys[k + 1]) - get(keys[k])) / dt;
  if (how == PoseInterpolation::Linear) return chord;
  return 1.5 * chord + glm::abs(tangent(keys, k, get)) + glm::abs(tangent(keys, k + 1, get));
}

// Calls fn(k) for every segment of @p keys that overlaps [t0, t1] (none before the first key
// or after the last, where everything is held).
template <class Key, class Fn>
void forEachSegment(const std::vector<Key>& keys, double t0, double t1, Fn fn) {
  if (keys.size() < 2 || t1 <= keys.front().time_s || t0 >= keys.back().time_s) return;
  const std::size_t first = segmentOf(keys, std::max(t0, keys.front().time_s));
  for (std::size_t k = first; k + 1 < keys.size() && keys[k].time_s < t1; ++k) fn(k);
}

const Vec3& offsetOf(const PoseKey& k) { return k.offset_m; }
const Vec3& anglesOf(const PoseKey& k) { return k.angles_deg; }

}  // namespace

glm::dquat yawPitchRoll(double yaw_deg, double pitch_deg, double roll_deg) {
  return glm::angleAxis(yaw_deg * kDegree, Vec3(0.0, 0.0, 1.0)) *
         glm::angleAxis(pitch_deg * kDegree, Vec3(0.0, 1.0, 0.0)) *
         glm::angleAxis(roll_deg * kDegree, Vec3(1.0, 0.0, 0.0));
}

Motion::Motion(MotionSpec spec, const Beam& laser) : spec_(std::move(spec)), laser_(laser) {
  if (spec_.poses.empty()) spec_.poses.push_back(PoseKey{});
  // The point of the target on the scene's beam axis nearest the pivot: what a tracking laser
  // keeps its axis on.
  const double along = std::max(0.0, glm::dot(spec_.pivot_m - laser_.origin_m, laser_.direction));
  aim_m = laser_.origin_m + along * laser_.direction;
}

Vec3 Motion::offsetAt(double t_s) const {
  return interpolate(spec_.poses, spec_.interpolation, t_s, offsetOf);
}

glm::dquat Motion::rotationAt(double t_s) const {
  const Vec3 a = interpolate(spec_.poses, spec_.interpolation, t_s, anglesOf);
  return yawPitchRoll(a[0], a[1], a[2]);
}

Vec3 Motion::toTargetFrame(double t_s, const Vec3& world_m) const {
  return spec_.pivot_m +
         glm::conjugate(rotationAt(t_s)) * (world_m - spec_.pivot_m - offsetAt(t_s));
}

Vec3 Motion::laserDirectionAt(double t_s) const {
  switch (spec_.pointing) {
    case LaserPointing::Fixed:
      break;
    case LaserPointing::Track: {
      const Vec3 aim_world =
          spec_.pivot_m + offsetAt(t_s) + rotationAt(t_s) * (aim_m - spec_.pivot_m);
      if (auto d = tryNormalize(aim_world - laser_.origin_m)) return *d;
      break;
    }
    case LaserPointing::Keyed: {
      const std::vector<DirectionKey>& keys = spec_.laser_keys;
      if (keys.size() == 1 || t_s <= keys.front().time_s) return keys.front().direction;
      if (t_s >= keys.back().time_s) return keys.back().direction;
      const std::size_t k = segmentOf(keys, t_s);
      const double s = (t_s - keys[k].time_s) / (keys[k + 1].time_s - keys[k].time_s);
      // Slerp: at a constant rate along the great circle between the two keys.
      const Vec3 a = keys[k].direction, b = keys[k + 1].direction;
      const double angle = angleBetween(a, b);
      if (!(angle > 1e-12)) return a;
      const double sine = std::sin(angle);
      return glm::normalize((std::sin((1.0 - s) * angle) * a + std::sin(s * angle) * b) / sine);
    }
  }
  return laser_.direction;
}

Beam Motion::beamAt(double t_s) const {
  Beam b = laser_;
  const glm::dquat to_target = glm::conjugate(rotationAt(t_s));
  b.origin_m = toTargetFrame(t_s, laser_.origin_m);
  b.direction = glm::normalize(to_target * laserDirectionAt(t_s));
  return b;
}

MotionRates Motion::ratesOver(double t0_s, double t1_s) const {
  MotionRates r;
  const std::vector<PoseKey>& keys = spec_.poses;
  forEachSegment(keys, t0_s, t1_s, [&](std::size_t k) {
    const Vec3 v = rateBound(keys, spec_.interpolation, k, offsetOf);
    const Vec3 w = rateBound(keys, spec_.interpolation, k, anglesOf);
    // A component bound per axis bounds the vector's length by its own length; each Euler
    // angle's rate turns the body about one unit axis, so the angular speed is at most their sum.
    r.target_speed_m_s = std::max(r.target_speed_m_s, glm::length(v));
    r.target_turn_rad_s = std::max(r.target_turn_rad_s, (w.x + w.y + w.z) * kDegree);
  });
  r.observer_speed_m_s = glm::length(spec_.observer_velocity_m_s);
  switch (spec_.pointing) {
    case LaserPointing::Fixed:
      break;
    case LaserPointing::Track: {
      // The aim point moves at most at the pivot's speed plus the turn's about the pivot; seen
      // from the laser it turns at that speed over its nearest distance.
      const double half = 0.5 * (t1_s - t0_s), mid = t0_s + half;
      const double aim_speed =
          r.target_speed_m_s + r.target_turn_rad_s * glm::length(aim_m - spec_.pivot_m);
      const Vec3 aim_world =
          spec_.pivot_m + offsetAt(mid) + rotationAt(mid) * (aim_m - spec_.pivot_m);
      const double nearest = glm::length(aim_world - laser_.origin_m) - half * aim_speed;
      r.laser_turn_rad_s =
          nearest > 0.0 ? aim_speed / nearest : std::numeric_limits<double>::infinity();
      break;
    }
    case LaserPointing::Keyed:
      forEachSegment(spec_.laser_keys, t0_s, t1_s, [&](std::size_t k) {
        const DirectionKey &a = spec_.laser_keys[k], &b = spec_.laser_keys[k + 1];
        r.laser_turn_rad_s = std::max(
            r.laser_turn_rad_s, angleBetween(a.direction, b.direction) / (b.time_s - a.time_s));
      });
      break;
  }
  return r;
}

double Motion::frameSweepM(const MotionRates& rates, double speed_m_s, double lever_m,
                           double half_s) {
  // In the target's frame the point is R(t)ᵀ r(t), r its place relative to the moved pivot:
  // R(t)ᵀ (r(t) − r(m)) moves it by at most (its speed + the pivot's) × time, and the turn
  // (R(t) − R(m))ᵀ r(m) by at most the angle × |r(m)|.
  return half_s * (speed_m_s + rates.target_speed_m_s + rates.target_turn_rad_s * lever_m);
}

Beam Motion::sweptBeam(double t0_s, double t1_s) const {
  const double half = 0.5 * (t1_s - t0_s), mid = t0_s + half;
  const MotionRates rates = ratesOver(t0_s, t1_s);
  Beam b = beamAt(mid);
  const double lever = glm::length(laser_.origin_m - spec_.pivot_m - offsetAt(mid));
  b.sweep_offset_m = frameSweepM(rates, 0.0, lever, half);
  // Seen from the target the direction turns with the laser and against the target.
  b.sweep_angle_rad = std::min(kPi, half * (rates.laser_turn_rad_s + rates.target_turn_rad_s));
  return b;
}

double Motion::observerSweepM(double t0_s, double t1_s, const Vec3& start_m) const {
  const double half = 0.5 * (t1_s - t0_s), mid = t0_s + half;
  const MotionRates rates = ratesOver(t0_s, t1_s);
  const double lever = glm::length(observerAt(mid, start_m) - spec_.pivot_m - offsetAt(mid));
  return frameSweepM(rates, rates.observer_speed_m_s, lever, half);
}

}  // namespace glint
