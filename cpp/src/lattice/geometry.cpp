// Exact predicates, units, quantization and the cell grid of the lattice engine in 2D and 3D
// (lattice/geometry.hpp, units.hpp, cell_grid.hpp).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "revcol/error.hpp"
#include "revcol/lattice/cell_grid.hpp"
#include "revcol/lattice/geometry.hpp"
#include "revcol/lattice/units.hpp"

namespace revcol::lattice {

namespace {
// overlaps_at, inlined into first_overlap's search (it runs up to five times per prediction)
template <std::size_t D>
[[gnu::always_inline]] inline bool overlap_at(const VecN<D>& r, const VecN<D>& w, std::int64_t tau, u128 sigma2) noexcept {
  constexpr i128 big = i128{1} << 61;
  if constexpr (D == 2) {  // the 2D engine's code as it was (measure before changing)
    const i128 dx = static_cast<i128>(r[0]) + static_cast<i128>(w[0]) * tau;
    const i128 dy = static_cast<i128>(r[1]) + static_cast<i128>(w[1]) * tau;
    if (dx >= big || dx <= -big || dy >= big || dy <= -big) return false;
    return norm2(static_cast<std::int64_t>(dx), static_cast<std::int64_t>(dy)) < sigma2;
  } else {
    VecN<D> d;
    for (std::size_t k = 0; k < D; ++k) {
      const i128 dk = static_cast<i128>(r[k]) + static_cast<i128>(w[k]) * tau;
      if (dk >= big || dk <= -big) return false;
      d[k] = static_cast<std::int64_t>(dk);
    }
    return norm2(d) < sigma2;
  }
}

// r . w and |w|^2 in double, summed from the first axis on (in 2D exactly r0 w0 + r1 w1, the
// order the 2D engine has always used: its guesses, hence its bits, stay the same)
template <std::size_t D>
inline double ddot(const VecN<D>& a, const VecN<D>& b) noexcept {
  double s = static_cast<double>(a[0]) * static_cast<double>(b[0]);
  for (std::size_t k = 1; k < D; ++k) s += static_cast<double>(a[k]) * static_cast<double>(b[k]);
  return s;
}

// The first overlap tick when the guess g (an estimate of the entry root) has it: t = max(1,
// ceil(g)) with f(t) < sigma2 <= f(t - 1) (f convex: its inside ticks are an interval, so none
// lies before t - 1); else -1. False for NaN and for g outside (-1, 2^61).
template <std::size_t D>
std::int64_t guessed_tick(const VecN<D>& r, const VecN<D>& w, u128 sigma2, double g) noexcept {
  if (!(g > -1.0 && g < 0x1p61)) return -1;
  std::int64_t t = static_cast<std::int64_t>(g);  // truncation, then the ceiling
  if (static_cast<double>(t) < g) ++t;
  t = std::max<std::int64_t>(1, t);
  if constexpr (D == 3) {
    // overlap_at's answers, decided in double when surely on one side (the common case: f moves
    // by ~1/64 of sigma^2 per tick near contact), else exactly. With u = 2^-53, a_k = |r_k| +
    // |w_k t| and m = sum a_k^2: each y_k = r_k + w_k t is within ~4u a_k, so f = |y|^2 is
    // within ~12u m of the exact value; the band is 1e-12 (m + sigma^2), ~800 times that. A
    // component beyond overlap_at's 2^61 range gives f >> sigma^2: "no overlap" either way.
    const double s2 = to_double(sigma2);  // 2^(2S): exact
    auto at = [&](std::int64_t tau) {
      const double td = static_cast<double>(tau);
      double f = 0.0, m = 0.0;
      for (std::size_t k = 0; k < D; ++k) {
        const double rk = static_cast<double>(r[k]), wt = static_cast<double>(w[k]) * td;
        const double y = rk + wt, a = std::fabs(rk) + std::fabs(wt);
        f += y * y;
        m += a * a;
      }
      const double band = 1e-12 * (m + s2);
      if (f < s2 - band) return true;
      if (f > s2 + band) return false;
      return overlap_at(r, w, tau, sigma2);
    };
    return at(t) && !at(t - 1) ? t : -1;
  }
  return overlap_at(r, w, t, sigma2) && !overlap_at(r, w, t - 1, sigma2) ? t : -1;
}

template <std::size_t D>
std::int64_t first_overlap_d(const VecN<D>& r, const VecN<D>& w, u128 sigma2) noexcept {
  if (norm2(r) < sigma2) return 0;
  const i128 B = dot(r, w);
  if (B >= 0) return -1;  // not approaching: f increases from f(0) >= 0
  const double a = ddot(w, w), b = ddot(r, w);
  {
    // the common case, decided by two exact predicates: the double entry root's ceiling t with
    // f(t) < 0 <= f(t - 1) is the answer (f convex and f(0) >= 0: nothing before t - 1 is inside)
    const double c0 = ddot(r, r) - to_double(sigma2);
    const double g = c0 / (std::sqrt(std::max(0.0, b * b - a * c0)) - b);
    if (g > 0.0) {
      const std::int64_t t = guessed_tick(r, w, sigma2, g);
      if (t > 0) return t;
    }
  }
  const i128 A = dot(w, w);
  // f is convex with its real minimum in [tv, tv + 1); the integer minimum is at tv or tv + 1.
  // tv = floor(-B / A): a double guess (from the 64-bit components: no 128-bit division or
  // conversion), made exact by A tv <= -B < A (tv + 1) in 128 bits (|B| < 2^118, |tv| < 2^62)
  std::int64_t tv = static_cast<std::int64_t>(std::clamp(std::floor(-b / a), 0.0, 0x1p61));
  while (tv > 0 && A * tv > -B) --tv;
  while (A * (tv + 1) <= -B) ++tv;
  const bool at_v = overlap_at(r, w, tv, sigma2);
  if (!at_v) return overlap_at(r, w, tv + 1, sigma2) ? tv + 1 : -1;
  // f decreases on [0, tv]: the answer is the first tau in (0, tv] with f < 0 (f(0) >= 0).
  // First guess in double: the smaller root of A t^2 + 2 B t + C (C exact, then rounded once).
  const double c = static_cast<double>(static_cast<i128>(norm2(r)) - static_cast<i128>(sigma2));
  const double disc = std::max(0.0, b * b - a * c);
  double g = c / (-b + std::sqrt(disc));  // cancellation-free form of (-b - sqrt(disc)) / a
  std::int64_t lo = 0, hi = tv;            // invariant: f(lo) >= 0, f(hi) < 0
  if (std::isfinite(g) && g > 0.0 && g < static_cast<double>(tv)) {
    const std::int64_t t = std::clamp<std::int64_t>(static_cast<std::int64_t>(std::ceil(g)), 1, tv);
    // the guess and its neighbours decide it in the common case
    for (std::int64_t s : {t, t - 1, t + 1}) {
      if (s <= lo || s >= hi) continue;
      if (overlap_at(r, w, s, sigma2)) hi = s; else lo = s;
    }
    if (hi - lo == 1) return hi;
    for (std::int64_t s : {t - 2, t + 2}) {
      if (s <= lo || s >= hi) continue;
      if (overlap_at(r, w, s, sigma2)) hi = s; else lo = s;
    }
  }
  while (hi - lo > 1) {  // exact bisection on integers (a far guess, e.g. near grazing)
    const std::int64_t mid = lo + (hi - lo) / 2;
    if (overlap_at(r, w, mid, sigma2)) hi = mid; else lo = mid;
  }
  return hi;
}
}  // namespace

bool overlaps_at(const Vec2& r, const Vec2& w, std::int64_t tau, u128 sigma2) noexcept { return overlap_at(r, w, tau, sigma2); }
bool overlaps_at(const Vec3& r, const Vec3& w, std::int64_t tau, u128 sigma2) noexcept { return overlap_at(r, w, tau, sigma2); }
std::int64_t first_overlap(const Vec2& r, const Vec2& w, u128 sigma2) noexcept { return first_overlap_d(r, w, sigma2); }
std::int64_t first_overlap(const Vec3& r, const Vec3& w, u128 sigma2) noexcept { return first_overlap_d(r, w, sigma2); }
std::int64_t first_overlap(const Vec3& r, const Vec3& w, u128 sigma2, double guess) noexcept {
  const std::int64_t t = guessed_tick(r, w, sigma2, guess);
  return t > 0 ? t : first_overlap_d(r, w, sigma2);
}

template <std::size_t Dim>
void validate(const UnitsN<Dim>& u) {
  require(u.S >= 8 && u.S <= 60, "lattice units: S must be in [8, 60]");
  require(u.sigma == (std::int64_t{1} << u.S), "lattice units: sigma must be 2^S");
  for (std::size_t k = 0; k < Dim; ++k) {
    require(u.L[k] > 0 && u.L[k] < max_box_of<Dim>,
            Dim == 2 ? "lattice units: a box length must be in (0, 2^63 - 2^56) lattice units"
                     : "lattice units: a box length must be in (0, 2^62) lattice units in 3D");
    require(u.wall[k] || !u.bounce[k], "lattice units: a bounce-back axis must have walls");
    if (u.wall[k]) {
      require(u.L[k] > u.sigma + 2, "lattice units: a walled axis must be longer than one diameter");
    } else {
      require(static_cast<double>(u.L[k]) >= 4.5 * static_cast<double>(u.sigma),
              "lattice units: a periodic axis must be at least 4.5 diameters long");
    }
  }
  require(u.vmax >= 1 && u.vmax <= u.sigma / 256, "lattice units: vmax must be in [1, sigma / 256]");
  require(u.tick_bits >= min_tick_bits && u.tick_bits <= max_tick_bits, "lattice units: tick_bits must be in [16, 26]");
  require(u.cell_bits >= min_units_cell_bits && u.cell_bits <= max_units_cell_bits,
          "lattice units: cell_bits must be in [12, 20]");
  int fields = 0;
  for (std::size_t k = 0; k < Dim; ++k) {
    const std::int64_t g = u.gravity[k];
    if (g == 0) continue;
    ++fields;
    require(u.wall[k], "lattice units: gravity is allowed only along a walled axis (a periodic axis has no floor)");
    require(g % 2 == 0, "lattice units: gravity must be an even number of lattice units per tick^2");
    require(g >= -max_gravity && g <= max_gravity, "lattice units: |gravity| must be at most 2^36 lattice units per tick^2");
  }
  require(fields <= 1, "lattice units: gravity may act along one axis only");
  if (u.shear != 0) {
    require(!u.wall[0] && !u.wall[1], "lattice units: shear (Lees-Edwards) needs axes 0 (the flow) and 1 (the gradient) periodic");
    require(u.shear >= -u.vmax / 4 && u.shear <= u.vmax / 4, "lattice units: |shear| must be at most vmax / 4 lattice units per tick");
    require(fields == 0, "lattice units: shear and gravity together are not built yet");
    for (std::size_t k = 2; k < Dim; ++k)  // (its stall of the other axes would move the images across a gradient face)
      require(!u.bounce[k], "lattice units: shear with bounce-back walls is not built yet (specular walls on axis 2)");
    // the engine's cells along the flow and the gradient (cell_grid.hpp): a crossing pair's image
    // is the one nearest at its prediction only while the box is >= 9 cells along the flow
    const std::int64_t w = u.sigma + 2 * u.vmax + 2;
    require(u.L[0] / w >= 9 && u.L[1] / w >= 5, "lattice units: a sheared box must be at least 9 diameters along axis 0 (the flow) and 5 along axis 1 (the gradient)");
  }
}

template <std::size_t Dim>
UnitsN<Dim> choose_units_d(const std::array<double, Dim>& box, double D, double v_rms, const std::array<bool, Dim>& wall,
                           int tick_bits, int cell_bits, std::size_t n) {
  require(tick_bits == auto_tick_bits || (tick_bits >= min_tick_bits && tick_bits <= max_tick_bits),
          "lattice: tick_bits must be in [16, 26] (a typical particle moves 2^-tick_bits diameters per tick), or 0 (automatic)");
  require(cell_bits >= min_units_cell_bits && cell_bits <= max_units_cell_bits,
          "lattice: cell_bits must be in [12, 20] (2^cell_bits direction cells per turn)");
  require(std::isfinite(D) && D > 0.0, "lattice: the diameter must be positive and finite");
  require(std::isfinite(v_rms) && v_rms > 0.0, "lattice: the rms speed must be positive and finite (a gas at rest has no dynamics)");
  double longest = 0.0;
  for (double b : box) {
    require(std::isfinite(b) && b > 0.0, "lattice: box lengths must be positive and finite");
    longest = std::max(longest, b / D);
  }
  int S = 60;
  while (S >= 40 && std::ldexp(longest, S) >= 0x1p61) --S;
  require(S >= 40, [&] {
    return "lattice: a box of " + std::to_string(longest) +
           " diameters is too long for the lattice (at most 2^21 diameters per axis)";
  });
  if (tick_bits == auto_tick_bits) {
    tick_bits = std::clamp(S - velocity_bits, 16, 24);
    // sqrt(n) v_rms <= vmax / 2 = 2^(S-9): T >= 9 + log2(n) / 2 (a huge gas in a huge box)
    int t_n = 9;
    while (n > 0 && static_cast<double>(n) > std::ldexp(1.0, 2 * (t_n - 9))) ++t_n;
    tick_bits = std::min(std::max(tick_bits, t_n), max_tick_bits);
  }
  UnitsN<Dim> u;
  u.S = S;
  u.sigma = std::int64_t{1} << S;
  u.wall = wall;
  for (std::size_t k = 0; k < Dim; ++k) u.L[k] = std::llround(std::ldexp(box[k] / D, S));
  u.vmax = std::int64_t{1} << (S - 8);
  u.length_unit = std::ldexp(D, -S);
  u.tick = std::ldexp(D, -tick_bits) / v_rms;
  u.tick_bits = tick_bits;
  u.cell_bits = cell_bits;
  validate(u);
  return u;
}

template <std::size_t Dim>
u128 energy2(const UnitsN<Dim>& u, const std::vector<VecN<Dim>>& x, const std::vector<VecN<Dim>>& v) noexcept {
  u128 e = kinetic2(v);
  const int k = field_axis(u);
  if (k < 0) return e;
  const auto K = static_cast<std::size_t>(k);
  const std::int64_t g = u.gravity[K];
  const u128 m = static_cast<u128>(2 * (g < 0 ? -g : g));
  for (const VecN<Dim>& a : x) {
    const std::int64_t h = g < 0 ? a[K] : u.L[K] - a[K];  // inside [0, L]: >= 0
    const u128 s = e + m * static_cast<u128>(h < 0 ? 0 : h);
    if (s < e) return ~u128{0};
    e = s;
  }
  return e;
}

template <std::size_t Dim>
u128 kinetic2(const std::vector<VecN<Dim>>& v) noexcept {
  u128 e = 0;
  for (const VecN<Dim>& a : v) {
    const u128 s = e + norm2(a);
    if (s < e) return ~u128{0};  // saturates (only a state far beyond vmax can reach 2^128)
    e = s;
  }
  return e;
}

namespace {
// the overlap check of validate_state: a hash grid of cells of one diameter (keys in unsigned
// arithmetic: a collision of keys only adds candidates, every pair is decided exactly). With
// velocities (v non-null), a pair that overlaps at the clock but did not one tick earlier is a
// collision pending at this tick (a snapshot taken between two collisions of one tick), not an
// overlap. A mixture (radius non-empty): a pair's contact distance is the sum of its radii
// (at most sigma, the cells' width).
template <std::size_t Dim>
void check_overlaps(const UnitsN<Dim>& u, const std::vector<VecN<Dim>>& x, const std::vector<VecN<Dim>>* v,
                    const std::vector<std::int64_t>& radius, std::int64_t clock) {
  const std::int64_t delta = shear_offset(u, clock);
  const u128 sigma2 = static_cast<u128>(u.sigma) * static_cast<u128>(u.sigma);
  std::array<std::int64_t, Dim> nc{};
  for (std::size_t k = 0; k < Dim; ++k) nc[k] = std::max<std::int64_t>(1, u.L[k] / u.sigma);
  using Cell = std::array<std::int64_t, Dim>;
  auto key = [&](const Cell& c) {
    std::uint64_t h = 0;
    for (std::size_t k = 0; k < Dim; ++k) h = h * static_cast<std::uint64_t>(nc[k]) + static_cast<std::uint64_t>(c[k]);
    return h;
  };
  auto cell_of = [&](const VecN<Dim>& p) {
    Cell c;
    for (std::size_t k = 0; k < Dim; ++k)
      c[k] = std::min<std::int64_t>(nc[k] - 1, static_cast<std::int64_t>(static_cast<i128>(p[k]) * nc[k] / u.L[k]));
    return c;
  };
  std::unordered_map<std::uint64_t, std::vector<int>> grid;
  for (std::size_t i = 0; i < x.size(); ++i) grid[key(cell_of(x[i]))].push_back(static_cast<int>(i));
  int offsets = 1;
  for (std::size_t k = 0; k < Dim; ++k) offsets *= 3;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Cell c0 = cell_of(x[i]);
    // the pairs (i, j > i) with j in cell c: an overlap at the clock is refused unless pending
    auto pairs_in = [&](const Cell& c) {
      const auto it = grid.find(key(c));
      if (it == grid.end()) return;
      for (int j : it->second) {
        if (j <= static_cast<int>(i)) continue;
        const auto sj = static_cast<std::size_t>(j);
        const u128 s2 = radius.empty() ? sigma2 : contact2(radius[i] + radius[sj]);
        std::int64_t n = 0;  // j's image: n boxes up the gradient axis (offset n delta along axis 0; shear.hpp)
        VecN<Dim> r;
        if (u.shear != 0) {
          r = sheared_diff<Dim>(x[i], x[sj], u.L, u.wall, delta, n);
        } else {
          for (std::size_t k = 0; k < Dim; ++k) {
            const std::int64_t d = x[i][k] - x[sj][k];
            r[k] = u.wall[k] ? d : min_image(d, u.L[k]);
          }
        }
        if (norm2(r) >= s2) continue;
        if (v != nullptr) {  // pending at the clock: apart at the tick before (differences below 2^62 + 2^53)
          VecN<Dim> before;
          for (std::size_t k = 0; k < Dim; ++k) before[k] = r[k] - ((*v)[i][k] - (*v)[sj][k]);
          before[0] += n * u.shear;  // (the image's velocity: v_j + n shear along axis 0)
          if (norm2(before) >= s2) continue;
        }
        require(false, [&] {
          return "lattice: particles " + std::to_string(i) + " and " + std::to_string(j) +
                 (v != nullptr ? " overlap, and did one tick before (not a collision pending at the clock)" : " overlap");
        });
      }
    };
    for (int o = 0; o < offsets; ++o) {  // the 3^Dim neighbour cells, the last axis fastest
      Cell c = c0;
      bool skip = false, across = false;  // across: beyond a gradient face of a sheared box
      int d0 = 0;                          // the offset along axis 0
      for (int k = static_cast<int>(Dim) - 1, rest = o; k >= 0; --k, rest /= 3) {
        const int d = rest % 3 - 1;
        c[k] += d;
        if (k == 0) d0 = d;
        if (c[k] < 0 || c[k] >= nc[k]) {
          if (u.wall[k]) skip = true;
          if (k == 1 && u.shear != 0) across = true;
          c[k] = (c[k] + nc[k]) % nc[k];
        }
      }
      if (skip) continue;
      if (!across) {
        pairs_in(c);
        continue;
      }
      // Lees-Edwards: across a gradient face the images are offset along axis 0, so that row's
      // every cell along axis 0 is looked at (once, from the middle offset)
      if (d0 != 0) continue;
      for (std::int64_t a0 = 0; a0 < nc[0]; ++a0) {
        c[0] = a0;
        pairs_in(c);
      }
    }
  }
}
}  // namespace

