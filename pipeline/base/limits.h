#pragma once
/// @file
/// @brief The range of every physical input, chosen so that double arithmetic carries the
/// whole chain from beam to summed irradiance without overflow (docs/reliability.md, "Overflow").
///
/// The largest numbers the chain forms are, with these limits:
/// - beam irradiance E_beam ≤ P / (π r²) ≤ 1e15 / (π · 1e-12) ≈ 3.2e26 W/m²;
/// - a facet's area ≤ that of a 1e5 m object, ≈ 1.3e11 m²;
/// - the lobe's peak Ξ ≤ 1 / (2π σ²) ≈ 1.6e11 sr⁻¹ (σ ≥ 1e-6; its (1 + tan²)² factor is
///   bounded where Ξ does not underflow);
/// - one kernel evaluation E_beam · A · ρ Ξ / (4 d²) at d ≥ 1 µm: ≈ 1.7e60 W/m², and the sum
///   of an observer's 4e6 evaluations ≈ 7e66, squared for an RMS ≈ 5e133;
/// - positions within 1e7 m (about the Earth's diameter) keep distances ≤ 3.5e7 m and
///   d² ≤ 1.2e15 m², where a double still resolves 2e-9 m.
/// Each is far below the double's 1.8e308, so only an observer closer than ~1e-120 m to the
/// surface could overflow: its result is checked and refused, never written.
///
/// The limits are wider than any laser-safety scene: the largest peak powers of pulsed lasers
/// are near 1e15 W (continuous lasers stop near 1e6 W), beam radii below a micrometre and
/// surfaces smoother than σ = 1e-6 are not optics the model describes.

#include <cstddef>

namespace glint::limits {

inline constexpr double kMaxPowerW = 1e15;      ///< laser.power_w ≤ this
inline constexpr double kMinLengthM = 1e-6;     ///< beam radius, object sizes, voxel, pixel ≥
inline constexpr double kMaxLengthM = 1e5;      ///< beam radius, object sizes ≤
inline constexpr double kMaxCoordinateM = 1e7;  ///< |every coordinate| ≤
inline constexpr double kMinSigma = 1e-6;       ///< material sigma ≥
/// A material's specular lobes ≤ this: each is integrated as a term of its own.
inline constexpr std::size_t kMaxLobes = 8;

}  // namespace glint::limits
