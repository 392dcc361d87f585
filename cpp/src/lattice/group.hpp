// The lattice engine's group collisions: a third body within one tick (LATTICE.md §4). The group,
// its specular resolution or bounce back, the post state's checks, the log entry, the reverse.
// Part of BasicEngine (revcol/lattice/engine_core.hpp, which declares it and explains the
// design); included by engine_impl.hpp, which the instantiating sources include.
#pragma once
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "revcol/lattice/engine_core.hpp"

namespace revcol::lattice {

// ---- a third body within one tick: group collisions (LATTICE.md §4, docs/lattice.md) ----
// When no draw is acceptable (a third body k is met within the tick, so every post state of the
// pair overlaps it or ties with it), the group G = {i, j}, closed under "a member's pre line
// overlaps a body at tick a", collides as one. Every member stays at its tick a-1 position at
// tick a (a stall of one tick), so the members' positions at a never overlap each other.
//   Resolve (first choice): the members' velocities go through sequential specular collisions
//   of the touching pairs (normal along the centres at a-1) until no touching pair approaches,
//   rounded to integers with the momentum kept exactly; the exact pre velocities go to the log.
//   For one pair this is the specular collision, and its reversed lines overlap at a-1 exactly
//   where the pre lines did at a, so the reverse meets the group at the same tick.
//   Bounce (fallback): every member's velocity negated (an involution: nothing but the members
//   is logged); the group's momentum is reversed.
// Either way a body that the post state would overlap at a, or whose point at a-1 the new lines
// would overlap, joins G (up to 16 members); a resolve whose reversed lines meet no member pair
// at a-1 (the reverse would not see it) or that breaks vmax falls back to the bounce. The post
// state must meet the invariants against bodies outside G and the walls, otherwise the collision
// is an error, nothing changed. The draws tried are logged with the entry.
// The group closed under "a member's pre line at a overlaps a body at a", ascending.
template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::group_of(int i, int j, std::int64_t a) const -> std::vector<int> {
  std::vector<int> g{i, j};
  auto member = [&](int q) { return std::find(g.begin(), g.end(), q) != g.end(); };
  for (std::size_t m = 0; m < g.size(); ++m) {
    const Vec xa = pos(g[m], a);
    near(g[m], [&](int q) {
      if (!member(q) && overlap_at(xa, pos(q, a), g[m], q, a)) g.push_back(q);
    });
  }
  return g;
}

// A group's stall (shear.hpp): the members' points at a from their points x at a-1, at rest in
// the frame of the first (the lowest id): a member whose image next to it is n boxes up moves by
// -n s along the flow, so no two members' relative vectors change (their points at a overlap no
// more than at a-1). Without shear, or within one box, the a-1 points themselves. Returns each
// member's n (empty without shear): a bounce negates the velocities in that frame too, v -> -v +
// 2 n s. The reverse takes the same rules in its frame (-s, the same n), which undo them.
template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::stall(std::vector<Vec>& x, std::int64_t a) const -> std::vector<std::int64_t> {
  if (sh_ == 0) [[likely]] return {};
  std::vector<std::int64_t> up(x.size(), 0);
  for (std::size_t m = 1; m < x.size(); ++m) {
    diff_at(x[m], x[0], a - 1, up[m]);  // the first's image n boxes up is next to m: m's image next to it is -n up
    if (up[m] != 0) x[m][0] = wrap(static_cast<i128>(x[m][0]) + static_cast<i128>(up[m]) * sh_, u_.L[0]);
  }
  return up;
}

// Post velocities of a resolve for the members g (their points at a, the stall's: x): sequential specular
// collisions of the pairs whose pre lines overlap at a, then integer rounding with the sum kept.
template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::resolve_velocities(const std::vector<int>& g, const std::vector<Vec>& x, std::int64_t a) const -> std::vector<Vec> {
  using VecD = std::array<double, D>;
  // a . b, summed from the first axis on (the 2D engine's order)
  auto ddot = [](const VecD& p, const VecD& q) {
    double s = p[0] * q[0];
    for (std::size_t k = 1; k < D; ++k) s += p[k] * q[k];
    return s;
  };
  const std::size_t n = g.size();
  std::vector<VecD> v(n);
  std::vector<Vec> mv(n);  // the members' moves over the tick (a field: v + h, field.hpp)
  for (std::size_t m = 0; m < n; ++m) mv[m] = plus_h(vel(g[m], a - 1));
  for (std::size_t m = 0; m < n; ++m)
    for (std::size_t k = 0; k < D; ++k) v[m][k] = static_cast<double>(mv[m][k]);
  struct Touch {
    std::size_t p, q;
    VecD n;
    double s;  // shear: q's image's extra speed along the flow, n s (shear.hpp)
  };
  std::vector<Touch> touch;
  for (std::size_t p = 0; p < n; ++p)
    for (std::size_t q = p + 1; q < n; ++q) {
      std::int64_t up;
      const Vec r = diff_at(x[p], x[q], a, up);
      const double s = static_cast<double>(up * sh_);
      VecD rd, w;
      for (std::size_t k = 0; k < D; ++k) {
        rd[k] = static_cast<double>(r[k]);
        w[k] = v[p][k] - v[q][k] - (k == 0 ? s : 0.0);
      }
      const double len = std::sqrt(ddot(rd, rd));
      // touching: the pre lines overlap at a, or the pair is within one tick's relative travel at a-1
      const bool near = len < static_cast<double>(rad(g[p]) + rad(g[q])) + std::sqrt(ddot(w, w));
      if (len > 0.0 && (near || overlap_at(pos(g[p], a), pos(g[q], a), g[p], g[q], a))) {
        for (std::size_t k = 0; k < D; ++k) rd[k] /= len;
        touch.push_back({p, q, rd, s});
      }
    }
  // a wall is met within the tick by a member whose line is beyond it at a: -1 lower, +1 upper
  std::vector<std::array<int, D>> wall(n, std::array<int, D>{});
  for (std::size_t m = 0; m < n; ++m) {
    const Vec xa = pos(g[m], a);
    for (std::size_t k = 0; k < D; ++k)
      if (u_.wall[k]) wall[m][k] = xa[k] < lo_of(g[m]) ? -1 : xa[k] > hi_of(g[m], static_cast<int>(k)) ? 1 : 0;
  }
  const double eps = 1e-12 * static_cast<double>(u_.vmax);
  for (int sweep = 0; sweep < 64; ++sweep) {
    bool any = false;
    for (std::size_t m = 0; m < n; ++m)
      for (std::size_t k = 0; k < D; ++k)
        if (wall[m][k] * v[m][k] > 0.0) {  // approaching a wall it meets: specular, exact
          if (u_.bounce[k]) {
            for (std::size_t j = 0; j < D; ++j) v[m][j] = -v[m][j];  // a bounce-back wall: v -> -v
          } else {
            v[m][k] = -v[m][k];
          }
          any = true;
        }
    for (const Touch& t : touch) {
      VecD w;
      for (std::size_t k = 0; k < D; ++k) w[k] = v[t.p][k] - v[t.q][k] - (k == 0 ? t.s : 0.0);
      const double wn = ddot(w, t.n);
      if (wn >= -eps) continue;  // not approaching along the normal
      for (std::size_t k = 0; k < D; ++k) {
        v[t.p][k] = v[t.p][k] - wn * t.n[k];
        v[t.q][k] = v[t.q][k] + wn * t.n[k];
      }
      any = true;
    }
    if (!any) break;
  }
  std::vector<Vec> out(n);
  for (std::size_t k = 0; k < D; ++k) {
    i128 before = 0, after = 0;
    std::size_t big = 0;
    for (std::size_t m = 0; m < n; ++m) {
      const double c = std::clamp(v[m][k], -static_cast<double>(tick_limit), static_cast<double>(tick_limit));
      out[m][k] = static_cast<std::int64_t>(std::llround(c));
      before += mv[m][k];
      after += out[m][k];
      if (std::abs(out[m][k]) > std::abs(out[big][k])) big = m;
    }
    out[big][k] += static_cast<std::int64_t>(before - after);  // momentum kept exactly
  }
  for (Vec& o : out) o = plus_h(o);  // the velocities at a
  return out;
}

// The post state of a group collision: positions at a (the a-1 points) and velocities, the
// group grown by every body the post state would meet. False when it breaks the walls, vmax,
// the 16-member cap or (a resolve) the reverse's view of it.
template <class Op, class Bits, class Queue>
auto BasicEngine<Op, Bits, Queue>::group_post(std::vector<int>& g, std::int64_t a, bool resolve, std::vector<Vec>& post, std::vector<Vec>& vel) const -> bool {
  auto member = [&](int q) { return std::find(g.begin(), g.end(), q) != g.end(); };
  for (;;) {
    if (g.size() > 16) return false;
    std::sort(g.begin(), g.end(), [&](int a, int b) { return gid(a) < gid(b); });  // by particle id
    post.assign(g.size(), Vec{});
    for (std::size_t m = 0; m < g.size(); ++m) post[m] = pos(g[m], a - 1);
    const std::vector<std::int64_t> up = stall(post, a);
    if (resolve) {
      vel = resolve_velocities(g, post, a);
    } else {
      vel.assign(g.size(), Vec{});
      for (std::size_t m = 0; m < g.size(); ++m) {
        vel[m] = neg(this->vel(g[m], a - 1));  // (a field too: the stall's move negated)
        if (!up.empty()) vel[m][0] += 2 * up[m] * sh_;  // (shear: negated in the first's frame)
      }
    }
    bool grew = false;
    for (std::size_t m = 0; m < g.size() && !grew; ++m) {
      for (std::size_t k = 0; k < D; ++k) {
        if (vel[m][k] > u_.vmax || vel[m][k] < -u_.vmax) return false;
        if (u_.wall[k] && (post[m][k] < lo_of(g[m]) || post[m][k] > hi_of(g[m], static_cast<int>(k)))) return false;
      }
      const Vec ghost = back_at(plus_h(post[m]), vel[m], a - 1);  // the new line at a-1 (a field: x - v + h)
      near(g[m], [&](int q) {
        if (grew || member(q)) return;
        if (overlap_at(post[m], pos(q, a), g[m], q, a) || overlap_at(ghost, pos(q, a - 1), g[m], q, a - 1)) {
          g.push_back(q);
          grew = true;
        }
      });
    }
    if (grew) continue;
    // the reverse must meet the group at this tick: some member pair's new lines overlap at a-1
    // (a bounce's new lines at a-1 are its pre lines at a, so it holds unless a member's line
    // was taken back from a reflection at a)
    for (std::size_t p = 0; p < g.size(); ++p)
      for (std::size_t q = p + 1; q < g.size(); ++q) {
        const Vec gp = back_at(plus_h(post[p]), vel[p], a - 1);
        const Vec gq = back_at(plus_h(post[q]), vel[q], a - 1);
        if (overlap_at(gp, gq, g[p], g[q], a - 1)) return true;  // the reverse meets this pair at a-1
      }
    return false;
  }
}

template <class Op, class Bits, class Queue>
bool BasicEngine<Op, Bits, Queue>::group_collide(int i, int j, std::int64_t a, std::uint64_t ctr0, const std::array<std::uint64_t, 8>& reasons, bool must) {
  // a member reflected at this very tick takes its line from before the reflection, and the
  // wall joins the group as a contact (resolve_velocities): the stall point is then a real point
  // inside the box, and the log's pre velocity is the one before the reflection
  const Line keep[2] = {ln_[i], ln_[j]};
  bool unreflected[2] = {false, false};
  for (int s = 0; s < 2; ++s) {
    const int m = s == 0 ? i : j;
    if (wall_tick_[m] == a) {
      ln_[m] = pre_wall_[m];
      unreflected[s] = true;
    }
  }
  const std::vector<int> g0 = group_of(i, j, a);
  std::vector<int> g = g0;
  std::vector<Vec> post, vel;
  bool resolve = group_resolve, ok = resolve && group_post(g, a, true, post, vel);
  if (!ok) {
    resolve = false;
    g = g0;
    ok = group_post(g, a, false, post, vel);
  }
  if (!ok) {
    own_[i].ctr = ctr0;  // nothing changed
    ln_[i] = keep[0];
    ln_[j] = keep[1];
    if (!must) return false;
    std::string why = "lattice engine: collision " + std::to_string(ncoll_ + 1) + " of particles " +
                      std::to_string(i) + ", " + std::to_string(j) + " at tick " + std::to_string(a) +
                      (mode_ == Mode::specular ? std::string(" had its specular post state refused and no draw of the ") +
                                                     "randomized operator in " + std::to_string(max_redraws) + " was acceptable"
                                               : " found no acceptable post state in " + std::to_string(max_redraws) + " redraws") +
                      ", and its group of " + std::to_string(g.size()) + " can neither resolve nor bounce back (";
    for (int k = 1; k < 8; ++k) why += std::string(redraw_names[k]) + " " + std::to_string(reasons[k]) + (k < 7 ? ", " : ")");
    throw std::runtime_error(why);
  }
  std::vector<Vec> pre_v;
  for (int q : g) {
    journal(q);
    if (jon_ && jhow_ != Rollback::reverse && !reversed_ && q != i && q != j) save_state(q);  // (i, j: saved by the loop)
  }
  if (resolve)
    for (int q : g) pre_v.push_back(this->vel(q, a - 1));
  ++ncoll_;
  std::vector<std::uint64_t> counts;
  for (int q : g) counts.push_back(++own_[q].pc);
  std::vector<int> ids;  // (the entry holds particle ids)
  for (int q : g) ids.push_back(gid(q));
  auto entry = std::make_shared<Group>(Group{gid(i), static_cast<std::uint32_t>(own_[i].ctr - ctr0), ids, counts, std::move(pre_v)});
  for (std::size_t m = 0; m < g.size(); ++m) {
    const LogKey key{static_cast<std::uint32_t>(ids[m]), counts[m]};
    groups_.emplace(key, entry);
    if (!undo_epoch_.empty()) undo_groups_.push_back(key);
  }
  ++ngroups_;
  ++cnt_.log_entries;
  ++cnt_.multi_body;
  ++(resolve ? cnt_.group_resolves : cnt_.group_bounces);
  for (int s = 0; s < 2; ++s)
    if (unreflected[s]) {
      wall_tick_[s == 0 ? i : j] = std::numeric_limits<std::int64_t>::min();  // the group took the reflection in
      unreflected_ |= static_cast<std::uint8_t>(1u << s);  // (the journal's entry: its undo reflects again)
      ++cnt_.wall_groups;
    }
  if (trace != nullptr) trace->push_back({a, gid(i), gid(j)});
  if (obs_ || events || seen_) [[unlikely]] note_group(a, g, post, vel);
  for (std::size_t m = 0; m < g.size(); ++m) {
    ln_[g[m]] = Line{post[m], vel[m], a};
    sync(g[m]);
    ++slot_[static_cast<std::size_t>(g[m])].ver;
  }
  ++cnt_.collisions;
  for (int q : g) predict(q, a);
  return true;
}

template <class Op, class Bits, class Queue>
void BasicEngine<Op, Bits, Queue>::group_back(int i, int j, std::int64_t a, Group& entry) {
  std::vector<int> g;  // the members' local indices
  for (int q : entry.members) g.push_back(static_cast<int>(local(q)));
  if (std::find(g.begin(), g.end(), i) == g.end() || std::find(g.begin(), g.end(), j) == g.end()) {
    inconsistent("the reverse met a group at another pair", i, j);
  }
  for (std::size_t m = 0; m < g.size(); ++m)
    if (own_[g[m]].pc != entry.counts[m]) inconsistent("the reverse met a group before a member's later collision", i, j);
  const std::uint32_t draws = entry.draws;
  const auto drawer = local(entry.drawer);
  if (own_[drawer].ctr < draws) inconsistent("a group's drawer's stream would step back past draw 0", i, j);
  const std::vector<Vec> pre_v = entry.pre_v;  // forward frame; empty: a bounce (a copy: popped below)
  std::vector<Vec> pre(g.size());
  for (std::size_t m = 0; m < g.size(); ++m) pre[m] = pos(g[m], a - 1);
  const std::vector<std::int64_t> up = stall(pre, a);
  for (std::size_t m = 0; m < g.size(); ++m) {
    Line& l = ln_[g[m]];
    Vec v = pre_v.empty() ? neg(vel(g[m], a - 1)) : neg(pre_v[m]);
    if (pre_v.empty() && !up.empty()) v[0] += 2 * up[m] * sh_;  // (a bounce under shear: stall())
    l = Line{pre[m], v, a};
    sync(g[m]);
    ++slot_[static_cast<std::size_t>(g[m])].ver;
  }
  own_[drawer].ctr -= draws;
  for (int q : g) {
    groups_.erase(LogKey{static_cast<std::uint32_t>(gid(q)), own_[q].pc});  // entry is gone after the last
    --own_[q].pc;
  }
  --ngroups_;
  --ncoll_;
  ++cnt_.collisions;
  for (int q : g) predict(q, a);
}

}  // namespace revcol::lattice