template <std::size_t Dim>
void validate_state(const UnitsN<Dim>& u, const std::vector<VecN<Dim>>& x, const std::vector<VecN<Dim>>& v,
                    bool pending, const std::vector<std::int64_t>& radius, std::int64_t clock) {
  validate(u);
  require(x.size() == v.size(), "lattice: x (positions) and v (velocities) differ in length");
  require(!x.empty(), "lattice: no particles");
  require(x.size() < (std::size_t{1} << 30), "lattice: at most 2^30 particles");
  validate_radii(u, radius, x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const std::int64_t h = radius.empty() ? u.sigma / 2 : radius[i];
    for (std::size_t k = 0; k < Dim; ++k) {
      require(x[i][k] >= 0 && x[i][k] < u.L[k], [&] {
        return "lattice: particle " + std::to_string(i) + " is outside the box [0, L)";
      });
      if (u.wall[k]) {
        require(x[i][k] >= h && x[i][k] <= u.L[k] - h, [&] {
          return "lattice: particle " + std::to_string(i) + " overlaps a wall";
        });
      }
      require(v[i][k] >= -u.vmax && v[i][k] <= u.vmax, [&] {
        return "lattice: particle " + std::to_string(i) + " is faster than the lattice allows (vmax = 2^(S-8) per axis)";
      });
    }
  }
  // in a field, the energy with its potential: what a particle could reach falling to the floor
  const u128 e = energy2(u, x, v);
  require(e <= static_cast<u128>(u.vmax) * static_cast<u128>(u.vmax),
          field_axis(u) < 0 ? "lattice: the total kinetic energy allows a speed beyond vmax (too many particles for the velocity scale)"
                            : "lattice: the total energy (kinetic and potential) allows a speed beyond vmax (a field too strong for the box and the velocity scale)");
  check_overlaps(u, x, pending ? &v : nullptr, radius, clock);
}

