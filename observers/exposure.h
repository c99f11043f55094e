#pragma once
/// @file
/// @brief Irradiance over an engagement's time span at fixed (or riding) observers, sampled
/// adaptively in time, and the radiant exposure it delivers (docs/engagement.md).
///
/// Each observer's span is cut into intervals, and each interval is split in two until either
/// its bound (FacetIntegrator::boundBall() of the interval's swept beam over the ball the
/// observer sweeps in the target's frame) proves it dark, or its samples follow the irradiance:
/// no glint narrower than the distance the observer moves through the light between samples
/// may pass (BallBound::narrow_w_m2), and splitting it changes neither the exposure nor the
/// peak by more than the tolerance. A glint that crosses an observer between two samples is so
/// found, not skipped.

#include <cstdint>
#include <span>
#include <vector>

#include "facets/integrator.h"
#include "observers/field.h"
#include "observers/motion.h"
#include "observers/point_set.h"

namespace glint {

/// @brief How finely time is sampled (scene key `engagement.time`).
struct ExposureOptions {
  double tolerance = 1e-3;  ///< relative, of each observer's exposure and peak irradiance
  /// Irradiance no observer needs resolved (W/m²): an interval whose bound stays below it is
  /// dark, and changes below it are not followed.
  double floor_w_m2 = 0.0;
  int initial_intervals = 16;  ///< equal intervals the span starts from
  int max_depth = 24;          ///< halvings of an initial interval at most
};

/// @brief One observer's irradiance over the span and what it adds up to.
struct ExposureHistory {
  /// The samples, in time order: a piecewise-linear irradiance through them is the estimate
  /// every figure below is taken from.
  std::vector<double> time_s;
  std::vector<double> irradiance_w_m2;
  double exposure_j_m2 = 0.0;  ///< ∫E dt over the span (trapezoids through the samples)
  /// Σ over intervals of the change one more halving made (a third of it: the trapezoid rule's
  /// Richardson estimate), plus the bound of the intervals proven dark.
  double error_j_m2 = 0.0;
  double peak_w_m2 = 0.0;
  double peak_time_s = 0.0;
  std::int64_t evaluations = 0;  ///< kernel evaluations of every sample
  /// Every interval met the tolerance before max_depth, and every sample's integration
  /// converged.
  bool converged = true;
};

/// @brief The irradiance over @p motion's span at each of @p observers_m (their places at
/// t = 0; they ride the motion's observer platform), in input order. @p reference is the
/// integrator of the target at the scene's pose (its beam is not used: each instant's comes
/// from @p motion). Results do not depend on the number of threads.
/// @param counter optional; items are samples, scheduled as they are learnt.
/// @param exchange optional: the processes of an MPI job, each of which samples every size-th
/// observer from its rank on and receives the others' histories (the same as one process).
/// @throw WorkStopped when the counter's stop flag is raised (between rounds) on any process.
std::vector<ExposureHistory> integrateExposures(const FacetIntegrator& reference,
                                                const Motion& motion,
                                                std::span<const Vec3> observers_m,
                                                const ExposureOptions& options,
                                                WorkCounter* counter = nullptr,
                                                PointExchange* exchange = nullptr);

/// @brief Which points of the lattice @p lattice (a plane's or a box's; their places at t = 0,
/// riding the motion's platform) the engagement may light above the floor. Blocks of the
/// lattice (squares of a plane, cubes of a box), coarsest first, are bounded over each initial
/// interval, and over its halves to three levels where that bound is above the floor, under
/// each interval's swept beam; a block some interval may light is split, down to single cells,
/// whose corners are then lit. The points of blocks no bound lets light are dark over the whole
/// span and need no sample. Indexed [(k × nodes[1] + j) × nodes[0] + i].
std::vector<std::uint8_t> litByBound(const FacetIntegrator& reference, const Motion& motion,
                                     const FieldSpec& lattice, const ExposureOptions& options);

/// @brief The same observers sampled at @p steps equal steps (steps + 1 samples), each
/// integrated to the reference's accuracy: the independent twin the adaptive sampling is
/// checked and benchmarked against.
std::vector<ExposureHistory> uniformExposures(const FacetIntegrator& reference,
                                              const Motion& motion,
                                              std::span<const Vec3> observers_m, int steps);

}  // namespace glint
