// The event queue (revcol/engine/event_queue.hpp) against a brute-force reference: random
// set / erase / top sequences with ties in time and kind, events at never(), empty queues,
// negative and huge times, for double times and std::int64_t ticks; the queue's own
// invariants checked along the way.
#include "revcol/engine/event_queue.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "check.hpp"

using revcol::engine::EventQueue;

namespace {

// The reference: a flat array, top() by a full scan; ties broken by tie[i] (the id, or a
// permutation of the ids).
template <class Time>
struct Brute {
  std::vector<Time> t;
  std::vector<std::int32_t> k;
  std::vector<bool> on;
  std::vector<std::int32_t> tie;
  explicit Brute(std::size_t n) : t(n), k(n), on(n, false), tie(n) {
    for (std::size_t i = 0; i < n; ++i) tie[i] = static_cast<std::int32_t>(i);
  }
  int top() const {
    int best = -1;
    for (int i = 0; i < static_cast<int>(t.size()); ++i) {
      if (!on[i]) continue;
      if (best < 0 || t[i] < t[best] || (t[i] == t[best] && (k[i] < k[best] || (k[i] == k[best] && tie[i] < tie[best]))))
        best = i;
    }
    return best;
  }
};

// An event-driven pattern: pop the top, reschedule it (and a few others) later than now,
// sometimes at exactly now or at the same time as another (ties), sometimes at never(), and
// sometimes erase; times drawn by `draw(now, rng)`. With `permuted_ties`, set() passes each
// id a tie breaker from a random permutation of the ids (the float engine's slots and ids).
template <class Time, class Draw>
int run_pattern(std::size_t n, Time now, Time width, int steps, std::uint32_t seed, Draw draw,
                bool permuted_ties = false) {
  std::mt19937_64 rng(seed);
  EventQueue<Time> q;
  Brute<Time> b(n);
  if (permuted_ties) std::shuffle(b.tie.begin(), b.tie.end(), rng);
  q.reset(n, now, width, permuted_ties);
  int bad = 0;
  auto set = [&](int id, Time t, std::int32_t kind) {
    if (permuted_ties) q.set(id, t, kind, b.tie[static_cast<std::size_t>(id)]);
    else q.set(id, t, kind);
    b.t[id] = t;
    b.k[id] = kind;
    b.on[id] = true;
  };
  for (std::size_t i = 0; i < n; ++i) set(static_cast<int>(i), draw(now, rng), static_cast<std::int32_t>(rng() % 3));
  for (int s = 0; s < steps; ++s) {
    const int want = b.top();
    const int got = q.top();
    if (got != want) ++bad;
    if (want < 0) {  // empty: refill a few
      for (int r = 0; r < 3; ++r) set(static_cast<int>(rng() % n), draw(now, rng), static_cast<std::int32_t>(rng() % 3));
      continue;
    }
    if (b.t[want] != EventQueue<Time>::never()) now = b.t[want];
    if (q.time(want) != b.t[want] || q.kind(want) != b.k[want] || !q.scheduled(want)) ++bad;
    const auto r = rng() % 16;
    if (r == 0) {
      q.erase(want);
      b.on[want] = false;
      if (q.scheduled(want)) ++bad;
    } else if (r == 1) {
      set(want, EventQueue<Time>::never(), 3);
    } else if (r == 2) {
      set(want, now, static_cast<std::int32_t>(rng() % 3));  // at the same instant: a tie in time
    } else {
      set(want, draw(now, rng), static_cast<std::int32_t>(rng() % 3));
    }
    // others rescheduled (a collision's partner), erased, or tied with the top
    const int other = static_cast<int>(rng() % n);
    const auto r2 = rng() % 8;
    if (r2 == 0) {
      q.erase(other);
      b.on[other] = false;
    } else if (r2 == 1 && b.on[want]) {
      set(other, b.t[want], b.k[want]);  // the same (time, kind): only the tie decides
    } else if (r2 < 5) {
      set(other, draw(now, rng), static_cast<std::int32_t>(rng() % 3));
    }
    if (s % 97 == 0 && !q.valid()) ++bad;
  }
  // drain: everything comes out in key order
  for (;;) {
    const int want = b.top();
    const int got = q.top();
    if (got != want) ++bad;
    if (want < 0) break;
    q.erase(want);
    b.on[want] = false;
  }
  if (!q.valid()) ++bad;
  return bad;
}

}  // namespace