template <std::size_t Dim>
void validate_radii(const UnitsN<Dim>& u, const std::vector<std::int64_t>& radius, std::size_t n) {
  if (radius.empty()) return;
  require(radius.size() == n, [&] {
    return "lattice: radius must have one entry per particle (" + std::to_string(n) + "), got " + std::to_string(radius.size());
  });
  const std::int64_t lo = min_radius(u);
  for (std::size_t i = 0; i < n; ++i)
    require(radius[i] >= lo && 2 * radius[i] <= u.sigma, [&] {
      return "lattice: particle " + std::to_string(i) + "'s radius " + std::to_string(radius[i]) +
             " is outside [sigma / 32, sigma / 2] = [" + std::to_string(lo) + ", " + std::to_string(u.sigma / 2) +
             "] lattice units (sigma, the largest diameter; diameters within a ratio of 16)";
    });
}

template <std::size_t Dim>
QuantizedN<Dim> quantize(const UnitsN<Dim>& u, const std::vector<double>& x, const std::vector<double>& v,
                         const std::vector<std::int64_t>& radius) {
  validate(u);
  require(x.size() == v.size() && x.size() % Dim == 0,
          Dim == 2 ? "lattice: positions and velocities must both be n x 2" : "lattice: positions and velocities must both be n x 3");
  const std::size_t n = x.size() / Dim;
  QuantizedN<Dim> q;
  q.x.resize(n);
  q.v.resize(n);
  const double vunit = u.length_unit / u.tick;  // float velocity of one lattice unit per tick
  double vr = 0.0;
  for (double a : v) vr += a * a;
  vr = std::sqrt(vr / std::max<std::size_t>(n, 1));
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = 0; k < Dim; ++k) {
      const double xf = x[Dim * i + k], vf = v[Dim * i + k];
      require(std::isfinite(xf) && std::isfinite(vf), "lattice: a position or velocity is not finite");
      const double xl = xf / u.length_unit, vl = vf / vunit;
      require(std::fabs(vl) <= static_cast<double>(u.vmax), [&] {
        return "lattice: particle " + std::to_string(i) + " is faster than the lattice allows (vmax = 2^(S-8) per axis)";
      });
      require(std::fabs(xl) < 0x1p62 && (u.wall[k] || std::fabs(xl) < static_cast<double>(u.L[k]) * 4.0), "lattice: a position is far outside the box");
      std::int64_t xi = std::llround(xl);
      xi = u.wall[k] ? xi : wrap(xi, u.L[k]);
      q.x[i][k] = xi;
      q.v[i][k] = std::llround(vl);
      const double ex = std::fabs(std::nearbyint(xl) - xl);  // the rounding, before the wrap
      q.max_position_error = std::max(q.max_position_error, ex / static_cast<double>(u.sigma));
      if (vr > 0.0) {
        q.max_velocity_error = std::max(q.max_velocity_error, std::fabs(static_cast<double>(q.v[i][k]) * vunit - vf) / vr);
      }
    }
  }
  validate_state(u, q.x, q.v, false, radius);
  return q;
}

