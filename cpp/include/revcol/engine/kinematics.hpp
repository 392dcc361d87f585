// The kinematics seam of the event-driven engine: a particle's stored state, free flight,
// and the times of the events a particle can predict alone (pair contact, list renewal,
// wall). The float engine flies in double precision; an engine on integer ticks (a lattice
// engine) implements the same three questions in integers.
//
// Free flight. A particle's stored position x_i is where it was at its local time t_i:
// x(t) = x_i + v_i (t - t_i). Moving the stored state to t (advance) changes the stamp,
// which invalidates every prediction made with the old state.
//
// Pair contact. For a particle a and its listed b with image shift s (r = x_a - x_b - s),
// from the later of the two local times t_r: with b = r.w (w = v_a - v_b), c = r^2 - D^2 (D the
// pair's contact distance, (D_a + D_b) / 2 in a mixture) and
// disc = b^2 - w^2 c, an approaching pair (b < 0) meets at
//     t = t_r + c / (-b + sqrt(disc))
// the cancellation-free root (the textbook (-b - sqrt(disc)) / w^2 loses digits when
// c << b^2 / w^2). Seen from b's side (shift -s) r and w are negated exactly, so both
// partners compute the same bits; starting from the later local time keeps that true
// whichever was moved last. A pair closer than D (1 + group_tol) and not separating is
// "touching" (the engine's group gate).
//
// List renewal. A particle leaves the sphere of radius h around its list centre c at the
// later root of |x_i + v (t - t_i) - c| = h, again in cancellation-free form.
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace revcol::engine {

/// One particle's stored state, one cache line in 3D: the neighbour scan reads it whole.
template <int Dim>
struct alignas(Dim == 3 ? 64 : 8) Particle {
  double x[Dim] = {};       ///< position at local time t
  double v[Dim] = {};       ///< velocity
  double t = 0.0;           ///< local time
  std::uint64_t stamp = 0;  ///< changes whenever x, v or t change (event invalidation)
};

/// Free flight and event times in double precision (the float engine's kinematics).
template <int Dim>
struct FloatKinematics {
  using Vec = std::array<double, Dim>;  ///< a d-vector

  /// Coordinate k of p's position at time t.
  static double pos_at(const Particle<Dim>& p, int k, double t) { return p.x[k] + p.v[k] * (t - p.t); }

  /// Moves p's stored state to time t (free flight); changes its stamp.
  static void advance(Particle<Dim>& p, double t) {
    const double dt = t - p.t;
    for (int k = 0; k < Dim; ++k) p.x[k] += p.v[k] * dt;
    p.t = t;
    ++p.stamp;
  }

  /// Contact time t of a with b, r = x_a - x_b - s (s: the image offset of b as a sees
  /// it), from the later local time; false when the pair does not approach, misses, or (with
  /// a `limit`) provably meets after `limit`. `touching`: within contact_tol (r^2 - D^2 <=
  /// contact_tol) and not separating.
  /// Symmetric to the bit: pair_time(b, a, -s) gives the same t and `touching` (its r and w
  /// are these negated, exactly: round-to-nearest is symmetric), so a prediction works from
  /// its own particle's side and both partners still compute the same bits. (Measured: the
  /// id-order swap this replaced, or a branch skipping a's zero extrapolation, cost ~4% more
  /// instructions per collision than this one straight line.)
  /// The limit test comes before the square root: dt >= c / (-2 b), the skipped candidate's
  /// lower bound; it is rounded, so the caller keeps a margin of many ulps above any time it
  /// still needs (EngineImpl::prune_limit).
  /// Field: under a uniform field g (d components; Field false: none, g unread) both move on
  /// parabolas, so from the later local time the separation is still linear in time: r and w
  /// are taken at that time (x + v d + g d^2 / 2, v + g d) and the rest is unchanged.
  template <bool Field = false>
  [[gnu::always_inline]] static bool pair_time(const Particle<Dim>& a, const Particle<Dim>& b, const Vec& s,
                                               double sigma2, double contact_tol, double& t, bool& touching,
                                               double limit = std::numeric_limits<double>::infinity(),
                                               const double* g = nullptr) {
    const double ta = a.t, tb = b.t;
    const double tr = ta > tb ? ta : tb;
    const double da = tr - ta, db = tr - tb;
    double r[Dim], w[Dim];
    for (int k = 0; k < Dim; ++k) {
      const double va = a.v[k], vb = b.v[k];
      if constexpr (Field) {
        const double h = 0.5 * g[k];
        r[k] = ((a.x[k] + va * da + h * da * da) - (b.x[k] + vb * db + h * db * db)) - s[k];
        w[k] = (va + g[k] * da) - (vb + g[k] * db);
      } else {
        (void)g;
        r[k] = ((a.x[k] + va * da) - (b.x[k] + vb * db)) - s[k];
        w[k] = va - vb;
      }
    }
    // the sums start from their first term, not from 0.0 + it: the same values but for the
    // sign of a zero bb, which no test below and no hit's time can see (a hit has bb < 0)
    double bb = r[0] * w[0], r2 = r[0] * r[0], w2 = w[0] * w[0];
    for (int k = 1; k < Dim; ++k) {
      bb += r[k] * w[k];
      r2 += r[k] * r[k];
      w2 += w[k] * w[k];
    }
    const double c = r2 - sigma2;
    const double disc = bb * bb - w2 * c;
    // one branch, taken by few candidates, instead of one per test: whether a candidate
    // approaches is a coin toss that a branch predictor loses half the time (measured: 9%
    // more instructions, 1.25x the collisions per second at N = 10 976, phi = 0.45)
    touching = !(bb > 0.0) & (c <= contact_tol);  // in contact, approaching or at rest
    const bool hit = (bb < 0.0) & !(c > -2.0 * bb * (limit - tr)) & !(disc < 0.0);
    if (!hit) return false;
    double dt = c / (-bb + std::sqrt(disc));
    if (dt < 0.0) dt = 0.0;
    t = tr + dt;
    return true;
  }

  /// pair_time's tests for two partners at once (b0 with shift s0, b1 with s1), in two-lane
  /// vectors (GCC/Clang vector extensions: SSE2 on x86-64, NEON on arm64, plain code
  /// elsewhere). Each lane runs pair_time's operations in pair_time's order, so every value
  /// below has pair_time's bits; what is left per lane is the square root of a hit
  /// (finish()). Lane l: touching[l], hit[l] (with `limit`), and tr, c, bb, disc.
  struct Pair2 {
    bool touching[2], hit[2];
    double tr[2], c[2], bb[2], disc[2];
    /// Lane l's contact time, for a hit (pair_time's last lines).
    double finish(int l) const {
      double dt = c[l] / (-bb[l] + std::sqrt(disc[l]));
      if (dt < 0.0) dt = 0.0;
      return tr[l] + dt;
    }
    /// Lane l's hit test with a lower limit than the one tested (the scan's best improved
    /// in lane 0): pair_time's limit term, the same bits.
    bool still_hit(int l, double limit) const { return hit[l] && !(c[l] > -2.0 * bb[l] * (limit - tr[l])); }
  };
  [[gnu::always_inline]] static void pair_test2(const Particle<Dim>& a, const Particle<Dim>& b0,
                                                const Particle<Dim>& b1, const Vec& s0, const Vec& s1,
                                                double sigma2, double contact_tol, double limit, Pair2& out) {
    pair_test2(a, b0, b1, s0, s1, sigma2, sigma2, contact_tol, contact_tol, limit, out);
  }
  /// The same with each lane's own contact distance and tolerance (a mixture): lane l's
  /// sigma2_l, contact_tol_l.
  template <bool Field = false>
  [[gnu::always_inline]] static void pair_test2(const Particle<Dim>& a, const Particle<Dim>& b0,
                                                const Particle<Dim>& b1, const Vec& s0, const Vec& s1,
                                                double sigma2_0, double sigma2_1, double contact_tol_0,
                                                double contact_tol_1, double limit, Pair2& out,
                                                const double* g = nullptr) {
    typedef double v2d __attribute__((vector_size(16)));
    typedef long long v2l __attribute__((vector_size(16)));
    const v2d ta = {a.t, a.t}, tb = {b0.t, b1.t};
    const v2d tr = ta > tb ? ta : tb;  // lane-wise: pair_time's tr
    const v2d da = tr - ta, db = tr - tb;
    v2d r[Dim], w[Dim];
    for (int k = 0; k < Dim; ++k) {
      const v2d va = {a.v[k], a.v[k]}, vb = {b0.v[k], b1.v[k]};
      const v2d ax = {a.x[k], a.x[k]}, bx = {b0.x[k], b1.x[k]}, sk = {s0[k], s1[k]};
      if constexpr (Field) {  // pair_time's field terms, lane by lane
        const v2d gk = {g[k], g[k]}, h = {0.5 * g[k], 0.5 * g[k]};
        r[k] = ((ax + va * da + h * da * da) - (bx + vb * db + h * db * db)) - sk;
        w[k] = (va + gk * da) - (vb + gk * db);
      } else {
        (void)g;
        r[k] = ((ax + va * da) - (bx + vb * db)) - sk;
        w[k] = va - vb;
      }
    }
    v2d bb = r[0] * w[0], r2 = r[0] * r[0], w2 = w[0] * w[0];  // as pair_time: from the first term
    for (int k = 1; k < Dim; ++k) {
      bb += r[k] * w[k];
      r2 += r[k] * r[k];
      w2 += w[k] * w[k];
    }
    const v2d sig = {sigma2_0, sigma2_1}, tol = {contact_tol_0, contact_tol_1}, lim = {limit, limit};
    const v2d zero = {0.0, 0.0}, m2 = {-2.0, -2.0};
    const v2d c = r2 - sig;
    const v2d disc = bb * bb - w2 * c;
    const v2l touching = ~(bb > zero) & (c <= tol);
    const v2l hit = (bb < zero) & ~(c > m2 * bb * (lim - tr)) & ~(disc < zero);
    for (int l = 0; l < 2; ++l) {
      out.touching[l] = touching[l] != 0;
      out.hit[l] = hit[l] != 0;
      out.tr[l] = tr[l];
      out.c[l] = c[l];
      out.bb[l] = bb[l];
      out.disc[l] = disc[l];
    }
  }

  /// Time after p's local time at which p leaves the sphere of radius h (h2 = h^2) around
  /// the centre c; false when p is at rest. Outside and not entering (round-off at the
  /// surface): 0, renew now.
  [[gnu::always_inline]] static bool renewal_time(const Particle<Dim>& p, const double* c, double h2, double& tau) {
    double dd = 0.0, b = 0.0, vv = 0.0;
    for (int k = 0; k < Dim; ++k) {
      const double dk = p.x[k] - c[k], vk = p.v[k];
      dd += dk * dk;
      b += dk * vk;
      vv += vk * vk;
    }
    if (!(vv > 0.0)) return false;
    const double cc = h2 - dd;  // > 0: x inside the sphere
    const double disc = b * b + vv * cc;
    tau = 0.0;
    if (disc > 0.0) tau = b <= 0.0 ? (-b + std::sqrt(disc)) / vv : cc / (b + std::sqrt(disc));
    return true;
  }

  /// Time at which coordinate k of p reaches the plane x_k = at (v_k != 0).
  static double plane_time(const Particle<Dim>& p, int k, double at) { return p.t + (at - p.x[k]) / p.v[k]; }

  // ---- under a uniform field g (gravity; d components) ----

  /// Coordinate k of p's position at time t: x + v dt + g dt^2 / 2.
  static double pos_at(const Particle<Dim>& p, int k, double t, const double* g) {
    const double dt = t - p.t;
    return p.x[k] + p.v[k] * dt + 0.5 * g[k] * dt * dt;
  }
  /// Component k of p's velocity at time t: v + g dt.
  static double vel_at(const Particle<Dim>& p, int k, double t, const double* g) { return p.v[k] + g[k] * (t - p.t); }
  /// Moves p's stored state to time t on its parabola; changes its stamp.
  static void advance(Particle<Dim>& p, double t, const double* g) {
    const double dt = t - p.t;
    for (int k = 0; k < Dim; ++k) {
      p.x[k] += p.v[k] * dt + 0.5 * g[k] * dt * dt;
      p.v[k] += g[k] * dt;
    }
    p.t = t;
    ++p.stamp;
  }
  /// The first time after p's local time at which coordinate k (field component gk != 0)
  /// reaches the plane lo moving down or hi moving up (lo <= x <= hi); false: never. `up`:
  /// which. Each root is the one arriving (velocity -sqrt(disc) at lo, +sqrt(disc) at hi), in
  /// the form without cancellation: 2 D / (sqrt(disc) - v) when the particle heads for the
  /// plane, (sqrt(disc) + |v|) / |g| when it first moves away and the field brings it back.
  static bool wall_time(const Particle<Dim>& p, int k, double gk, double lo, double hi, double& tau, int& up) {
    const double x = p.x[k], v = p.v[k];
    bool found = false;
    const auto offer = [&](double t, int u) {
      if (!found || t < tau) {
        tau = t;
        up = u;
        found = true;
      }
    };
    const double dh = hi - x > 0.0 ? hi - x : 0.0, disc_h = v * v + 2.0 * gk * dh;  // up: x + v t + g t^2 / 2 = hi
    if (disc_h >= 0.0) {
      const double r = std::sqrt(disc_h);
      if (v > 0.0) offer(2.0 * dh / (v + r), 1);
      else if (gk > 0.0) offer((r - v) / gk, 1);
    }
    const double dl = x - lo > 0.0 ? x - lo : 0.0, disc_l = v * v - 2.0 * gk * dl;  // down: ... = lo
    if (disc_l >= 0.0) {
      const double r = std::sqrt(disc_l);
      if (v < 0.0) offer(2.0 * dl / (r - v), 0);
      else if (gk < 0.0) offer((r + v) / -gk, 0);
    }
    return found;
  }
  /// renewal_time under a field of magnitude gn > 0: a time by which p is still within h of c,
  /// conservative: at distance d0 now, its straight line stays within h - e and its fall from
  /// that line, gn t^2 / 2, within e = (h - d0) / 2. So the renewal comes no later than the
  /// parabola leaves the list's reach (0: at or beyond it now).
  static bool renewal_time(const Particle<Dim>& p, const double* c, double h, double gn, double& tau) {
    double d2 = 0.0;
    for (int k = 0; k < Dim; ++k) d2 += (p.x[k] - c[k]) * (p.x[k] - c[k]);
    const double e = 0.5 * (h - std::sqrt(d2));
    tau = 0.0;
    if (!(e > 0.0)) return true;
    double t_line = std::numeric_limits<double>::infinity();
    const bool moving = renewal_time(p, c, (h - e) * (h - e), t_line);
    const double t_fall = std::sqrt(2.0 * e / gn);
    tau = moving && t_line < t_fall ? t_line : t_fall;
    return true;
  }
};

}  // namespace revcol::engine
