// Named collision geometries: the paper's configurations and those beyond it. Used by
// verify(), the tests and the benchmarks. Diameter 1; the contact normal of (i, j) is
// x_i - x_j. Particle 0 is the paper's particle 1 (the smallest id).
#pragma once
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "revcol/collide/exact.hpp"

namespace revcol {

/// A named collision geometry.
struct NamedCase {
  std::string name;               ///< e.g. "triple2d-c1"
  int n = 0, d = 0;               ///< particles, dimension
  std::vector<Contact> contacts;  ///< contact pairs (i, j)
  std::vector<double> positions;  ///< n x d, touching pairs at distance 1
  std::string description;        ///< one line
};

/// Every named case, in a stable order.
std::vector<NamedCase> named_cases();
/// The case called `name`; throws InvalidArgument listing the known names otherwise.
NamedCase named_case(const std::string& name);
/// The exact operator for a named case.
ExactCollision exact_operator(const NamedCase& c, Law law = Law::flux,
                              int bits = FixedPoint::default_bits);
/// A deterministic valid pre-collision state (n x d velocities: every contact approaching)
/// drawn from standard normal velocities with the given seed.
std::vector<double> approaching_state(const ExactCollision& op, std::uint64_t seed);

}  // namespace revcol