// ---- cells ----

template <std::size_t Dim>
void CellGridN<Dim>::build(const UnitsN<Dim>& u, std::size_t n, std::int64_t wmin, int span, bool members) {
  if (wmin <= 0) wmin = u.sigma + 2 * u.vmax + 2;
  span_ = span == 2 ? 2 : 1;
  std::array<std::int64_t, Dim> ncl{};
  for (std::size_t k = 0; k < Dim; ++k) {
    L_[k] = u.L[k];
    wall_[k] = u.wall[k];
    ncl[k] = std::max<std::int64_t>(1, u.L[k] / wmin);
  }
  // at most ~4 cells per particle: a sparse gas takes wider cells (any width >= wmin works)
  const double cap = 4.0 * static_cast<double>(n) + 64.0;
  double total = static_cast<double>(ncl[0]);
  for (std::size_t k = 1; k < Dim; ++k) total *= static_cast<double>(ncl[k]);
  if (total > cap) {
    const double f = Dim == 2 ? std::sqrt(total / cap) : std::cbrt(total / cap);
    for (std::size_t k = 0; k < Dim; ++k)
      ncl[k] = std::max<std::int64_t>(1, static_cast<std::int64_t>(static_cast<double>(ncl[k]) / f));
  }
  if (u.shear != 0) {  // a sheared box keeps >= 9 cells along the flow, 5 along the gradient (shear.hpp)
    ncl[0] = std::max<std::int64_t>(ncl[0], std::min<std::int64_t>(9, u.L[0] / wmin));
    ncl[1] = std::max<std::int64_t>(ncl[1], std::min<std::int64_t>(5, u.L[1] / wmin));
  }
  for (std::size_t k = 0; k < Dim; ++k) {
    all_[k] = !u.wall[k] && ncl[k] < 2 * span_ + 3;
    nc_[k] = static_cast<int>(all_[k] ? 8 : ncl[k]);
    bounds_[k].resize(static_cast<std::size_t>(nc_[k]) + 1);
    for (int c = 0; c <= nc_[k]; ++c) bounds_[k][c] = static_cast<std::int64_t>(static_cast<i128>(c) * L_[k] / nc_[k]);
    scale_[k] = static_cast<double>(nc_[k]) / static_cast<double>(L_[k]);
    nbr_[k].assign(static_cast<std::size_t>(nc_[k]) * 8, 0);
    nbrn_[k].assign(static_cast<std::size_t>(nc_[k]), 0);
    nbs_[k].assign(static_cast<std::size_t>(nc_[k]) * 8, 0);
    for (int c = 0; c < nc_[k]; ++c) {
      const std::size_t at = static_cast<std::size_t>(c) * 8;
      nbrn_[k][static_cast<std::size_t>(c)] = static_cast<std::uint8_t>(axis_range(static_cast<int>(k), c, &nbr_[k][at]));
      // a neighbour reached across the end (periodic): below 0 its members are seen at x - L, so
      // a point of c sees them at x_c + L - x; past the end at x_c - L - x (for_neighbours_shifted)
      for (int i = 0; i < nbrn_[k][static_cast<std::size_t>(c)]; ++i) {
        const int d = nbr_[k][at + static_cast<std::size_t>(i)] - c;
        nbs_[k][at + static_cast<std::size_t>(i)] = all_[k] ? 0 : d > span_ ? L_[k] : d < -span_ ? -L_[k] : 0;
      }
    }
  }
  // disks with centres in a w0 x w1 cell, pairwise >= sigma apart: at most (ceil(w/sigma) + 1)^2
  // (spheres in 3D: the product over three axes)
  std::int64_t per = 1;
  for (std::size_t k = 0; k < Dim; ++k) per *= (L_[k] / nc_[k] + u.sigma) / u.sigma + 1;
  cap_ = static_cast<std::size_t>(std::min<std::int64_t>(per + 2, 8));
  std::size_t cells = 1;
  for (std::size_t k = 0; k < Dim; ++k) cells *= static_cast<std::size_t>(nc_[k]);
  if (!members) cells = 0, n = 0;
  slots_.assign(cells * static_cast<std::size_t>(cap_), -1);
  count_.assign(cells, 0);
  where_.assign(n, -1);
  slot_.assign(n, -1);
}

