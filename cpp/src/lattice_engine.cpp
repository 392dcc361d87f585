// The 2D lattice engine (lattice/engine.hpp): the explicit instantiation over the exact pair
// operator, starts from float states, snapshots and diagnostics.
#include "revcol/lattice/engine.hpp"

#include <cmath>

#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/error.hpp"

namespace revcol::lattice {

template class BasicEngine<LatticePair2D, BitsBack>;

std::vector<std::uint64_t> initial_bits(std::uint32_t seed) {
  std::vector<std::uint64_t> w;
  for (std::uint32_t k = 0; k < 2; ++k) {
    const auto b = rng::philox4x32_10({k, 0U, 0U, 0U}, {0xFFFFFFFFU, seed});
    w.push_back((std::uint64_t{b[0]} << 32) | b[1]);
    w.push_back((std::uint64_t{b[2]} << 32) | b[3]);
  }
  w.back() |= std::uint64_t{1} << 63;  // exactly 256 bits
  return w;
}

bool same_state(const Snapshot& a, const Snapshot& b) {
  const Units &u = a.units, &w = b.units;
  return u.S == w.S && u.sigma == w.sigma && u.L == w.L && u.wall == w.wall && u.vmax == w.vmax &&
         u.tick_bits == w.tick_bits && u.cell_bits == w.cell_bits &&
         a.seed == b.seed && a.clock == b.clock && a.origin == b.origin && a.collisions == b.collisions &&
         a.x == b.x && a.v == b.v && a.streams == b.streams && a.bits == b.bits && a.log == b.log &&
         a.groups == b.groups &&
         a.energy0 == b.energy0 && a.momentum0 == b.momentum0;
}

LatticeStart quantize_start(const LatticeConfig& c, const std::vector<double>& x, const std::vector<double>& v) {
  require(x.size() == v.size() && x.size() % 2 == 0 && !x.empty(), "lattice: positions and velocities must both be n x 2");
  double s2 = 0.0;
  for (double a : v) s2 += a * a;
  const double v_rms = std::sqrt(s2 / static_cast<double>(x.size() / 2));
  LatticeStart s;
  s.units = choose_units(c.box, c.diameter, v_rms, c.wall, c.tick_bits, c.cell_bits, x.size() / 2);
  Quantized q = quantize(s.units, x, v);
  s.x = std::move(q.x);
  s.v = std::move(q.v);
  s.max_position_error = q.max_position_error;
  s.max_velocity_error = q.max_velocity_error;
  return s;
}

LatticeStart random_start(const LatticeConfig& c, std::size_t n, double phi, std::uint64_t seed,
                          const std::string& init) {
  engine::Config fc;
  fc.dim = 2;
  fc.diameter = c.diameter;
  for (int k = 0; k < 2; ++k) fc.boundary[k] = c.wall[k] ? engine::Boundary::wall : engine::Boundary::periodic;
  const engine::InitialState st = engine::random_state(fc, n, phi, seed, 0.0, init);
  LatticeConfig lc = c;
  lc.box = {st.config.box[0], st.config.box[1]};
  return quantize_start(lc, st.x, st.v);
}

Diagnostics diagnostics(const LatticeEngine& e) {
  Diagnostics d;
  const u128 E = kinetic2(e.velocities()), E0 = e.energy0();
  const double dE = E >= E0 ? static_cast<double>(E - E0) : -static_cast<double>(E0 - E);
  d.energy_drift_units = dE;
  d.energy_drift = E0 > 0 ? dE / static_cast<double>(E0) : 0.0;
  const auto P = LatticeEngine::momentum_of(e.velocities());
  for (int k = 0; k < 2; ++k) d.momentum_drift[k] = static_cast<double>(P[k] - e.momentum0(k));
  d.bits_length = e.bits().bit_length();
  d.log_entries = e.log_size();
  d.collisions = e.collisions();
  d.clock = e.clock();
  d.time = static_cast<double>(e.clock() - e.origin()) * e.units().tick;
  d.memory_bytes = e.memory_bytes();
  return d;
}

}  // namespace revcol::lattice
