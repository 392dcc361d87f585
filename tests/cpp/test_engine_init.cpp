// The engine's random start in any box (engine/init.hpp) and its limits (engine/limits.hpp):
// no overlap, inside the box, zero momentum, the energy asked, same seed same bits, clear
// errors; the limits agree with what the engine accepts.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "check.hpp"
#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/engine/limits.hpp"
#include "revcol/error.hpp"

using namespace revcol;
using namespace revcol::engine;

namespace {

Config box_config(std::vector<double> box, std::vector<Boundary> b, double D = 1.0) {
  Config c;
  c.dim = static_cast<int>(box.size());
  for (int k = 0; k < c.dim; ++k) {
    c.box[k] = box[k];
    c.boundary[k] = b.size() == 1 ? b[0] : b[k];
  }
  c.diameter = D;
  return c;
}

// Smallest centre distance over D (periodic images folded), and whether every centre is in
// its range (walls: at least D/2 from each wall; periodic: in [0, L)).
struct Shape {
  double min_gap = 1e300;
  bool inside = true;
};

Shape shape(const Config& c, const InitialState& s) {
  const int d = c.dim;
  const std::size_t n = s.x.size() / d;
  Shape out;
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < d; ++k) {
      const double p = s.x[i * d + k], L = c.box[k];
      const bool ok = c.boundary[k] == Boundary::wall ? (p >= 0.5 * c.diameter && p <= L - 0.5 * c.diameter)
                                                      : (p >= 0.0 && p < L);
      out.inside = out.inside && ok;
    }
    for (std::size_t j = 0; j < i; ++j) {
      double r2 = 0.0;
      for (int k = 0; k < d; ++k) {
        double dx = std::abs(s.x[i * d + k] - s.x[j * d + k]);
        if (c.boundary[k] == Boundary::periodic) dx = std::min(dx, c.box[k] - dx);
        r2 += dx * dx;
      }
      out.min_gap = std::min(out.min_gap, std::sqrt(r2) / c.diameter);
    }
  }
  return out;
}

std::vector<double> momentum(int d, const std::vector<double>& v) {
  std::vector<double> p(d, 0.0);
  for (std::size_t i = 0; i < v.size(); ++i) p[i % d] += v[i];
  return p;
}

double energy(const std::vector<double>& v) {
  double e = 0.0;
  for (double q : v) e += 0.5 * q * q;
  return e;
}

template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("random_start: rsa and crystal in non-cubic boxes, walls and periodic per axis") {
  const Boundary W = Boundary::wall, P = Boundary::periodic;
  struct Case {
    std::vector<double> box;
    std::vector<Boundary> b;
    std::size_t n;
    const char* init;
    double D;
  };
  const Case cases[] = {
      {{40.0}, {W}, 30, "rsa", 1.0},          {{40.0}, {P}, 35, "crystal", 1.0},
      {{12.0, 5.0}, {W, P}, 30, "crystal", 1.0}, {{12.0, 5.0}, {P, W}, 20, "rsa", 1.0},
      {{30.0, 4.0}, {W}, 45, "crystal", 1.0}, {{5.0, 6.0, 9.0}, {W, P, W}, 60, "crystal", 1.0},
      {{5.0, 6.0, 9.0}, {P}, 60, "rsa", 1.0}, {{8.0, 8.0, 3.5}, {P}, 90, "crystal", 1.0},
      {{7.5, 12.0}, {W}, 15, "auto", 1.5},   {{9.0, 12.0}, {W}, 30, "auto", 1.5},
  };
  for (const Case& k : cases) {
    const Config c = box_config(k.box, k.b, k.D);
    const double e_asked = 3.5 * static_cast<double>(k.n);
    const InitialState s = random_start(c, k.n, 11, e_asked, k.init);
    REQUIRE(s.x.size() == k.n * c.dim && s.v.size() == k.n * c.dim);
    const Shape sh = shape(c, s);
    CHECK(sh.inside);
    CHECK(sh.min_gap >= 1.0);
    for (double p : momentum(c.dim, s.v)) CHECK(std::abs(p) < 1e-12 * std::sqrt(e_asked));
    CHECK(std::abs(energy(s.v) / e_asked - 1.0) < 1e-14);
    CHECK(s.config.box == c.box && s.config.boundary == c.boundary);
    // the engine takes the start as it is
    CHECK(make_simulation(s.config, s.x, s.v)->size() == k.n);
  }
}