template <std::size_t Dim>
std::int64_t CellGridN<Dim>::exit_ticks(int k, int c, std::int64_t x0, std::int64_t v) const noexcept {
  if (v > 0) {
    if (wall_[k] && c + 1 == nc_[k]) return -1;  // the wall comes first
    return (boundary(k, c + 1) - x0 + v - 1) / v;
  }
  if (v < 0) {
    if (wall_[k] && c == 0) return -1;
    return (x0 - boundary(k, c)) / -v + 1;
  }
  return -1;
}

template <std::size_t Dim>
int CellGridN<Dim>::axis_range(int k, int c, int* out) const noexcept {
  const int nc = nc_[k];
  if (all_[k]) {
    for (int i = 0; i < nc; ++i) out[i] = i;
    return nc;
  }
  int n = 0;
  for (int d = -span_; d <= span_; ++d) {
    int a = c + d;
    if (a < 0 || a >= nc) {
      if (wall_[k]) continue;
      a = (a + nc) % nc;
    }
    bool seen = false;
    for (int i = 0; i < n; ++i) seen = seen || out[i] == a;
    if (!seen) out[n++] = a;
  }
  return n;
}

template <std::size_t Dim>
void CellGridN<Dim>::grow() {
  const std::size_t cap = 2 * cap_;
  std::vector<int> wider(count_.size() * cap, -1);
  for (std::size_t id = 0; id < count_.size(); ++id)
    for (std::int32_t k = 0; k < count_[id]; ++k) wider[id * cap + k] = slots_[id * cap_ + k];
  slots_.swap(wider);
  cap_ = cap;
}

