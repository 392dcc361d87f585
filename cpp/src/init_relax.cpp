// The relaxed random start (init_relax.hpp): FIRE on the harmonic overlap energy, neighbours
// from a cell grid rebuilt at every step (O(N) a step), walls by projection.
#include "init_relax.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "revcol/engine/limits.hpp"

namespace revcol::engine::detail {
namespace {

// FIRE's parameters (Bitzek et al. 2006), the time step in units of the largest diameter (the
// stiffness 1 / D^2, unit masses: one contact's period is 2 pi D).
constexpr double kDt0 = 0.02, kDtMax = 0.1, kAlpha0 = 0.1, kFAlpha = 0.99, kFInc = 1.1, kFDec = 0.5;
constexpr int kNMin = 5;
// Steps without the largest overlap halving after which a relaxation gives up (at or past
// jamming: measured, a 1:1 mixture of ratio 1.4 at 0.62 in 3D halves it every ~150 steps,
// at 0.645 every ~10 000).
constexpr long kStall = 5000;

class Relaxer {
 public:
  Relaxer(const RelaxBox& b, const std::vector<double>& diam) : b_(b), n_(diam.size()), diam_(diam) {
    dmax_ = *std::max_element(diam.begin(), diam.end());
    accept_ = 1.0 + kRelaxGap;
    push_ = 1.0 + 2.0 * kRelaxGap;
    limits::capped_cell_counts(b_.d, b_.L, dmax_ * push_, limits::max_cells(n_), nc_);  // the widest reach
    std::size_t total = 1;
    for (int k = 0; k < b_.d; ++k) {
      cw_[k] = b_.L[k] / nc_[k];
      total *= static_cast<std::size_t>(nc_[k]);
      if (!b_.wall[k] && nc_[k] < 3) brute_ = true;  // a neighbouring cell's image would repeat
    }
    head_.assign(total, -1);
    next_.assign(n_, -1);
  }

  // The forces on every centre (into f), and the pairs closer than accept_ times their contact
  // distance (a centre closer to a wall than accept_ times its radius counts as one): their
  // count and the largest shortfall over that distance.
  long forces(const std::vector<double>& x, std::vector<double>& f, double& worst) {
    std::fill(f.begin(), f.end(), 0.0);
    worst = 0.0;
    long count = 0;
    const int d = b_.d;
    const double k2 = 1.0 / (dmax_ * dmax_);
    auto pair = [&](std::size_t i, std::size_t j) {
      double dx[3], r2 = 0.0;
      for (int k = 0; k < d; ++k) {
        double u = x[i * d + k] - x[j * d + k];
        if (!b_.wall[k]) {  // the nearest image (centres in [0, L): |u| < L)
          if (u > 0.5 * b_.L[k]) u -= b_.L[k];
          else if (u < -0.5 * b_.L[k]) u += b_.L[k];
        }
        dx[k] = u;
        r2 += u * u;
      }
      const double contact = 0.5 * (diam_[i] + diam_[j]), a = contact * accept_, s = contact * push_;
      if (!(r2 < s * s)) return;
      const double r = std::sqrt(r2);
      if (r2 < a * a) {
        ++count;
        worst = std::max(worst, (a - r) / a);
      }
      if (!(r > 0.0)) return;  // coincident centres: the others' pushes part them
      const double mag = k2 * (s - r) / r;
      for (int k = 0; k < d; ++k) {
        f[i * d + k] += mag * dx[k];
        f[j * d + k] -= mag * dx[k];
      }
    };
    for (std::size_t i = 0; i < n_; ++i)  // a wall pushes as a pair does, at the radius
      for (int k = 0; k < d; ++k) {
        if (!b_.wall[k]) continue;
        const double r = 0.5 * diam_[i], a = r * accept_, s = r * push_;
        for (int up = 0; up < 2; ++up) {
          const double dist = up ? b_.L[k] - x[i * d + k] : x[i * d + k];
          if (!(dist < s)) continue;
          if (dist < a) {
            ++count;
            worst = std::max(worst, (a - dist) / a);
          }
          f[i * d + k] += (up ? -k2 : k2) * (s - dist);
        }
      }
    if (brute_) {
      for (std::size_t i = 0; i < n_; ++i)
        for (std::size_t j = i + 1; j < n_; ++j) pair(i, j);
      return count;
    }
    bin(x);
    const int noff = d == 1 ? 3 : d == 2 ? 9 : 27;
    for (std::size_t c = 0; c < head_.size(); ++c) {
      if (head_[c] < 0) continue;
      int cc[3] = {0, 0, 0};
      std::size_t rest = c;
      for (int k = 0; k < d; ++k) {
        cc[k] = static_cast<int>(rest % static_cast<std::size_t>(nc_[k]));
        rest /= static_cast<std::size_t>(nc_[k]);
      }
      for (int o = 0; o < noff; ++o) {
        int rem = o;
        std::size_t id = 0, stride = 1;
        bool in = true;
        for (int k = 0; k < d; ++k) {
          int ck = cc[k] + rem % 3 - 1;
          rem /= 3;
          if (ck < 0 || ck >= nc_[k]) {
            if (b_.wall[k]) {
              in = false;
              break;
            }
            ck = ck < 0 ? ck + nc_[k] : ck - nc_[k];
          }
          id += static_cast<std::size_t>(ck) * stride;
          stride *= static_cast<std::size_t>(nc_[k]);
        }
        if (!in) continue;
        for (int i = head_[c]; i >= 0; i = next_[i])
          for (int j = head_[id]; j >= 0; j = next_[j])
            if (j > i) pair(static_cast<std::size_t>(i), static_cast<std::size_t>(j));
      }
    }
    return count;
  }