TEST_CASE("double times: random event-driven sequences match the brute-force reference") {
  for (std::uint32_t seed = 1; seed <= 6; ++seed)
    for (std::size_t n : {1u, 2u, 7u, 100u, 1000u}) {
      // exponential gaps (a gas), quantized to 1/8 so that exact ties in time happen
      auto draw = [](double now, std::mt19937_64& rng) {
        std::exponential_distribution<double> e(1.0);
        return now + std::floor(e(rng) * 8.0) / 8.0;
      };
      CHECK(run_pattern<double>(n, 0.0, 0.05, 4000, seed, draw) == 0);
      // a bucket width far too small and far too large: order does not depend on it
      CHECK(run_pattern<double>(n, 0.0, 1e-9, 2000, seed, draw) == 0);
      CHECK(run_pattern<double>(n, 0.0, 1e9, 2000, seed, draw) == 0);
    }
}

TEST_CASE("double times: negative clock (a reversed run), arbitrary earlier times") {
  for (std::uint32_t seed = 1; seed <= 4; ++seed) {
    auto draw = [](double now, std::mt19937_64& rng) {
      std::uniform_real_distribution<double> u(-1.0, 20.0);  // some earlier than now
      return now + u(rng);
    };
    CHECK(run_pattern<double>(300, -1e3, 0.1, 5000, seed, draw) == 0);
  }
}

TEST_CASE("int64 ticks: random sequences, ties, huge and negative ticks") {
  for (std::uint32_t seed = 1; seed <= 6; ++seed)
    for (std::size_t n : {1u, 3u, 64u, 500u}) {
      auto small = [](std::int64_t now, std::mt19937_64& rng) {
        return now + static_cast<std::int64_t>(rng() % 50);
      };
      CHECK(run_pattern<std::int64_t>(n, 0, 1, 3000, seed, small) == 0);
      CHECK(run_pattern<std::int64_t>(n, -123456789, 7, 3000, seed, small) == 0);
      auto huge = [](std::int64_t now, std::mt19937_64& rng) {
        // room up to max - 1, computed without overflow for negative now (UBSan)
        const std::int64_t top = std::numeric_limits<std::int64_t>::max() - 1;
        const std::int64_t room = now < 0 ? top / 2 : top - now;
        const std::int64_t step = static_cast<std::int64_t>(rng() >> 2) % (room / 4 + 1);
        return now + step;
      };
      CHECK(run_pattern<std::int64_t>(n, std::numeric_limits<std::int64_t>::min() / 2, 1000, 2000, seed, huge) == 0);
      CHECK(run_pattern<std::int64_t>(n, 0, std::numeric_limits<std::int64_t>::max() / 4, 2000, seed, small) == 0);
    }
}

TEST_CASE("an empty queue returns -1, takes events again, and unscheduled ids report so") {
  EventQueue<double> q;
  q.reset(5, 0.0, 1.0);
  CHECK(q.top() == -1);
  CHECK(!q.scheduled(2));
  CHECK(q.time(2) == EventQueue<double>::never());
  q.set(3, 1e6, 2);
  q.set(1, 1e6, 2);
  q.set(4, 1e6, 1);
  CHECK(q.top() == 4);  // smaller kind first at equal time
  q.erase(4);
  CHECK(q.top() == 1);  // then the smaller id
  q.erase(1);
  q.erase(3);
  CHECK(q.top() == -1);
  q.set(0, -5.0, 0);  // earlier than the window's start
  CHECK(q.top() == 0);
  q.set(2, EventQueue<double>::never(), 3);
  q.erase(0);
  CHECK(q.top() == 2);  // an event at never() is kept and comes out last
  CHECK(q.valid());
  CHECK(q.memory_bytes() > 0);

  EventQueue<std::int64_t> t;
  t.reset(3, 0, 0);  // a width of 0 is taken as 1
  CHECK(t.top() == -1);
  t.set(1, 10, 0);
  t.set(0, 10, 0);
  CHECK(t.top() == 0);
  t.set(0, 11, 0);
  CHECK(t.top() == 1);
  CHECK(t.valid());
}