template <std::size_t Dim>
void CellGridN<Dim>::insert(int p, int id) {
  if (static_cast<std::size_t>(count_[id]) >= cap_) grow();
  where_[p] = id;
  slot_[p] = count_[id];
  slots_[static_cast<std::size_t>(id) * cap_ + count_[id]++] = p;
}

template <std::size_t Dim>
void CellGridN<Dim>::remove(int p) {
  const int id = where_[p];
  const int s = slot_[p];
  const int last = slots_[static_cast<std::size_t>(id) * cap_ + --count_[id]];
  slots_[static_cast<std::size_t>(id) * cap_ + s] = last;
  slot_[last] = s;
  where_[p] = -1;
}

template <std::size_t Dim>
std::size_t CellGridN<Dim>::memory_bytes() const noexcept {
  std::size_t b = (slots_.capacity() + where_.capacity() + slot_.capacity()) * sizeof(int) + count_.capacity() * 4;
  for (std::size_t k = 0; k < Dim; ++k) b += nbr_[k].capacity() * sizeof(int) + nbrn_[k].capacity() + nbs_[k].capacity() * 8;
  return b;
}

// ---- the two dimensions ----
template void validate(const UnitsN<2>&);
template void validate(const UnitsN<3>&);
template UnitsN<2> choose_units_d<2>(const std::array<double, 2>&, double, double, const std::array<bool, 2>&, int, int,
                                     std::size_t);