TEST_CASE("random_start: default energy N d / 2, equal speeds, one particle") {
  const Config c = box_config({10.0, 10.0}, {Boundary::wall});
  const InitialState s = random_start(c, 20, 4);
  CHECK(std::abs(energy(s.v) / 20.0 - 1.0) < 1e-14);  // N d / 2 = 20
  const InitialState q = random_start(c, 20, 4, 0.0, "auto", true);
  const double s0 = std::hypot(q.v[0], q.v[1]);
  for (std::size_t i = 0; i < 20; ++i) CHECK(std::abs(std::hypot(q.v[2 * i], q.v[2 * i + 1]) / s0 - 1.0) < 1e-14);
  const InitialState one = random_start(box_config({3.0}, {Boundary::wall}), 1, 2, 2.0);
  CHECK(one.x.size() == 1 && std::abs(energy(one.v) - 2.0) < 1e-15);
}

TEST_CASE("random_start refuses more particles than a list entry's id holds, before allocating") {
  // a list entry packs an id above 2 d bits of image code in 32 bits (revcol/engine/neighbours.hpp)
  CHECK(limits::max_particles(1) == (std::uint64_t{1} << 30));
  CHECK(limits::max_particles(2) == (std::uint64_t{1} << 28));
  CHECK(limits::max_particles(3) == (std::uint64_t{1} << 26));
  for (int d = 1; d <= 3; ++d) {
    const Config c = box_config(std::vector<double>(d, 1e6), {Boundary::periodic});
    const std::size_t n = limits::max_particles(d) + 1;  // a few GB if it were allocated
    const std::string e = error_of([&] { random_start(c, n, 1); });
    CHECK(e == "too many particles in " + std::to_string(d) + "D (N must be at most " +
                   std::to_string(limits::max_particles(d)) + ", got " + std::to_string(n) + ")");
  }
}

TEST_CASE("random_start: same seed same bits; another seed another start") {
  const Config c = box_config({9.0, 7.0, 11.0}, {Boundary::periodic, Boundary::wall, Boundary::periodic});
  for (const char* init : {"rsa", "crystal"}) {
    const InitialState a = random_start(c, 80, 5, 0.0, init), b = random_start(c, 80, 5, 0.0, init);
    const InitialState o = random_start(c, 80, 6, 0.0, init);
    CHECK(a.x == b.x && a.v == b.v);
    CHECK(a.x != o.x && a.v != o.v);
  }
}

TEST_CASE("parse_placement: \"crystal\", and \"lattice\" its old name for the same start") {
  CHECK(parse_placement("crystal") == Placement::crystal);
  CHECK(parse_placement("lattice") == Placement::crystal);
  const Config c = box_config({9.0, 7.0, 11.0}, {Boundary::periodic, Boundary::wall, Boundary::periodic});
  const InitialState a = random_start(c, 80, 5, 0.0, "crystal"), b = random_start(c, 80, 5, 0.0, "lattice");
  CHECK(a.x == b.x);
  CHECK(a.v == b.v);
  const std::string e = error_of([&] { parse_placement("grid"); });
  CHECK(e.find("'auto', 'rsa', 'crystal' or 'relax'") != std::string::npos);
}

TEST_CASE("random_state is random_start in the cube of its packing fraction") {
  for (int d = 1; d <= 3; ++d)
    for (const char* init : {"rsa", "crystal"}) {
      Config c;
      c.dim = d;
      c.boundary = {Boundary::wall, Boundary::periodic, Boundary::wall};
      const InitialState s = random_state(c, 120, 0.2, 9, 0.0, init);
      const InitialState t = random_start(s.config, 120, 9, 0.0, init);
      CHECK(s.x == t.x && s.v == t.v);
      CHECK(std::abs(box_fraction(s.config, 120) / 0.2 - 1.0) < 1e-14);
    }
}

TEST_CASE("random_state: a walled cube whose equal crystal counts crowd the sites takes unequal ones") {
  // 1000 spheres at volume fraction 0.45 between walls: 7 x 7 x 7 FCC cells of the usable box
  // put the nearest sites 0.96 D apart (this threw before); 6 x 6 x 7 cells fit
  Config c;
  c.dim = 3;
  c.boundary = {Boundary::wall, Boundary::wall, Boundary::wall};
  const InitialState s = random_state(c, 1000, 0.45, 3, 0.0, "crystal");
  const Shape sh = shape(s.config, s);
  CHECK(sh.inside);
  CHECK(sh.min_gap >= 1.0);
  CHECK(std::abs(box_fraction(s.config, 1000) / 0.45 - 1.0) < 1e-14);
  // a cube whose equal counts fit keeps them, bit for bit: test_engine_hash's known starts
  Config p = c;
  p.boundary = {Boundary::periodic, Boundary::periodic, Boundary::periodic};
  const InitialState q = random_state(p, 1000, 0.45, 3, 0.0, "crystal");
  CHECK(shape(q.config, q).min_gap >= 1.0);
}

