#include "revcol/collide/cases.hpp"

#include <cmath>

#include "revcol/error.hpp"
#include "revcol/rng/normal.hpp"

namespace revcol {
namespace {

constexpr double kPi = trig::kPi;

NamedCase make(std::string name, int n, int d, std::vector<Contact> contacts,
               std::vector<double> positions, std::string description) {
  return NamedCase{std::move(name), n, d, std::move(contacts), std::move(positions),
                   std::move(description)};
}

using Normal = rng::SplitMixNormal;  // revcol/rng/normal.hpp

}  // namespace

std::vector<NamedCase> named_cases() {
  const double s2 = 1.0 / std::sqrt(2.0), s3 = 1.0 / std::sqrt(3.0), h = std::sqrt(3.0) / 2.0;
  const double th = 5.0 * kPi / 6.0;  // C3/C4 angle, in (pi/3, 5 pi/3)
  const double z3 = std::sqrt(1.0 - 0.3 * 0.3 - 0.5 * 0.5);
  return {
      make("pair1d", 2, 1, {{0, 1}}, {1, 0}, "2 particles in 1D (the paper's §4.1)"),
      make("pair2d", 2, 2, {{0, 1}}, {s2, s2, 0, 0}, "2 particles in 2D, r21 = (1, 1) (§4.2)"),
      make("pair3d", 2, 3, {{0, 1}}, {s3, s3, s3, 0, 0, 0}, "2 particles in 3D, r21 = (1, 1, 1) (§4.3)"),
      make("triple1d", 3, 1, {{1, 0}, {2, 1}}, {0, 1, 2}, "3 particles in a row in 1D (§4.4)"),
      make("triple2d-c1", 3, 2, {{1, 0}, {2, 1}, {2, 0}}, {0, 0, 1, 0, 0.5, h},
           "3 disks in mutual contact, P3 above P1-P2 (C1, §4.5)"),
      make("triple2d-c2", 3, 2, {{1, 0}, {2, 1}, {2, 0}}, {0, 0, 1, 0, 0.5, -h},
           "3 disks in mutual contact, P3 below P1-P2 (C2)"),
      make("triple2d-c3", 3, 2, {{1, 0}, {2, 1}}, {0, 0, 1, 0, 1 - std::cos(th), -std::sin(th)},
           "P3 touches P2 only, theta = 5 pi/6 (C3)"),
      make("triple2d-c4", 3, 2, {{1, 0}, {2, 0}}, {0, 0, 1, 0, std::cos(th), std::sin(th)},
           "P3 touches P1 only, theta = 5 pi/6 (C4)"),
      make("chain4-1d", 4, 1, {{1, 0}, {2, 1}, {3, 2}}, {0, 1, 2, 3}, "4 particles in a row, 1D"),
      make("chain4-2d", 4, 2, {{1, 0}, {2, 1}, {3, 2}}, {0, 0, 1, 0, 1.5, h, 2.5, h},
           "4 disks in a zigzag chain, 2D"),
      make("chain4-3d", 4, 3, {{1, 0}, {2, 1}, {3, 2}},
           {0, 0, 0, 1, 0, 0, 1.5, h, 0, 1.5, h + 0.5, h}, "4 spheres in a non-planar chain, 3D"),
      make("triple3d-2", 3, 3, {{1, 0}, {2, 1}}, {0, 0, 0, 1, 0, 0, 1.3, 0.5, z3},
           "3 spheres, 2 contacts, 3D"),
      make("triple3d-3", 3, 3, {{1, 0}, {2, 1}, {2, 0}},
           {0, 0, 0, 1, 0, 0, 0.5, h * std::cos(kPi / 6), h * std::sin(kPi / 6)},
           "3 spheres in mutual contact, 3D"),
      make("cradle1d", 3, 1, {{1, 0}, {2, 1}}, {0, 1, 2},
           "Newton's cradle, 1D: particle 0 hits two touching particles at rest"),
      make("cradle2d", 3, 2, {{1, 0}, {2, 1}}, {0, 0, 1, 0, 2, 0},
           "Newton's cradle, 2D: a disk hits a row of two touching disks at rest"),
  };
}

NamedCase named_case(const std::string& name) {
  std::string known;
  for (NamedCase& c : named_cases()) {
    if (c.name == name) return c;
    known += (known.empty() ? "" : ", ") + c.name;
  }
  throw InvalidArgument("unknown case '" + name + "' (known: " + known + ")");
}

ExactCollision exact_operator(const NamedCase& c, Law law, int bits) {
  return ExactCollision::from_positions(c.n, c.d, c.contacts, c.positions, 1.0, law, bits);
}

std::vector<double> approaching_state(const ExactCollision& op, std::uint64_t seed) {
  const int n = op.particles(), d = op.dim();
  Normal N{seed * 0x632be59bd9b4e019ULL + 1};
  std::vector<double> v(n * d);
  for (int attempt = 0; attempt < 1000000; ++attempt) {
    for (double& x : v) x = N();
    bool ok = true;
    for (double p : op.normal_speeds(v.data())) ok = ok && p < 0.0;
    if (ok) return v;
  }
  throw InvalidArgument("no approaching state found for this geometry");
}

}  // namespace revcol