template UnitsN<3> choose_units_d<3>(const std::array<double, 3>&, double, double, const std::array<bool, 3>&, int, int,
                                     std::size_t);
template u128 kinetic2(const std::vector<VecN<2>>&) noexcept;
template u128 kinetic2(const std::vector<VecN<3>>&) noexcept;
template u128 energy2(const UnitsN<2>&, const std::vector<VecN<2>>&, const std::vector<VecN<2>>&) noexcept;
template u128 energy2(const UnitsN<3>&, const std::vector<VecN<3>>&, const std::vector<VecN<3>>&) noexcept;
template void validate_state(const UnitsN<2>&, const std::vector<VecN<2>>&, const std::vector<VecN<2>>&, bool, const std::vector<std::int64_t>&, std::int64_t);
template void validate_state(const UnitsN<3>&, const std::vector<VecN<3>>&, const std::vector<VecN<3>>&, bool, const std::vector<std::int64_t>&, std::int64_t);
template void validate_radii(const UnitsN<2>&, const std::vector<std::int64_t>&, std::size_t);
template void validate_radii(const UnitsN<3>&, const std::vector<std::int64_t>&, std::size_t);
template QuantizedN<2> quantize(const UnitsN<2>&, const std::vector<double>&, const std::vector<double>&, const std::vector<std::int64_t>&);
template QuantizedN<3> quantize(const UnitsN<3>&, const std::vector<double>&, const std::vector<double>&, const std::vector<std::int64_t>&);
template class CellGridN<2>;
template class CellGridN<3>;

}  // namespace revcol::lattice
