// The lattice engine (lattice/engine.hpp): the explicit instantiation of the 2D engine over the
// exact pair operator (the 3D engine's is engine3d.cpp), starts from float states in 2D and
// 3D, and diagnostics.
#include "revcol/lattice/engine.hpp"

#include "engine_impl.hpp"

#include <cmath>

#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/error.hpp"

namespace revcol::lattice {

template class BasicEngine<LatticePair2D, BitsBack>;

std::vector<std::uint64_t> initial_bits(std::uint32_t p, std::uint32_t seed) {
  const auto b = rng::philox4x32_10({0U, 0U, 1U, 0U}, {p, seed});
  std::vector<std::uint64_t> w{(std::uint64_t{b[0]} << 32) | b[1], (std::uint64_t{b[2]} << 32) | b[3]};
  w.back() |= std::uint64_t{1} << 63;  // exactly 128 bits
  return w;
}

namespace {
// A mixture's diameters checked (one per particle, each finite and > 0); the largest.
double largest_diameter(const std::vector<double>& diameters, std::size_t n) {
  require(diameters.size() == n, [&] {
    return "lattice: diameters must have one entry per particle (" + std::to_string(n) + "), got " + std::to_string(diameters.size());
  });
  double dmax = 0.0;
  for (double d : diameters) {
    require(std::isfinite(d) && d > 0.0, "lattice: every diameter must be finite and > 0");
    dmax = std::max(dmax, d);
  }
  return dmax;
}
}  // namespace

template <std::size_t D>
LatticeStartN<D> quantize_start(const LatticeConfigN<D>& c, const std::vector<double>& x, const std::vector<double>& v) {
  require(x.size() == v.size() && x.size() % D == 0 && !x.empty(),
          D == 2 ? "lattice: positions and velocities must both be n x 2" : "lattice: positions and velocities must both be n x 3");
  double s2 = 0.0;
  for (double a : v) s2 += a * a;
  const double v_rms = std::sqrt(s2 / static_cast<double>(x.size() / D));
  const std::size_t n = x.size() / D;
  const double dmax = c.diameters.empty() ? c.diameter : largest_diameter(c.diameters, n);
  LatticeStartN<D> s;
  s.units = choose_units_d<D>(c.box, dmax, v_rms, c.wall, c.tick_bits, c.cell_bits, n);
  double gmax = 0.0;  // the strongest field component, float units
  for (double g : c.gravity) gmax = std::max(gmax, std::isfinite(g) ? std::fabs(g) : 0.0);
  if (c.tick_bits == auto_tick_bits && gmax > 0.0) {
    // a field and the automatic tick: a coarser tick (each bit a factor 4 on g in lattice units)
    // until g's rounding to an even integer is within 2^-8 relative; g = 1 at kT = 1, a power of
    // two there, keeps the tick. A coarser tick makes third bodies within a tick, so groups and
    // redraws, more frequent, and the fall heats the gas (kT ~ 50 in a 2D box 160 tall under
    // g = 1), which coarsens it again: a tick coarsened until |g| >= 2^12 units, then 2^8,
    // passed 1e-5 log entries per collision there (docs/engine.md, measured)
    auto rounding = [&](const UnitsN<D>& u) {
      const double gl = gmax * u.tick * u.tick / u.length_unit;
      return gl < 2.0 ? 1.0 : std::fabs(2.0 * std::round(0.5 * gl) - gl) / gl;
    };
    int T = s.units.tick_bits;
    while (T > min_tick_bits && rounding(s.units) > 0x1p-8) {
      --T;
      s.units = choose_units_d<D>(c.box, dmax, v_rms, c.wall, T, c.cell_bits, n);
    }
  }
  s.units.bounce = c.bounce;
  for (std::size_t k = 0; k < D; ++k) {  // a field, quantized once to even lattice units per tick^2
    const double g = c.gravity[k];
    require(std::isfinite(g), "lattice: gravity must be finite");
    if (g == 0.0) continue;
    require(c.wall[k], "lattice: gravity is allowed only along a walled axis (a periodic axis has no floor)");
    const double gl = g * s.units.tick * s.units.tick / s.units.length_unit;
    const double ge = 2.0 * std::round(0.5 * gl);
    require(std::fabs(ge) >= 2.0, [&] {
      return "lattice: gravity " + std::to_string(g) + " is below the lattice's resolution at this tick (" +
             std::to_string(gl) + " lattice units per tick^2; 2 is the least): use a coarser tick (smaller tick_bits)";
    });
    require(std::fabs(ge) <= static_cast<double>(max_gravity), "lattice: gravity is too strong for the lattice at this tick (above 2^36 lattice units per tick^2): use a finer tick (larger tick_bits)");
    s.units.gravity[k] = static_cast<std::int64_t>(ge);
    s.gravity_error = std::max(s.gravity_error, std::fabs(ge - gl) / std::fabs(gl));
  }
  require(std::isfinite(c.shear_rate), "lattice: shear_rate must be finite");
  if (c.shear_rate != 0.0) {  // Lees-Edwards, quantized once to lattice units per tick (shear.hpp)
    require(!c.wall[0] && !c.wall[1], "lattice: shear needs axes 0 (the flow) and 1 (the gradient) periodic");
    const double sl = c.shear_rate * c.box[1] * s.units.tick / s.units.length_unit;
    const double se = std::round(sl);
    require(std::fabs(se) >= 1.0, "lattice: the shear rate is below the lattice's resolution at this tick");
    require(std::fabs(se) <= static_cast<double>(s.units.vmax / 4), "lattice: the shear rate is too high for the lattice (gamma L_1 above vmax / 4)");
    s.units.shear = static_cast<std::int64_t>(se);
    s.shear_error = std::fabs(se - sl) / std::fabs(sl);
  }
  validate(s.units);
  if (!c.diameters.empty()) {
    s.radius.resize(n);
    for (std::size_t p = 0; p < n; ++p) {  // the largest exactly sigma / 2
      const double r = c.diameters[p] == dmax ? static_cast<double>(s.units.sigma / 2) : std::round(0.5 * c.diameters[p] / s.units.length_unit);
      s.radius[p] = static_cast<std::int64_t>(std::min(r, static_cast<double>(s.units.sigma / 2)));
    }
    validate_radii(s.units, s.radius, n);
  }
  QuantizedN<D> q = quantize(s.units, x, v, s.radius);
  s.x = std::move(q.x);
  s.v = std::move(q.v);
  s.max_position_error = q.max_position_error;
  s.max_velocity_error = q.max_velocity_error;
  return s;
}

template <std::size_t D>
LatticeStartN<D> random_start(const LatticeConfigN<D>& c, std::size_t n, double phi, std::uint64_t seed,
                              const std::string& init, const InterruptCheck& interrupt) {
  engine::Config fc;
  fc.dim = static_cast<int>(D);
  fc.diameter = c.diameter;
  for (std::size_t k = 0; k < D; ++k)
    fc.boundary[k] = !c.wall[k] ? engine::Boundary::periodic : c.bounce[k] ? engine::Boundary::bounce : engine::Boundary::wall;
  engine::InitialState st;
  if (!c.diameters.empty()) {
    largest_diameter(c.diameters, n);  // one per particle, each finite and > 0 (named errors)
    fc.diameters = c.diameters;        // a mixture: engine::random_state's cube of their own volumes
    fc.diameter = 1.0;                 // (it sets the largest)
  }
  try {
    st = engine::random_state(fc, n, phi, seed, 0.0, init, false, interrupt);
  } catch (const InvalidArgument& e) {
    if (c.diameters.empty()) throw;
    throw InvalidArgument(std::string("lattice: ") + e.what());
  }
  LatticeConfigN<D> lc = c;
  for (std::size_t k = 0; k < D; ++k) lc.box[k] = st.config.box[k];
  require(std::isfinite(c.shear_rate), "lattice: shear_rate must be finite");
  if (c.shear_rate != 0.0) {  // the steady profile about the particles' mean height (no momentum added)
    double ym = 0.0;
    for (std::size_t p = 0; p < n; ++p) ym += st.x[D * p + 1];
    ym /= static_cast<double>(n);
    for (std::size_t p = 0; p < n; ++p) st.v[D * p] += c.shear_rate * (st.x[D * p + 1] - ym);
  }
  return quantize_start(lc, st.x, st.v);
}

template LatticeStartN<2> quantize_start(const LatticeConfigN<2>&, const std::vector<double>&, const std::vector<double>&);
template LatticeStartN<3> quantize_start(const LatticeConfigN<3>&, const std::vector<double>&, const std::vector<double>&);
template LatticeStartN<2> random_start(const LatticeConfigN<2>&, std::size_t, double, std::uint64_t, const std::string&,
                                       const InterruptCheck&);
template LatticeStartN<3> random_start(const LatticeConfigN<3>&, std::size_t, double, std::uint64_t, const std::string&,
                                       const InterruptCheck&);

namespace {
template <class Eng>
DiagnosticsN<Eng::D> diagnostics_of(const Eng& e) {
  DiagnosticsN<Eng::D> d;
  const u128 E = energy2(e.units(), e.positions(), e.velocities()), E0 = e.energy0();
  const double dE = E >= E0 ? static_cast<double>(E - E0) : -static_cast<double>(E0 - E);
  d.energy_drift_units = dE;
  d.energy_drift = E0 > 0 ? dE / static_cast<double>(E0) : 0.0;
  const auto P = Eng::momentum_of(e.velocities());
  for (std::size_t k = 0; k < Eng::D; ++k) d.momentum_drift[k] = static_cast<double>(P[k] - e.momentum0(static_cast<int>(k)));
  d.bits_length = e.bits_length();
  d.log_entries = e.log_size();
  d.collisions = e.collisions();
  d.clock = e.clock();
  d.time = static_cast<double>(e.clock() - e.origin()) * e.units().tick;
  d.memory_bytes = e.memory_bytes();
  return d;
}
}  // namespace

Diagnostics diagnostics(const LatticeEngine& e) { return diagnostics_of(e); }
DiagnosticsN<3> diagnostics(const LatticeEngine3D& e) { return diagnostics_of(e); }

}  // namespace revcol::lattice
