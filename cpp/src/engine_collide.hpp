// EngineImpl's collisions: a pair through the operator Op, a group through ExactCollision,
// the walls a colliding particle touches (the wall-mask log, revcol/engine/logs.hpp), and
// the random numbers they draw.
// The protocol (ties, groups, walls at a collision, the exact-pre log) is described in
// revcol/engine/engine.hpp. Private to cpp/src, included after engine_impl.hpp.
#pragma once
#include <stdexcept>

#include "engine_impl.hpp"

namespace revcol::engine::detail {

template <int Dim, PairOperator Op>
struct EngineImpl<Dim, Op>::Group {
  int n = 0;
  int id[kMaxGroup];  // the members' slots (bk_[slot].id their ids)
  Vec off[kMaxGroup];
  int ne = 0;
  int ea[3 * kMaxGroup], eb[3 * kMaxGroup];  // edges as member indices
  bool overflow = false;
};

// Members of the contact component of (a, b) at time t, each with its image offset: every
// particle whose contact with a member is closed within group_tol and approaching or at
// rest, found through the members' lists.
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::gather(int a, int b, const Vec& s, double t, Group& g) const {
  g.n = 2;
  g.id[0] = a;
  g.off[0] = Vec{};
  g.id[1] = b;
  g.off[1] = s;  // x_b + s is b's image next to a
  g.ne = 1;
  g.ea[0] = 0;
  g.eb[0] = 1;
  for (int m = 0; m < g.n && !g.overflow; ++m) {
    const int im = g.id[m];
    Vec pm;
    for (int k = 0; k < Dim; ++k) pm[k] = pos_at(im, k, t);
    for_neighbours(im, [&](int j, const Vec& sh) {
      if (g.overflow) return;
      double r2 = 0.0, rw = 0.0;
      double r[Dim];
      for (int k = 0; k < Dim; ++k) {
        r[k] = pm[k] - (pos_at(j, k, t) + sh[k]);
        r2 += r[k] * r[k];
      }
      const double s2 = sigma2(im, j);
      if (!(r2 - s2 <= contact_tol(s2))) return;
      for (int k = 0; k < Dim; ++k) rw += r[k] * (vel_at(im, k, t) - vel_at(j, k, t));
      if (!(rw <= 0.0)) return;
      int q = -1;
      for (int u = 0; u < g.n; ++u)
        if (g.id[u] == j) q = u;
      if (q < 0) {
        if (g.n == kMaxGroup) {
          g.overflow = true;
          return;
        }
        q = g.n++;
        g.id[q] = j;
        for (int k = 0; k < Dim; ++k) g.off[q][k] = g.off[m][k] + sh[k];
      } else {
        // the same image? (a component wrapping around the box is not one contact set)
        for (int k = 0; k < Dim; ++k)
          if (g.off[q][k] != g.off[m][k] + sh[k]) return;
      }
      for (int e = 0; e < g.ne; ++e)
        if ((g.ea[e] == m && g.eb[e] == q) || (g.ea[e] == q && g.eb[e] == m)) return;
      if (g.ne == 3 * kMaxGroup) {
        g.overflow = true;
        return;
      }
      g.ea[g.ne] = m;
      g.eb[g.ne] = q;
      ++g.ne;
    });
  }
}

// ---- random numbers ------------------------------------------------------------------------

// CLCG4 only: each stream's state, from the family and the draws taken (drawn): a
// modular power of the multipliers per stream.
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::make_generators() {
  clcg_.clear();
  if (cfg_.generator != Generator::clcg4) return;
  clcg_ = rng::generator_traits<rng::CLCG4>::family(cfg_.seed, stream_count());
  for (std::size_t i = 0; i < clcg_.size(); ++i) {
    if (drawn(static_cast<int>(i)) == 0) continue;
    rng::CLCG4::State st = clcg_[i].state();
    for (int j = 0; j < 4; ++j)
      st[j] = rng::clcg4_detail::mulmod(
          st[j], rng::clcg4_detail::powmod(rng::CLCG4::multiplier[j], drawn(static_cast<int>(i)), rng::CLCG4::modulus[j]),
          rng::CLCG4::modulus[j]);
    clcg_[i].set_state(st);
  }
}

// One number from a stream: Philox at the stream's counter, or CLCG4 next / prev.
template <int Dim, PairOperator Op>
double EngineImpl<Dim, Op>::draw(int stream, std::uint64_t& count, bool reversed) {
  if (cfg_.generator == Generator::clcg4) {
    if (reversed) {
      --count;
      return clcg_[stream].prev();
    }
    ++count;
    return clcg_[stream].next();
  }
  const rng::Philox p({static_cast<std::uint32_t>(stream), cfg_.seed}, 0);
  if (reversed) return p.at(--count);
  return p.at(count++);
}

// ---- walls at a collision's instant (the wall-mask log) -----------------------------------

// Reflects i on the walls it meets (touches and approaches) at this instant, by the corner
// rule of Boundaries::reflect (each wall's own reflection, revcol/engine/boundary.hpp);
// returns the mask applied, which the wall-mask log keeps.
template <int Dim, PairOperator Op>
Reflection EngineImpl<Dim, Op>::touch_walls(int i) {
  if (!box_.any_walls()) return 0;  // periodic on every axis: nothing to touch (the common gas)
  Vec x, v;
  for (int k = 0; k < Dim; ++k) {
    x[k] = p_[i].x[k];
    v[k] = p_[i].v[k];
  }
  const Reflection mask = box_.reflect(x, v, radius(i));
  if (mask != 0) set_velocity(i, v, mask);
  return mask;
}
// Re-applies a logged mask to i (each reflection is its own inverse).
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::flip_mask(int i, Reflection mask) {
  if (mask == 0) return;
  Vec v;
  for (int k = 0; k < Dim; ++k) v[k] = p_[i].v[k];
  apply<Dim>(mask, v);
  set_velocity(i, v, mask);
}
// Sets i's velocity to v, the result of the reflection `mask`, and counts it (reflections()).
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::set_velocity(int i, const Vec& v, Reflection mask) {
  for (int k = 0; k < Dim; ++k) p_[i].v[k] = v[k];
  counters_.wall_events += static_cast<std::uint64_t>(reflections(mask));
  if (obs_) [[unlikely]] note_wall(i);
}
// The mask a standalone wall event of i on axis k applies at time t (i's position then):
// Boundaries::reflect_at, computed on a copy of the velocity.
template <int Dim, PairOperator Op>
Reflection EngineImpl<Dim, Op>::wall_mask(int i, int k, double t) const {
  Vec x, v;
  for (int j = 0; j < Dim; ++j) {
    x[j] = pos_at(i, j, t);
    v[j] = p_[i].v[j];
  }
  return box_.reflect_at(k, x, v, radius(i));
}
// Whether the W2 mask of wall-log member slot m holds every reflection of `mask`.
template <int Dim, PairOperator Op>
bool EngineImpl<Dim, Op>::w2_covers(long m, Reflection mask) const {
  const std::uint64_t bits = std::uint64_t{mask} << 8;
  return (wlog_.mask(m) & bits) == bits;
}
template <int Dim, PairOperator Op>
bool EngineImpl<Dim, Op>::touches_wall(int i) const {
  for (int k = 0; k < Dim; ++k)
    if (box_.touches(k, p_[i].x[k], radius(i))) return true;
  return false;
}

// ---- pairs --------------------------------------------------------------------------------

// A collision of a and b predicted at t (stamps checked). Returns whether one happened.
template <int Dim, PairOperator Op>
bool EngineImpl<Dim, Op>::collide(int a, int b, double t, bool reversed) {
  if (bk_[a].id > bk_[b].id) std::swap(a, b);  // a: the smaller id (slots a, b)
  const Vec s = nl_.pair_shift(a, b);
  // The gather scans two neighbourhoods; it runs only when a group is possible: a
  // neighbour was within the contact tolerance at a prediction (resting contacts), or a
  // second collision of a or b was predicted within a relative kTieWindow of t (ties).
  const double window = t + kTieWindow * (std::fabs(t) + 1.0);
  const Book &ba = bk_[a], &bb = bk_[b];
  const bool maybe = cfg_.force_group_search || ba.touching || bb.touching || ba.second <= window ||
                     bb.second <= window;
  if (cfg_.groups && maybe) {
    Group g;
    gather(a, b, s, t, g);
    if (g.n > 2 || g.overflow) {
      if (!g.overflow && equal_masses(g) && group_collide(g, t, reversed)) return true;
      ++counters_.group_fallbacks;  // (the group operator collides equal masses only)
    }
  }
  nl_.prefetch_list(a);  // both are predicted after the operator, whose work hides the loads
  nl_.prefetch_list(b);
  advance(a, t);
  advance(b, t);
  const std::int64_t wkey = reversed ? bk_[a].netc - 1 : bk_[a].netc;
  Reflection w1[2] = {0, 0}, w2[2] = {0, 0};
  if (reversed) {
    wlog_.pop(bk_[a].id, wkey, 2, w1, w2);
    flip_mask(a, w2[0]);
    flip_mask(b, w2[1]);
  } else {
    w1[0] = touch_walls(a);
    w1[1] = touch_walls(b);
  }
  Vec r;
  double rw = 0.0;
  for (int k = 0; k < Dim; ++k) {
    r[k] = (p_[a].x[k] - p_[b].x[k]) - s[k];
    rw += r[k] * (p_[a].v[k] - p_[b].v[k]);
  }
  if (!(rw < 0.0)) {  // grazing: round-off left no approach at contact
    ++counters_.grazing_skipped;
    repredict(a);
    repredict(b);
    return false;
  }
  PairV<Dim> in;
  for (int k = 0; k < Dim; ++k) {
    in.i[k] = p_[a].v[k];
    in.j[k] = p_[b].v[k];
  }
  // Unequal masses: the operator (of equal masses) acts on the relative velocity w in the
  // centre-of-mass frame, (w/2, -w/2); the centre-of-mass velocity V stays, and the members
  // take V + m_b/M w', V - m_a/M w' (the elastic collision of any masses: the law of w' given
  // w and the normal does not depend on them). Equal masses go straight through (same bits).
  const bool heavy = !mass_.empty() && mass_[static_cast<std::size_t>(a)] != mass_[static_cast<std::size_t>(b)];
  Vec vcm{};
  if (heavy) [[unlikely]] in = to_relative(in, a, b, vcm);
  PairV<Dim> out;
  try {
    out = apply_pair(in, r, a, reversed);
  } catch (const InvalidArgument&) {
    // Only a reversed run can get here: a post state this operator cannot reverse (the
    // rare log is empty, or the state fails validation) means the reversed trajectory has
    // left the forward one (beyond the round-off horizon). The pair reflects specularly,
    // drawing nothing, and the failure is counted: the restored state is not the start.
    if (!reversed) throw;
    ++counters_.reverse_failures;
    trace_.diverge(net_, Divergence::operator_);
    out = Specular<Dim>::reflect(in, r);
  }
  if (heavy) [[unlikely]] out = from_relative(out, a, b, vcm);
  for (int k = 0; k < Dim; ++k) {
    p_[a].v[k] = out.i[k];
    p_[b].v[k] = out.j[k];
  }
  if (obs_) [[unlikely]] note_pair(a, b);
  if (reversed) {
    flip_mask(a, w1[0]);
    flip_mask(b, w1[1]);
  } else {
    w2[0] = touch_walls(a);
    w2[1] = touch_walls(b);
    if (w1[0] | w1[1] | w2[0] | w2[1] || touches_wall(a) || touches_wall(b)) {
      const int ids[2] = {bk_[a].id, bk_[b].id};
      const std::int64_t nc[2] = {bk_[a].netc, bk_[b].netc};
      wlog_.push(ids[0], wkey, t, 2, ids, nc, w1, w2);
    }
  }
  finish_collision(a, reversed);
  finish_collision(b, reversed);
  ++counters_.pair_collisions;
  const int ids[2] = {bk_[a].id, bk_[b].id};
  trace_collision(ids, 2, reversed);
  const int slots[2] = {a, b};
  validate_collision(slots, 2);
  repredict(a);
  repredict(b);
  return true;
}

// Unequal masses: (v_a, v_b) -> (w/2, -w/2), w = v_a - v_b, and V = (m_a v_a + m_b v_b) / M.
template <int Dim, PairOperator Op>
PairV<Dim> EngineImpl<Dim, Op>::to_relative(const PairV<Dim>& v, int a, int b, Vec& vcm) const {
  const double ma = mass(a), mb = mass(b), m = ma + mb;
  PairV<Dim> out;
  for (int k = 0; k < Dim; ++k) {
    vcm[k] = (ma * v.i[k] + mb * v.j[k]) / m;
    const double w = v.i[k] - v.j[k];
    out.i[k] = 0.5 * w;
    out.j[k] = -0.5 * w;
  }
  return out;
}
// ... and back: w' = u_a - u_b, v_a' = V + m_b / M w', v_b' = V - m_a / M w'.
template <int Dim, PairOperator Op>
PairV<Dim> EngineImpl<Dim, Op>::from_relative(const PairV<Dim>& u, int a, int b, const Vec& vcm) const {
  const double ma = mass(a), mb = mass(b), m = ma + mb;
  PairV<Dim> out;
  for (int k = 0; k < Dim; ++k) {
    const double w = u.i[k] - u.j[k];
    out.i[k] = vcm[k] + (mb / m) * w;
    out.j[k] = vcm[k] - (ma / m) * w;
  }
  return out;
}
// Whether a group's members all have one mass (the group operator's case).
template <int Dim, PairOperator Op>
bool EngineImpl<Dim, Op>::equal_masses(const Group& g) const {
  for (int u = 1; u < g.n; ++u)
    if (mass(g.id[u]) != mass(g.id[0])) return false;
  return true;
}

// Forward: Op's forward; reversed (velocities negated): -Op.reverse(-v), its draws stepped
// back in the opposite order, from the stream of the particle in slot s. An operator that
// needs the exact-pre log keeps a singular pre state whose cell centre is off by more than
// 1e-10, keyed by (stream, counter before the draws), and the reversed collision restores it.
template <int Dim, PairOperator Op>
PairV<Dim> EngineImpl<Dim, Op>::apply_pair(const PairV<Dim>& in, const Vec& r, int s, bool reversed) {
  const int stream = stream_of(s);
  std::uint64_t& count = drawn_at(s);
  PairV<Dim> arg = in;
  if (reversed)
    for (int k = 0; k < Dim; ++k) {
      arg.i[k] = -arg.i[k];
      arg.j[k] = -arg.j[k];
    }
  std::array<double, (Op::draws > 0 ? Op::draws : 1)> g{};
  if (reversed)
    for (int k = Op::draws - 1; k >= 0; --k) g[k] = draw(stream, count, true);
  else
    for (int k = 0; k < Op::draws; ++k) g[k] = draw(stream, count, false);
  PairV<Dim> out;
  if (reversed) {
    out = op_.reverse(arg, r, g.data(), log_);
    if constexpr (Op::needs_exact_pre_log) pre_.pop(stream, count, out.i.data(), out.j.data());
    for (int k = 0; k < Dim; ++k) {
      out.i[k] = -out.i[k];
      out.j[k] = -out.j[k];
    }
  } else {
    out = op_.forward(arg, r, g.data(), log_);
    if constexpr (Op::needs_exact_pre_log) {
      static_assert(ExactPreLogged<Op>, "an operator that needs the exact-pre log gives singular() and quantize()");
      if (op_.singular(arg, r)) {
        const PairV<Dim> q = op_.quantize(arg, r);
        if (ExactPreLog::off_by(arg.i.data(), q.i.data(), Dim) || ExactPreLog::off_by(arg.j.data(), q.j.data(), Dim))
          pre_.push(stream, count - Op::draws, arg.i.data(), arg.j.data(), Dim);
      }
    }
  }
  return out;
}

// ---- groups -------------------------------------------------------------------------------

// A group of n > 2 particles: members sorted by id, contacts oriented from the larger id to
// the smaller, ExactCollision drawing (n-1)d-1 numbers from the stream of the smallest id.
// Returns false (nothing changed) when the operator refuses the group.
template <int Dim, PairOperator Op>
bool EngineImpl<Dim, Op>::group_collide(Group& g, double t, bool reversed) {
  int order[kMaxGroup] = {};
  for (int u = 0; u < g.n; ++u) order[u] = u;
  for (int u = 1; u < g.n; ++u)  // insertion sort by id (n <= 8)
    for (int w = u; w > 0 && bk_[g.id[order[w]]].id < bk_[g.id[order[w - 1]]].id; --w) std::swap(order[w], order[w - 1]);
  const int n = g.n;
  const int first = g.id[order[0]];  // the slot of the smallest id
  const int first_id = bk_[first].id;
  const std::int64_t wkey = reversed ? bk_[first].netc - 1 : bk_[first].netc;
  Reflection w1[kMaxGroup] = {}, w2[kMaxGroup] = {};
  for (int u = 0; u < n; ++u) advance(g.id[order[u]], t);
  // W1 reaches the observer only once the operator accepts the group (group_operator tells
  // it then): a refused group undoes W1, and the pair that follows reflects for real
  Observer* const obs = obs_;
  obs_ = nullptr;
  if (reversed) {
    wlog_.pop(first_id, wkey, n, w1, w2);
    for (int u = 0; u < n; ++u) flip_mask(g.id[order[u]], w2[u]);
  } else {
    for (int u = 0; u < n; ++u) w1[u] = touch_walls(g.id[order[u]]);
  }
  int sl[kMaxGroup], ids[kMaxGroup];  // the members' slots and ids, in id order
  std::int64_t nc[kMaxGroup];  // the members' net counts before this collision (wall-log keys)
  for (int u = 0; u < n; ++u) {
    sl[u] = g.id[order[u]];
    ids[u] = bk_[sl[u]].id;
    nc[u] = bk_[sl[u]].netc;
  }
  obs_ = obs;
  if (!group_operator(g, order, t, reversed, w1)) {
    // refused before any draw was consumed (validation comes first): undo the walls
    obs_ = nullptr;
    for (int u = 0; u < n; ++u) {
      const Reflection m = reversed ? w2[u] : w1[u];
      flip_mask(sl[u], m);
      // neither the reflection nor its undoing happened: take both out of the counter
      counters_.wall_events -= 2 * static_cast<std::uint64_t>(reflections(m));
    }
    obs_ = obs;
    if (reversed && (std::any_of(w1, w1 + n, [](Reflection q) { return q != 0; }) ||
                     std::any_of(w2, w2 + n, [](Reflection q) { return q != 0; })))
      wlog_.push(first_id, wkey, t, n, ids, nc, w1, w2);  // put the masks back
    return false;
  }
  for (int u = 0; u < n; ++u) {
    if (reversed) flip_mask(sl[u], w1[u]);
    else w2[u] = touch_walls(sl[u]);
    finish_collision(sl[u], reversed);
  }
  if (!reversed) {
    bool any = false;
    for (int u = 0; u < n; ++u) any = any || w1[u] != 0 || w2[u] != 0 || touches_wall(sl[u]);
    if (any) {
      wlog_.push(first_id, wkey, t, n, ids, nc, w1, w2);  // the counts before this collision
    }
  }
  ++counters_.group_collisions;
  counters_.group_particles += static_cast<std::uint64_t>(n);
  trace_collision(ids, n, reversed);
  validate_collision(sl, n);
  for (int u = 0; u < n; ++u) repredict(g.id[u]);
  return true;
}

// The group's velocities through ExactCollision (members in id order): forward, or
// -reverse(-v) with the draws stepped back; the exact-pre log for resting contacts. Sets
// the members' velocities; returns false, nothing changed, when the operator refuses.
// Observing, an accepted group first tells the observer its W1 reflections (masks w1, in
// id order; group_collide held them back), then the collision.
template <int Dim, PairOperator Op>
bool EngineImpl<Dim, Op>::group_operator(Group& g, const int* order, double t, bool reversed, const Reflection* w1) {
  const int n = g.n;
  int rank[kMaxGroup];
  for (int u = 0; u < n; ++u) rank[order[u]] = u;
  struct E {
    int i, j, mi, mj;
  };
  std::vector<E> edges;
  edges.reserve(g.ne);
  for (int e = 0; e < g.ne; ++e) {
    int p = g.ea[e], q = g.eb[e];
    if (bk_[g.id[p]].id > bk_[g.id[q]].id) std::swap(p, q);
    edges.push_back({rank[p], rank[q], p, q});
  }
  std::sort(edges.begin(), edges.end(), [](const E& x, const E& y) { return x.i != y.i ? x.i < y.i : x.j < y.j; });
  std::vector<Contact> contacts;
  std::vector<double> normals;
  for (const E& e : edges) {
    contacts.push_back({e.i, e.j});
    for (int k = 0; k < Dim; ++k) {
      const double xi = pos_at(g.id[e.mi], k, t) + g.off[e.mi][k];
      const double xj = pos_at(g.id[e.mj], k, t) + g.off[e.mj][k];
      normals.push_back(xi - xj);
    }
  }
  std::vector<double> pre(n * Dim), post(n * Dim);
  for (int u = 0; u < n; ++u)
    for (int k = 0; k < Dim; ++k) {
      const double vk = p_[g.id[order[u]]].v[k];
      pre[u * Dim + k] = reversed ? -vk : vk;
    }
  const int stream = stream_of(g.id[order[0]]);
  std::uint64_t& count = drawn_at(g.id[order[0]]);
  try {
    const ExactCollision op(n, Dim, contacts, normals, cfg_.law, cfg_.bits);
    const int m = op.draws();
    std::vector<double> gs(m);
    if (reversed) {
      op.check_post(pre.data());
      for (int k = m - 1; k >= 0; --k) gs[k] = draw(stream, count, true);
      op.reverse(pre.data(), gs.data(), post.data(), log_);
      pre_.pop(stream, count, post.data(), nullptr);
    } else {
      op.check_pre(pre.data());
      const std::uint64_t key = count;
      for (int k = 0; k < m; ++k) gs[k] = draw(stream, count, false);
      op.forward(pre.data(), gs.data(), post.data(), log_);
      // resting contacts and aligned velocities put the pre state on a singular set of
      // the chart (a vertex of T, eta = 0), where its cell spans ~2^-K/2: keep it exactly
      std::vector<double> q(n * Dim);
      op.quantize(pre.data(), q.data());
      if (ExactPreLog::off_by(pre.data(), q.data(), n * Dim)) pre_.push(stream, key, pre.data(), nullptr, n * Dim);
    }
  } catch (const InvalidArgument&) {
    return false;
  }
  if (obs_ && !reversed) {  // image-consistent positions: the group's virial (observe.hpp)
    int ids[kMaxGroup];
    double xs[kMaxGroup * Dim];
    for (int u = 0; u < n; ++u)
      if (w1[u] != 0) note_wall(g.id[order[u]]);  // the velocities are still those after W1
    for (int u = 0; u < n; ++u) {
      ids[u] = bk_[g.id[order[u]]].id;
      for (int k = 0; k < Dim; ++k) xs[u * Dim + k] = pos_at(g.id[order[u]], k, t) + g.off[order[u]][k];
    }
    obs_->group(t, n, ids, xs, post.data());
  }
  for (int u = 0; u < n; ++u) {
    const int id = g.id[order[u]];
    for (int k = 0; k < Dim; ++k) p_[id].v[k] = reversed ? -post[u * Dim + k] : post[u * Dim + k];
  }
  return true;
}

// ---- the collision trace (revcol/engine/trace.hpp) -----------------------------------------

// Adds (forward) or removes (reversed) the signature of the collision just done or undone
// (its members, ascending).
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::trace_collision(const int* ids, int n, bool reversed) {
  trace_.apply(CollisionTrace::signature(ids, n), reversed);
}

// At a grid point of the trace: forward, keep the trace's sum; reversed, compare it, and at a
// grid point proper also the conserved quantities.
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::trace_point(bool reversed) {
  const double t = reversed ? -clock_ : clock_;  // a reversed run's clock is negated (flip)
  if (!reversed) {
    trace_.record(net_, t);
    return;
  }
  if (trace_.check(net_, t)) check_conservation();
}

// Energy, and momentum on periodic axes when no wall is a bounce wall (specular walls keep the
// other components), against their start values: a change beyond CollisionTrace::kConserveTol
// is a divergence at the current net count (round-off keeps both within ~1e-12 over 10^9
// collisions; a log entry restored into the wrong collision moves them by O(1)).
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::check_conservation() {
  if (trace_.reason() != Divergence::none || !(e0_ > 0.0)) return;
  std::array<double, 3> p{};
  const double e = energy_momentum(p);
  if (!(std::fabs(e - e0_) <= CollisionTrace::kConserveTol * e0_)) {
    trace_.diverge(net_, Divergence::energy);
    return;
  }
  bool bounce = false;
  for (int k = 0; k < Dim; ++k) bounce = bounce || cfg_.boundary[k] == Boundary::bounce;
  if (bounce) return;
  const double scale = std::sqrt(2.0 * e0_ * total_mass_);
  const double sign = rev_ ? -1.0 : 1.0;  // inside a reversed run the velocities are negated (flip)
  for (int k = 0; k < Dim; ++k)
    if (cfg_.boundary[k] == Boundary::periodic &&
        !(std::fabs(sign * p[k] - p0_[k]) <= CollisionTrace::kConserveTol * scale)) {
      trace_.diverge(net_, Divergence::momentum);
      return;
    }
}

// ---- observation (revcol/engine/observe.hpp) ------------------------------------------------

// A new observer from the state at the clock (in a field: the velocities there); built
// before the old one goes, so a bad config changes nothing.
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::observe(const ObserveConfig& c) {
  std::array<bool, 3> walls{};
  for (int k = 0; k < Dim; ++k) walls[k] = box_.walls(k);
  auto o = std::make_unique<Observer>(c, Dim, positions(), velocities(), clock_, cfg_.box, walls, cfg_.diameter);
  describe_particles(*o);  // masses (m v^2, m Delta v) and species
  observer_ = std::move(o);
  obs_ = observer_.get();
}
// The hooks, out of line and cold, called after the velocities changed with as little as
// possible live (the observer keeps the velocities before and the positions): a run that
// does not observe pays the pointer test only (measured: docs/physics.md).
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::note_wall(int i) {
  obs_->wall(clock_, bk_[i].id, p_[i].v);
}
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::note_pair(int a, int b) {
  obs_->template pair_d<Dim>(clock_, bk_[a].id, bk_[b].id, p_[a].v, p_[b].v);
}
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::stop_observing() {
  if (obs_) obs_->sync(clock_);
  obs_ = nullptr;
}

}  // namespace revcol::engine::detail