TEST_CASE("for_next names at most k scheduled events other than the top, and the next top when the bucket holds it") {
  std::mt19937_64 rng(7);
  EventQueue<double> q;
  const int n = 500;
  q.reset(n, 0.0, 0.01);
  std::vector<double> t(n);
  for (int i = 0; i < n; ++i) {
    t[i] = std::uniform_real_distribution<double>(0.0, 10.0)(rng);
    q.set(i, t[i], 2);
  }
  int named = 0, next_named = 0, steps = 0;
  for (int s = 0; s < 5000; ++s) {
    const int top = q.top();
    std::vector<int> ids;
    q.for_next(6, [&](int j) { ids.push_back(j); });
    CHECK(ids.size() <= 6);
    for (int j : ids) {
      CHECK(j != top);
      CHECK(q.scheduled(j));
      CHECK(q.time(j) >= q.time(top));
    }
    named += static_cast<int>(ids.size());
    t[top] += std::uniform_real_distribution<double>(0.0, 10.0)(rng);  // the top moves on, as after its event
    q.set(top, t[top], 2);
    const int next = q.top();
    for (int j : ids) next_named += j == next ? 1 : 0;
    ++steps;
  }
  std::printf("  for_next: %.2f ids per top, the next top among them %.0f%% of the time\n",
              static_cast<double>(named) / steps, 100.0 * next_named / steps);
  CHECK(named > 0);
  CHECK(next_named > steps / 4);  // a heap of the bucket's events holds the next top often
}

TEST_CASE("second is the second event in key order, the next top when the top moves past it") {
  // coarse times and permuted ties: the order among equal (time, kind) is the ties'
  for (std::uint32_t seed = 1; seed <= 3; ++seed) {
    std::mt19937_64 rng(seed);
    const int n = 300;
    EventQueue<double> q;
    Brute<double> b(n);
    std::shuffle(b.tie.begin(), b.tie.end(), rng);
    q.reset(n, 0.0, 0.25, /*ties=*/true);
    const auto set = [&](int id, double t, std::int32_t kind) {
      q.set(id, t, kind, b.tie[static_cast<std::size_t>(id)]);
      b.t[id] = t;
      b.k[id] = kind;
      b.on[id] = true;
    };
    for (int i = 0; i < n; ++i) set(i, static_cast<double>(rng() % 40) * 0.25, static_cast<std::int32_t>(rng() % 3));
    int named = 0, next_named = 0;
    for (int s = 0; s < 20000; ++s) {
      const int top = q.top();
      CHECK(top == b.top());
      const int g = q.second();
      if (g >= 0) {
        ++named;
        b.on[top] = false;  // the reference's second: its top with the top left out
        CHECK(g == b.top());
        b.on[top] = true;
      }
      const double now = b.t[top];
      set(top, now + static_cast<double>(1 + rng() % 40) * 0.25, static_cast<std::int32_t>(rng() % 3));
      if (g >= 0 && rng() % 2 == 0) set(static_cast<int>(rng() % n), now + static_cast<double>(rng() % 8) * 0.25, 0);
      if (g >= 0) next_named += q.top() == g ? 1 : 0;
    }
    std::printf("  second: named %d of 20000 tops, the next top %d times\n", named, next_named);
    CHECK(named > 10000);
    CHECK(next_named > named / 2);
  }
}

CHECK_MAIN()

TEST_CASE("a tie breaker other than the id: equal (time, kind) leave in the order of the ties") {
  // coarse times, so that many events share a time and a kind
  const auto coarse = [](double now, std::mt19937_64& rng) { return now + static_cast<double>(rng() % 4); };
  const auto coarse64 = [](std::int64_t now, std::mt19937_64& rng) { return now + static_cast<std::int64_t>(rng() % 4); };
  for (std::uint32_t seed = 1; seed <= 4; ++seed) {
    CHECK(run_pattern<double>(200, 0.0, 0.5, 20000, seed, coarse, /*permuted_ties=*/true) == 0);
    CHECK(run_pattern<std::int64_t>(200, 0, 1, 20000, seed, coarse64, /*permuted_ties=*/true) == 0);
  }
}