  // Centre i's hard range on axis k: [lo, hi] (walls: its radius (1 + kWallMargin) inside; the
  // pushes keep it a radius (1 + kRelaxGap) inside at the end).
  double lo(std::size_t i, int k) const { return b_.wall[k] ? kWall * diam_[i] : 0.0; }
  double hi(std::size_t i, int k) const { return b_.wall[k] ? b_.L[k] - kWall * diam_[i] : b_.L[k]; }
  static constexpr double kWall = 0.5 * (1.0 + limits::kWallMargin);

 private:
  void bin(const std::vector<double>& x) {
    std::fill(head_.begin(), head_.end(), -1);
    const int d = b_.d;
    for (std::size_t i = 0; i < n_; ++i) {
      std::size_t id = 0, stride = 1;
      for (int k = 0; k < d; ++k) {
        const int ck = std::clamp(static_cast<int>(x[i * d + k] / cw_[k]), 0, nc_[k] - 1);
        id += static_cast<std::size_t>(ck) * stride;
        stride *= static_cast<std::size_t>(nc_[k]);
      }
      next_[i] = head_[id];
      head_[id] = static_cast<int>(i);
    }
  }

  RelaxBox b_;
  std::size_t n_;
  const std::vector<double>& diam_;
  // the pushes act within push_ times a contact distance, a start is accepted beyond accept_
  // times it: the gap between them keeps a pair whose overlap rounds away in sqrt pushed
  double dmax_ = 1.0, accept_ = 1.0, push_ = 1.0;
  int nc_[3] = {1, 1, 1};
  double cw_[3] = {1.0, 1.0, 1.0};
  bool brute_ = false;
  std::vector<int> head_, next_;
};

}  // namespace

RelaxResult relax_overlaps(const RelaxBox& b, const std::vector<double>& diam, std::vector<double>& x,
                           long max_steps, const InterruptCheck& interrupt) {
  const int d = b.d;
  const std::size_t n = diam.size();
  RelaxResult out;
  if (n == 0) {
    out.done = true;
    return out;
  }
  Relaxer rx(b, diam);
  InterruptPoll poll(interrupt, 16);
  const double dmax = *std::max_element(diam.begin(), diam.end());
  std::vector<double> v(n * d, 0.0), f(n * d, 0.0);
  double dt = kDt0 * dmax, alpha = kAlpha0;
  int since = 0;  // steps since the power was last negative
  double halved = 1e300;  // the largest overlap when it last fell below half the one before
  long since_halved = 0;
  for (;; ++out.steps) {
    poll.tick();
    double worst = 0.0;
    if (rx.forces(x, f, worst) == 0) {
      out.done = true;
      return out;
    }
    if (out.steps >= max_steps) {
      out.overlap = worst;
      return out;
    }
    double power = 0.0, vv = 0.0, ff = 0.0;
    for (std::size_t q = 0; q < n * d; ++q) {
      power += f[q] * v[q];
      vv += v[q] * v[q];
      ff += f[q] * f[q];
    }
    // jammed: the forces balance (rms below 1e-9 of the largest overlap, both over D) with the
    // overlaps left; stalled: the largest overlap has not halved in kStall steps
    if (std::sqrt(ff / static_cast<double>(n)) * dmax < 1e-9 * worst || out.steps - since_halved > kStall) {
      out.overlap = worst;
      return out;
    }
    if (worst < 0.5 * halved) {
      halved = worst;
      since_halved = out.steps;
    }
    if (power > 0.0) {  // downhill: steer the velocity towards the force, and speed up
      const double mix = alpha * std::sqrt(vv / ff);
      for (std::size_t q = 0; q < n * d; ++q) v[q] = (1.0 - alpha) * v[q] + mix * f[q];
      if (++since > kNMin) {
        dt = std::min(dt * kFInc, kDtMax * dmax);
        alpha *= kFAlpha;
      }
    } else {  // uphill: stop, and take smaller steps
      std::fill(v.begin(), v.end(), 0.0);
      dt *= kFDec;
      alpha = kAlpha0;
      since = 0;
    }
    for (std::size_t i = 0; i < n; ++i)  // semi-implicit Euler, then back into the box
      for (int k = 0; k < d; ++k) {
        const std::size_t q = i * d + k;
        v[q] += f[q] * dt;
        double p = x[q] + v[q] * dt;
        if (b.wall[k]) {
          const double l = rx.lo(i, k), h = rx.hi(i, k);
          if (p < l || p > h) {
            p = std::clamp(p, l, h);
            v[q] = 0.0;
          }
        } else {
          if (p >= b.L[k] || p < 0.0) p -= b.L[k] * std::floor(p / b.L[k]);
          if (!(p < b.L[k])) p = 0.0;  // a rounding onto L
        }
        x[q] = p;
      }
  }
}

}  // namespace revcol::engine::detail
