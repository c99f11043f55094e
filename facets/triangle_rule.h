#pragma once
/// @file
/// @brief Product Gauss rules on a triangle (Stroud's conical product): the high-order rule of
/// the cubature scheme (integrator.h, IntegrationScheme::Cubature).

#include <span>

#include "facets/vec3.h"

namespace glint {

/// @brief A node of a rule on a triangle: barycentric coordinates and a weight. The weights of
/// a rule sum to 1, so ∫_T f dA ≈ area(T) · Σ wₖ f(xₖ).
struct TriangleNode {
  Vec3 bary;
  double weight;
};

/// @brief The n × n conical product rule, exact for every polynomial of total degree 2n − 1.
///
/// The triangle is the image of the unit square under (ξ, η) ↦ (λ₁, λ₂) = (ξ, (1 − ξ) η), whose
/// Jacobian is (1 − ξ): Gauss–Jacobi (weight 1 − ξ) nodes in ξ and Gauss–Legendre nodes in η
/// make the product exact to degree 2n − 1 in each variable, hence in total degree. All nodes
/// lie inside the triangle and all weights are positive, so the rule never amplifies noise and
/// a positive integrand gives a positive sum. Nodes come from the Golub–Welsch eigenproblem,
/// computed once per n.
/// @param n points per direction, 1 to 12.
std::span<const TriangleNode> conicalProductRule(int n);

}  // namespace glint
