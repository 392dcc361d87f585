// The collision trace's grid (revcol/engine/trace.hpp): keeping, checking, saving.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "revcol/engine/trace.hpp"
#include "revcol/error.hpp"

namespace revcol::engine {

CollisionTrace::Point* CollisionTrace::find(std::int64_t g) {
  auto it = std::lower_bound(points_.begin(), points_.end(), g, [](const Point& p, std::int64_t m) { return p.m < m; });
  return it != points_.end() && it->m == g ? &*it : nullptr;
}

void CollisionTrace::record(std::int64_t m, double t) {
  suspect_ = kNever;  // a forward step ends whatever reversed pass left a suspect
  misses_ = 0;
  clock_dev_ = 0.0;
  // only the trajectory that led here is kept: drop what lies above m
  while (!points_.empty() && points_.back().m > m) points_.pop_back();
  if (!points_.empty()) {
    Point& b = points_.back();
    if (b.m + kOffset > m) b.have &= ~std::uint64_t{2};
    if (b.m + 1 > m) b.have &= ~std::uint64_t{4};
  }
  const std::uint64_t mask = stride_ - 1;
  const auto u = static_cast<std::uint64_t>(m);
  if ((u & mask) == 0) {
    if (!points_.empty() && points_.back().m == m) {
      points_.back().at = sum_;
      points_.back().have |= 1;
    } else {
      if (points_.size() == kCapacity) {  // thin: every other point goes, the stride doubles
        const std::uint64_t wide = 2 * stride_ - 1;
        std::erase_if(points_, [&](const Point& p) { return (static_cast<std::uint64_t>(p.m) & wide) != 0; });
        stride_ *= 2;
      }
      if ((u & (stride_ - 1)) == 0) points_.push_back({m, sum_, 0, 1, 0.0});
    }
  }
  if (((u - kOffset) & (stride_ - 1)) == 0)
    if (Point* p = find(m - kOffset)) {
      p->above = sum_;
      p->have |= 2;
    }
  if (((u - 1) & (stride_ - 1)) == 0)
    if (Point* p = find(m - 1)) {
      p->t_next = t;
      p->have |= 4;
    }
}

void CollisionTrace::verdict(std::int64_t m, bool same) {
  if (same) {
    if (misses_ > 0) ++reorderings_;  // mismatches, then agreement: collisions undone in another order
    suspect_ = kNever;
    misses_ = 0;
    verified_at_ = m;
    return;
  }
  if (misses_++ == 0) suspect_ = m;
  if (misses_ >= kConfirm) diverge(suspect_, Divergence::sequence);
}

bool CollisionTrace::check(std::int64_t m, double t) {
  const std::uint64_t mask = stride_ - 1;
  const auto u = static_cast<std::uint64_t>(m);
  if (((u - kOffset) & mask) == 0)
    if (const Point* p = find(m - kOffset); p && (p->have & 2)) verdict(m, p->above == sum_);
  const bool primary = (u & mask) == 0;
  if (primary)
    if (const Point* p = find(m)) {
      if (p->have & 4) clock_dev_ = std::max(clock_dev_, std::fabs(t - p->t_next));
      if (p->have & 1) verdict(m, p->at == sum_);
    }
  return primary;
}

void CollisionTrace::check_start(std::int64_t m) {
  if (points_.empty() || points_.front().m != m || !(points_.front().have & 1)) return;
  if (points_.front().at != sum_) diverge(suspect_ != kNever ? suspect_ : m, Divergence::sequence);
}

std::vector<std::uint64_t> CollisionTrace::save() const {
  std::vector<std::uint64_t> a{sum_,
                               stride_,
                               static_cast<std::uint64_t>(suspect_),
                               misses_,
                               reorderings_,
                               static_cast<std::uint64_t>(reason_),
                               static_cast<std::uint64_t>(diverged_at_),
                               static_cast<std::uint64_t>(verified_at_),
                               std::bit_cast<std::uint64_t>(clock_dev_)};
  static_assert(kHeader == 9 && kWords == 5);
  for (const Point& p : points_) {
    a.push_back(static_cast<std::uint64_t>(p.m));
    a.push_back(p.at);
    a.push_back(p.above);
    a.push_back(p.have);
    a.push_back(std::bit_cast<std::uint64_t>(p.t_next));
  }
  return a;
}

CollisionTrace CollisionTrace::load(const std::vector<std::uint64_t>& a, std::size_t n) {
  require(a.size() >= kHeader && (a.size() - kHeader) % kWords == 0,
          "checkpoint: trace must hold 9 header words and 5 per point, got " + std::to_string(a.size()));
  const std::size_t np = (a.size() - kHeader) / kWords;
  require(np <= kCapacity, "checkpoint: trace holds " + std::to_string(np) + " points, at most " +
                               std::to_string(kCapacity) + " are kept");
  CollisionTrace t(n);
  t.sum_ = a[0];
  t.stride_ = a[1];
  require(std::has_single_bit(t.stride_) && t.stride_ >= kMinStride && t.stride_ <= (std::uint64_t{1} << 62),
          "checkpoint: trace stride must be a power of two in [128, 2^62]");
  t.suspect_ = static_cast<std::int64_t>(a[2]);
  t.misses_ = a[3];
  t.reorderings_ = a[4];
  require(a[5] <= static_cast<std::uint64_t>(Divergence::overlap), "checkpoint: trace reason must be 0..5");
  t.reason_ = static_cast<Divergence>(a[5]);
  // mismatches in a row go with the first one's count, and reach kConfirm only after a divergence
  require((t.misses_ == 0) == (t.suspect_ == kNever) && (t.misses_ < kConfirm || t.reason_ != Divergence::none),
          "checkpoint: trace mismatch count and suspect count disagree");
  t.diverged_at_ = static_cast<std::int64_t>(a[6]);
  t.verified_at_ = static_cast<std::int64_t>(a[7]);
  t.clock_dev_ = std::bit_cast<double>(a[8]);
  require(std::isfinite(t.clock_dev_) && t.clock_dev_ >= 0.0, "checkpoint: trace clock deviation must be finite, >= 0");
  require((t.reason_ == Divergence::none) == (t.diverged_at_ == kNever),
          "checkpoint: trace has a divergence count without a reason, or a reason without a count");
  for (std::size_t u = 0; u < np; ++u) {
    const std::uint64_t* w = a.data() + kHeader + kWords * u;
    const Point p{static_cast<std::int64_t>(w[0]), w[1], w[2], w[3], std::bit_cast<double>(w[4])};
    require((static_cast<std::uint64_t>(p.m) & (t.stride_ - 1)) == 0,
            "checkpoint: trace point " + std::to_string(u) + " is not a multiple of the stride");
    require(t.points_.empty() || t.points_.back().m < p.m,
            "checkpoint: trace points must be in ascending order");
    require(p.have >= 1 && p.have <= 7, "checkpoint: trace point flags must be 1..7");
    require(std::isfinite(p.t_next), "checkpoint: trace point " + std::to_string(u) + " has a time that is not finite");
    t.points_.push_back(p);
  }
  return t;
}

}  // namespace revcol::engine
