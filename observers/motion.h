#pragma once
/// @file
/// @brief An engagement's motion over time: the target's poses, the laser's pointing and the
/// observers' platform as functions of time, and bounds of how far each moves over an interval,
/// seen from the target (docs/engagement.md).
///
/// The whole target moves as one rigid body about its pivot. Everything is computed in the
/// target's own frame, the scene's pose (offset 0, angles 0): there the target stands still and
/// the laser and the observers move, so one target serves every instant (FacetIntegrator::
/// withBeam()).

#include <glm/gtc/quaternion.hpp>
#include <vector>

#include "facets/beam.h"
#include "facets/vec3.h"

namespace glint {

/// @brief The rotation R = Rz(yaw) Ry(pitch) Rx(roll), angles in degrees (the convention of
/// studies, engagements and a mesh's `yaw_pitch_roll_deg`).
glm::dquat yawPitchRoll(double yaw_deg, double pitch_deg, double roll_deg);

/// @brief The target's pose at one time: turned about the pivot by yawPitchRoll() of
/// `angles_deg` (yaw, pitch, roll), then moved by `offset_m`.
struct PoseKey {
  double time_s = 0.0;
  Vec3 offset_m{0.0};
  Vec3 angles_deg{0.0};  ///< yaw, pitch, roll
};

/// @brief How the target's pose runs between its keys.
enum class PoseInterpolation {
  Linear,  ///< offset and angles linear in time
  Spline,  ///< Catmull–Rom (tangents by central differences in time), C¹ through the keys
};

/// @brief The laser's direction at one time (world frame, unit).
struct DirectionKey {
  double time_s = 0.0;
  Vec3 direction{1.0, 0.0, 0.0};
};

/// @brief What the laser points at.
enum class LaserPointing {
  Fixed,  ///< the scene's direction throughout
  Track,  ///< follows the point of the target its scene direction aims at (nearest the pivot)
  Keyed,  ///< DirectionKey's, turned at a constant rate between them (slerp)
};

/// @brief An engagement: the time span and every motion in it (scene key `engagement`).
struct MotionSpec {
  double start_s = 0.0;
  double end_s = 0.0;
  Vec3 pivot_m{0.0};  ///< what the target turns about (default: the mean of object centres)
  std::vector<PoseKey> poses;  ///< time order; before the first and after the last, held
  PoseInterpolation interpolation = PoseInterpolation::Linear;
  LaserPointing pointing = LaserPointing::Fixed;
  std::vector<DirectionKey> laser_keys;  ///< Keyed only; time order
  Vec3 observer_velocity_m_s{0.0};       ///< every observer moves at it, from its place at t = 0
};

/// @brief An upper bound of each motion's rate over a time interval.
struct MotionRates {
  double target_speed_m_s = 0.0;   ///< of the pivot
  double target_turn_rad_s = 0.0;  ///< angular speed of the target
  double laser_turn_rad_s = 0.0;   ///< angular speed of the laser's direction (world)
  double observer_speed_m_s = 0.0;
};

/// @brief An engagement's motion, ready to be asked where things are.
class Motion {
 public:
  /// @brief @p laser is the scene's beam (its direction the one at the scene's pose).
  /// @pre @p spec validated: keys in time order, start < end, unit directions.
  Motion(MotionSpec spec, const Beam& laser);

  [[nodiscard]] const MotionSpec& spec() const { return spec_; }
  [[nodiscard]] double durationS() const { return spec_.end_s - spec_.start_s; }

  /// @brief The target's rotation and the pivot's offset at @p t_s.
  [[nodiscard]] glm::dquat rotationAt(double t_s) const;
  [[nodiscard]] Vec3 offsetAt(double t_s) const;

  /// @brief Where the world point @p world_m lies in the target's frame at @p t_s.
  [[nodiscard]] Vec3 toTargetFrame(double t_s, const Vec3& world_m) const;

  /// @brief The laser's beam at @p t_s, seen from the target's frame.
  [[nodiscard]] Beam beamAt(double t_s) const;

  /// @brief The laser's direction at @p t_s in the world.
  [[nodiscard]] Vec3 laserDirectionAt(double t_s) const;

  /// @brief Where an observer that starts at @p start_m (its place at t = 0) is at @p t_s.
  [[nodiscard]] Vec3 observerAt(double t_s, const Vec3& start_m) const {
    return start_m + spec_.observer_velocity_m_s * t_s;
  }

  /// @brief Bounds of the rates over [@p t0_s, @p t1_s].
  [[nodiscard]] MotionRates ratesOver(double t0_s, double t1_s) const;

  /// @brief The beam of the interval [@p t0_s, @p t1_s]: the one at its middle, swept
  /// (Beam::sweep_offset_m, sweep_angle_rad) so that its bounds hold for the beam at every
  /// instant of it, seen from the target's frame.
  [[nodiscard]] Beam sweptBeam(double t0_s, double t1_s) const;

  /// @brief How far, at most, the observer that starts at @p start_m moves in the target's
  /// frame between the middle of [@p t0_s, @p t1_s] and any instant of it.
  [[nodiscard]] double observerSweepM(double t0_s, double t1_s, const Vec3& start_m) const;

 private:
  // How far a world point moving at @p speed_m_s, @p lever_m from the pivot at the middle,
  // moves in the target's frame within @p half_s of the middle, under @p rates.
  static double frameSweepM(const MotionRates& rates, double speed_m_s, double lever_m,
                            double half_s);

  MotionSpec spec_;
  Beam laser_;
  Vec3 aim_m{0.0};  // Track: the target point the laser follows, in the target's frame
};

}  // namespace glint
