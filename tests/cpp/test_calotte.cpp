#include "revcol/collide/calotte.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "check.hpp"

using namespace revcol;
using namespace revcol::paper;

namespace {
constexpr double kPi = 3.141592653589793238462643383279502884;

// H_3 in closed form: int_0^psi sin t sqrt(1 + 2 sin^2 t) dt = int_{cos psi}^1 sqrt(3 - 2 c^2) dc
double h3_exact(double psi) {
  auto G = [](double c) {
    return 0.5 * c * std::sqrt(3.0 - 2.0 * c * c) + 3.0 / (2.0 * std::sqrt(2.0)) * std::asin(std::sqrt(2.0 / 3.0) * c);
  };
  return (G(1.0) - G(std::cos(psi))) / (G(1.0) - G(-1.0));
}
double uniform01(std::mt19937_64& rng) { return (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53; }
}  // namespace

TEST_CASE("H_3 calotte fractions: table and direct quadrature against the closed form") {
  const CalotteTable& t = CalotteTable::h3();
  CHECK(t.dim() == 3);
  for (int k = 0; k <= 200; ++k) {
    const double psi = kPi * k / 200.0;
    CHECK_NEAR(t.fraction(psi), h3_exact(psi), 1e-13);
  }
  CHECK_NEAR(CalotteTable::fraction_direct(3, 1.1), h3_exact(1.1), 1e-14);
}

TEST_CASE("H_4 calotte fractions: the table against direct quadrature, symmetry, endpoints") {
  const CalotteTable& t = CalotteTable::h4();
  CHECK(t.dim() == 4);
  for (double psi : {0.0, 0.05, 0.4, 1.0, 1.5707963267948966, 2.2, 3.0, kPi}) {
    CHECK_NEAR(t.fraction(psi), CalotteTable::fraction_direct(4, psi), 1e-13);
    CHECK_NEAR(t.fraction(psi) + t.fraction(kPi - psi), 1.0, 1e-13);  // x_1 -> -x_1
  }
  CHECK(t.fraction(0.0) == 0.0);
  CHECK(t.fraction(kPi) == 1.0);
  // density ~ sin^2 near the pole (a 3-sphere's cap), so F ~ psi^3
  CHECK(t.fraction(1e-3) < 1e-8);
}

TEST_CASE("inverse: F^-1(F(psi)) = psi, monotone, endpoints") {
  for (const CalotteTable* t : {&CalotteTable::h3(), &CalotteTable::h4()}) {
    for (int k = 1; k < 300; ++k) {
      const double psi = kPi * k / 300.0;
      CHECK_NEAR(t->inverse(t->fraction(psi)), psi, 1e-11);
    }
    CHECK(t->inverse(0.0) == 0.0);
    CHECK_NEAR(t->inverse(1.0), kPi, 1e-12);
    double prev = 0.0;
    for (int k = 0; k <= 1000; ++k) {
      const double p = t->inverse(k / 1000.0);
      CHECK(p >= prev);
      prev = p;
    }
  }
}

TEST_CASE("psi_1 has the marginal of H_4's surface measure (Monte Carlo, rejection on |L^-1 u|)") {
  // points uniform on the surface of diag(1, 1, 1/sqrt3, 1/sqrt3) S^3: u uniform on S^3,
  // accepted with probability |Lambda^-1 u| / max = sqrt(1 + 2 (u3^2 + u4^2)) / sqrt3
  std::mt19937_64 rng(3);
  std::normal_distribution<double> N;
  std::vector<double> psi1;
  while (psi1.size() < 200000) {
    double u[4], n2 = 0;
    for (double& x : u) { x = N(rng); n2 += x * x; }
    const double n = std::sqrt(n2);
    for (double& x : u) x /= n;
    if (uniform01(rng) * std::sqrt(3.0) < std::sqrt(1.0 + 2.0 * (u[2] * u[2] + u[3] * u[3])))
      psi1.push_back(std::acos(u[0]));
  }
  std::sort(psi1.begin(), psi1.end());
  const CalotteTable& t = CalotteTable::h4();
  double D = 0.0;
  for (std::size_t k = 0; k < psi1.size(); ++k)
    D = std::max({D, std::fabs(t.fraction(psi1[k]) - double(k) / psi1.size()),
                  std::fabs(t.fraction(psi1[k]) - double(k + 1) / psi1.size())});
  CHECK(D < 1.63 / std::sqrt(double(psi1.size())));  // KS at p = 0.01
  // and it is not the uniform (round-sphere) marginal, whose density is 2/pi sin^2
  double Du = 0.0;
  for (std::size_t k = 0; k < psi1.size(); k += 100) {
    const double p = psi1[k], F = (p - std::sin(p) * std::cos(p)) / kPi;
    Du = std::max(Du, std::fabs(F - double(k) / psi1.size()));
  }
  CHECK(Du > 5.0 / std::sqrt(double(psi1.size())));
}

TEST_CASE("the sampler: exactly three numbers, ranges, psi_3 = 2 pi G_3, validation") {
  const HyperEllipsoidSampler s;
  const auto p = s.psi({0.5, 0.5, 0.25});
  CHECK_NEAR(p[0], 0.5 * kPi, 1e-12);  // symmetric shapes: the median latitude is the equator
  CHECK_NEAR(p[1], 0.5 * kPi, 1e-12);
  CHECK_NEAR(p[2], 0.5 * kPi, 1e-15);
  const auto lo = s.psi({0.0, 0.0, 0.0}), hi = s.psi({1.0, 1.0, 1.0});
  CHECK(lo[0] == 0.0 && lo[1] == 0.0 && lo[2] == 0.0);
  CHECK_NEAR(hi[0], kPi, 1e-12);
  CHECK_NEAR(hi[2], 2.0 * kPi, 1e-15);
  CHECK_THROWS_AS(s.psi({-0.1, 0.5, 0.5}), InvalidArgument);
  CHECK_THROWS_AS(s.psi({0.5, 1.1, 0.5}), InvalidArgument);
  CHECK_THROWS_AS(s.psi({0.5, 0.5, std::nan("")}), InvalidArgument);
  CHECK_THROWS_AS(CalotteTable::h4().fraction(4.0), InvalidArgument);
  CHECK_THROWS_AS(CalotteTable::h4().inverse(-1e-3), InvalidArgument);
  CHECK_THROWS_AS(CalotteTable::fraction_direct(5, 1.0), InvalidArgument);
}

CHECK_MAIN()