TEST_CASE("random_start: N that does not fit, and bad input, are clear errors") {
  const Config c = box_config({5.0, 6.0, 9.0}, {Boundary::wall, Boundary::periodic, Boundary::wall});
  CHECK(error_of([&] { random_start(c, 500, 1); }).find("500 particles of diameter 1") != std::string::npos);
  CHECK(error_of([&] { random_start(c, 500, 1); }).find("do not fit") != std::string::npos);
  // under the packing-fraction limit, but no crystal of spacing > D holds 10 disks in 3.5 x 3.5
  // walls (centres in [0.5, 3]); 9 fit on the crystal whose outer rows lie on the walls' margins
  // (spacing 1.25), the last resort of a walled start (issue 58), and the error names the densest
  const Config small = box_config({3.5, 3.5}, {Boundary::wall});
  const std::string why = error_of([&] { random_start(small, 10, 1, 0.0, "crystal"); });
  CHECK(why.find("do not fit on a crystal") != std::string::npos);
  CHECK(why.find("fits up to a packing fraction of") != std::string::npos);
  const InitialState nine = random_start(small, 9, 1, 0.0, "crystal");
  CHECK(shape(nine.config, nine).min_gap >= 1.0);
  CHECK(error_of([&] { random_start(c, 0, 1); }).find("N = 0") != std::string::npos);
  CHECK(error_of([&] { random_start(c, 10, 1ull << 32); }).find("seed") != std::string::npos);
  CHECK(error_of([&] { random_start(c, 10, 1, 0.0, "grid"); }).find("init must be") != std::string::npos);
  CHECK(error_of([&] { random_start(box_config({2.9, 10.0}, {Boundary::periodic}), 2, 1); })
            .find("periodic box too small") != std::string::npos);
  CHECK(error_of([&] { random_start(box_config({1.0, 10.0}, {Boundary::wall}), 2, 1); })
            .find("too large for the box") != std::string::npos);
  Config bad = c;
  bad.diameter = -1.0;
  CHECK(error_of([&] { random_start(bad, 10, 1); }).find("diameter") != std::string::npos);
}

TEST_CASE("limits agree with the engine: paper mode dimensions, periodic axes, walls, volume") {
  for (int d = 1; d <= 3; ++d) {
    Config c;
    c.dim = d;
    c.mode = Mode::paper;
    c.boundary = {Boundary::wall, Boundary::wall, Boundary::wall};
    for (int k = 0; k < 3; ++k) c.box[k] = 10.0;
    std::vector<double> x(2 * d, 5.0), v(2 * d, 0.0);
    x[0] = 2.0;
    v[0] = 1.0;
    const bool accepted = error_of([&] { make_simulation(c, x, v); }).empty();
    CHECK(accepted == limits::paper_mode_allowed(d));
  }
  for (double L : {2.999, 3.0, 3.001}) {
    Config c;
    c.dim = 2;
    c.box = {L, 10.0, 1.0};
    const std::vector<double> x{1.0, 1.0, 1.0, 5.0}, v{1.0, 0.0, -1.0, 0.0};
    const bool accepted = error_of([&] { make_simulation(c, x, v); }).empty();
    CHECK(accepted == limits::periodic_axis_fits(L, 1.0));
  }
  CHECK(!limits::periodic_axis_fits(2.999, 1.0) && limits::periodic_axis_fits(3.0, 1.0));
  CHECK(limits::wall_axis_fits(1.001, 1.0) && !limits::wall_axis_fits(1.0, 1.0));
  CHECK(particle_volume(1, 2.0) == 2.0);
  CHECK(std::abs(particle_volume(2, 2.0) - limits::kPi) < 1e-15);
  CHECK(std::abs(particle_volume(3, 2.0) - 4.0 * limits::kPi / 3.0) < 1e-15);
  for (int d = 1; d <= 3; ++d) CHECK(limits::rsa_fraction(d) < limits::max_fraction(d));
}

int main() { return check::run_all(); }
