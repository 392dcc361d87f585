// EngineImpl::fault(): the invariants the event loop relies on, checked at the clock.
// A restored snapshot keeps its schedule (event times, list centres) so that it resumes bit
// for bit, and so trusts it: a forged or damaged checkpoint whose schedule, centres and
// particles disagree would run on and pass particles through each other unreported (issue
// 59's property run). restore refuses such a snapshot, naming the first fault. Private to
// cpp/src: included by engine_build.hpp.
#pragma once
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "engine_impl.hpp"

namespace revcol::engine::detail {

// The loop needs, at the clock:
//  (a) every particle within renew_h of its list centre (its list then holds every particle
//      it can meet before its renewal; not in 1D's adjacent lists, which hold the rods beside),
//  (b) no wall, renewal or collision with a listed particle before i's scheduled event, and
//      no listed pair meeting before the earlier of its two scheduled events (whichever pops
//      first predicts the pair again),
//  (c) a scheduled collision whose partner is unchanged since (stamps equal) at the time the
//      pair meets, and a listed partner.
// Times agree to 1e-9 relative plus 1e-6 of the fastest particle's flight of one diameter:
// the engine predicts from the same numbers, so a schedule it wrote agrees to rounding.
// Walls are not checked in a reversed run, whose predictions follow the wall log.
template <int Dim, PairOperator Op>
std::string EngineImpl<Dim, Op>::schedule_fault() const {
  double vmax = 0.0;
  for (const auto& q : p_)
    for (int k = 0; k < Dim; ++k) vmax = std::max(vmax, std::fabs(q.v[k]));
  const double flight = vmax > 0.0 ? 1e-6 * cfg_.diameter / vmax : 0.0;
  const auto slack = [&](double t) { return flight + 1e-9 * (std::fabs(t) + std::fabs(clock_) + 1.0); };
  // t comes before `ref` by more than rounding (anything finite comes before an event at infinity)
  const auto sooner = [&](double t, double ref) { return ref == kInf ? t < kInf : t < ref - slack(ref); };
  const auto who = [&](int j) { return "particle " + std::to_string(bk_[static_cast<std::size_t>(j)].id); };
  for (int i = 0; i < static_cast<int>(n_); ++i) {
    const Particle<Dim>& pi = p_[static_cast<std::size_t>(i)];
    const Ev& e = bk_[static_cast<std::size_t>(i)].ev;
    const auto before = [&](double t) { return sooner(t, e.t); };
    if (!adjacent()) {
      const double* c = nl_.centre(i);
      double dd = 0.0;
      for (int k = 0; k < Dim; ++k) dd += (pos_at(i, k, clock_) - c[k]) * (pos_at(i, k, clock_) - c[k]);
      if (!(std::sqrt(dd) <= renew_h_ * (1.0 + 1e-9) + 1e-9 * cfg_.diameter))
        return who(i) + " is " + std::to_string(std::sqrt(dd)) + " from its list centre, beyond its reach " +
               std::to_string(renew_h_);
      double tau;
      const bool renews = field_ ? Kin::renewal_time(pi, c, renew_h_, gn_, tau) : Kin::renewal_time(pi, c, renew_h2_, tau);
      if (renews && before(std::max(pi.t + tau, clock_)))
        return who(i) + " leaves its list's reach before its scheduled event";
    }
    for (int k = 0; k < Dim && !rev_; ++k) {
      const double vk = pi.v[k];
      if (field_ && g_[k] != 0.0) {
        double tau;
        int up;
        if (Kin::wall_time(pi, k, g_[k], box_.wall_at(k, 0, radius(i)), box_.wall_at(k, 1, radius(i)), tau, up) &&
            before(std::max(pi.t + tau, clock_)))
          return who(i) + " meets a wall on axis " + std::to_string(k) + " before its scheduled event";
        continue;
      }
      if (vk == 0.0 || !box_.walls(k)) continue;
      if (before(std::max(Kin::plane_time(pi, k, box_.wall_at(k, vk > 0.0 ? 1 : 0, radius(i))), clock_)))
        return who(i) + " meets a wall on axis " + std::to_string(k) + " before its scheduled event";
    }
    const bool live = e.kind == kColl && p_[static_cast<std::size_t>(e.partner)].stamp == e.stamp;
    bool found = false;
    std::string fault;
    nl_.for_neighbours(
        i,
        [&](int j, const Vec& sh) {
          double t;
          bool touching = false;
          const double s2 = sigma2(i, j);
          const bool hit = field_ ? Kin::template pair_time<true>(pi, p_[static_cast<std::size_t>(j)], sh, s2, contact_tol(s2),
                                                                  t, touching, kInf, g_.data())
                                  : Kin::pair_time(pi, p_[static_cast<std::size_t>(j)], sh, s2, contact_tol(s2), t, touching);
          if (live && j == e.partner) {
            found = true;
            if (fault.empty() && !(hit && std::fabs(std::max(t, clock_) - e.t) <= slack(e.t)))
              fault = who(i) + "'s scheduled collision with " + who(j) + " is not when the pair meets";
          }
          if (!hit || !fault.empty()) return;
          if (sooner(std::max(t, clock_), std::min(e.t, bk_[static_cast<std::size_t>(j)].ev.t)))
            fault = who(i) + " and " + who(j) + " meet before either's scheduled event";
        },
        [](int) {});
    if (!fault.empty()) return fault;
    if (live && !found) return who(i) + "'s scheduled collision partner is not on its list";
  }
  return "";
}

// The first pair of particles that overlap at the clock (|r| < D (1 - 1e-9), the bar of
// validate_snapshot), or "": each listed pair once (a particle within its list's reach, as
// schedule_fault checks, has every particle it overlaps on its list). A reversed run calls it
// at its end: within the round-off horizon it retraces the forward path and finds none; past
// it, a particle's path up to its local time is still the forward one while others' are not,
// and no collision before that time is predicted (pair_time starts at the later local time).
template <int Dim, PairOperator Op>
std::string EngineImpl<Dim, Op>::first_overlap() const {
  const auto who = [&](int j) { return "particle " + std::to_string(bk_[static_cast<std::size_t>(j)].id); };
  std::string fault;
  for (int i = 0; i < static_cast<int>(n_) && fault.empty(); ++i)
    nl_.for_neighbours(
        i,
        [&](int j, const Vec& sh) {
          if (j <= i || !fault.empty()) return;
          double r2 = 0.0;
          for (int k = 0; k < Dim; ++k) {
            const double rk = (pos_at(i, k, clock_) - pos_at(j, k, clock_)) - sh[k];
            r2 += rk * rk;
          }
          const double s2 = sigma2(i, j);
          if (r2 < s2 * (1.0 - 1e-9) * (1.0 - 1e-9))
            fault = who(i) + " and " + who(j) + " overlap: distance " + std::to_string(std::sqrt(r2)) +
                    " < contact distance " + std::to_string(std::sqrt(s2));
        },
        [](int) {});
  return fault;
}

template <int Dim, PairOperator Op>
std::string EngineImpl<Dim, Op>::fault() const {
  std::string f = schedule_fault();
  return f.empty() ? first_overlap() : f;
}

// REVCOL_VALIDATE builds: after a collision, the members are not overlapping any listed
// neighbour (beyond round-off), every list is symmetric (small systems) and the queue
// keeps its invariants. Throws std::logic_error on a violation. A no-op otherwise.
template <int Dim, PairOperator Op>
void EngineImpl<Dim, Op>::validate_collision(const int* slots, int n) const {
#ifdef REVCOL_VALIDATE
  for (int u = 0; u < n; ++u) {
    const int i = slots[u];
    for_neighbours(i, [&](int j, const Vec& sh) {
      double r2 = 0.0;
      for (int k = 0; k < Dim; ++k) {
        const double d = pos_at(i, k, clock_) - (pos_at(j, k, clock_) + sh[k]);
        r2 += d * d;
      }
      const double s2 = sigma2(i, j);
      if (!(r2 >= s2 * (1.0 - 1e-6)))
        throw std::logic_error("REVCOL_VALIDATE: particles " + std::to_string(bk_[i].id) + " and " + std::to_string(bk_[j].id) +
                               " overlap after a collision: |r| / D = " + std::to_string(std::sqrt(r2 / s2)) +
                               (rev_ ? " (reversed run)" : " (forward run)") + " at t = " + std::to_string(clock_));
    });
  }
  if (!queue_.valid()) throw std::logic_error("REVCOL_VALIDATE: event queue invariants broken");
  if (n_ <= 2000 && !nl_.valid()) throw std::logic_error("REVCOL_VALIDATE: neighbour lists not symmetric");
#else
  (void)slots;
  (void)n;
#endif
}

}  // namespace revcol::engine::detail
