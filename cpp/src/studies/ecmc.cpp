// Event-chain Monte Carlo of hard spheres: see revcol/studies/ecmc.hpp.
#include "revcol/studies/ecmc.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "revcol/engine/limits.hpp"
#include "revcol/error.hpp"

namespace revcol::ecmc {

namespace {
/// Cells are at least D (1 + kCellMargin) wide, so that a position a rounding off its cell's
/// face still has every sphere it can touch in the 3^d cells around.
constexpr double kCellMargin = 1e-9;
/// A pair closer than D (1 - kOverlapTol) is refused as an overlap.
constexpr double kOverlapTol = 1e-9;
/// A mixture's diameters lie within this ratio of the largest (the lattice engine's bound).
constexpr double kMaxSizeRatio = 16.0;
/// Philox key word of the chains' stream (the engine's start uses 0xFFFFFF00 and 0xFFFFFF01).
constexpr std::uint32_t kStreamWord = 0xFFFFFF10u;
}  // namespace

EventChain::EventChain(std::vector<double> box, std::vector<double> x, double diameter, std::uint64_t seed)
    : dim_(static_cast<int>(box.size())), n_(0), diameter_(diameter), rng_({kStreamWord, 0}) {
  init(std::move(box), std::move(x), {}, seed);
}

EventChain::EventChain(std::vector<double> box, std::vector<double> x, const std::vector<double>& diameters,
                       std::uint64_t seed)
    : dim_(static_cast<int>(box.size())), n_(0), diameter_(0.0), rng_({kStreamWord, 0}) {
  for (std::size_t i = 0; i < diameters.size(); ++i) {
    const double d = diameters[i];
    require(std::isfinite(d) && d > 0, [&] {
      return "diameters must be positive and finite: diameter " + std::to_string(i) + " is " + num(d);
    });
    diameter_ = std::max(diameter_, d);
  }
  for (std::size_t i = 0; i < diameters.size(); ++i)
    require(diameters[i] * kMaxSizeRatio >= diameter_, [&] {
      return "diameter " + std::to_string(i) + " = " + num(diameters[i]) + " is more than " +
             std::to_string(static_cast<int>(kMaxSizeRatio)) + " times smaller than the largest, " + num(diameter_);
    });
  require(dim_ == 0 || x.size() == diameters.size() * box.size(), [&] {
    return "diameters must give one diameter per sphere: " + std::to_string(diameters.size()) + " for " +
           std::to_string(x.size() / box.size()) + " spheres";
  });
  if (diameters.empty()) diameter_ = 1.0;  // no spheres: nothing to size (the checks below still run)
  init(std::move(box), std::move(x), diameters, seed);
}

void EventChain::init(std::vector<double> box, std::vector<double> x, const std::vector<double>& diameters,
                      std::uint64_t seed) {
  const double diameter = diameter_;
  require(dim_ >= 1 && dim_ <= 3, [&] { return "box must have 1, 2 or 3 lengths, got " + std::to_string(dim_); });
  require(std::isfinite(diameter) && diameter > 0, [&] { return "diameter must be positive and finite, got " + num(diameter); });
  require(seed <= 0xFFFFFFFFull, [&] { return "seed must be below 2^32, got " + std::to_string(seed); });
  for (int k = 0; k < dim_; ++k) {
    const double L = box[static_cast<std::size_t>(k)];
    require(std::isfinite(L) && L >= 3.0 * diameter, [&] {
      return "box length " + std::to_string(k) + " must be finite and at least 3 diameters, got " + num(L);
    });
    require(L / diameter <= 1e7, [&] { return "box length " + std::to_string(k) + " is over 1e7 diameters: " + num(L); });
    box_[k] = L;
    m_[k] = static_cast<int>(std::floor(L / (diameter * (1.0 + kCellMargin))));
    w_[k] = L / m_[k];
  }
  require(x.size() % static_cast<std::size_t>(dim_) == 0,
          [&] { return "positions must hold n x " + std::to_string(dim_) + " numbers, got " + std::to_string(x.size()); });
  n_ = x.size() / static_cast<std::size_t>(dim_);
  require(n_ <= static_cast<std::size_t>(std::numeric_limits<int>::max()), "too many particles");
  std::size_t cells = 1;
  for (int k = 0; k < dim_; ++k) cells *= static_cast<std::size_t>(m_[k]);
  require(cells <= (std::size_t{1} << 22), [&] {
    return "the box holds " + std::to_string(cells) + " cells of one diameter, more than 2^22: the sampler keeps "
           "slots per cell, so a box this large for its diameter is refused";
  });
  cell_.resize(n_);
  for (std::size_t i = 0; i < n_; ++i)
    for (int k = 0; k < dim_; ++k) {
      const double v = x[i * dim_ + k];
      require(std::isfinite(v) && v >= 0.0 && v < box_[k], [&] {
        return "position " + std::to_string(i) + " axis " + std::to_string(k) + " = " + num(v) +
               " is outside [0, " + num(box_[k]) + ")";
      });
      cell_[i][k] = std::min(static_cast<int>(v / w_[k]), m_[k] - 1);
    }
  x_ = std::move(x);
  radius_.clear();
  for (const double d : diameters) radius_.push_back(0.5 * d);
  count_.assign(cells, 0);
  cap_ = dim_ == 1 ? 2 : dim_ == 2 ? 4 : 8;
  members_.assign(cells * static_cast<std::size_t>(cap_), -1);
  slot_.resize(n_);
  for (std::size_t i = 0; i < n_; ++i) insert(static_cast<int>(i), cell_index(cell_[i]));
  const double md = min_distance();
  require(md >= 1.0 - kOverlapTol, [&] {
    return "two spheres overlap: the closest pair is " + num(md) + (radius_.empty() ? " D" : " contact distances") +
           " apart";
  });
  rng_ = rng::Philox({kStreamWord, static_cast<std::uint32_t>(seed)});
}

std::size_t EventChain::cell_index(const std::array<int, 3>& c) const {
  return (static_cast<std::size_t>(c[2]) * m_[1] + c[1]) * m_[0] + c[0];
}

double EventChain::packing_fraction() const {
  double vol = 1.0;
  for (int k = 0; k < dim_; ++k) vol *= box_[k];
  if (radius_.empty()) return static_cast<double>(n_) * engine::limits::particle_volume(dim_, diameter_) / vol;
  double v = 0.0;
  for (const double r : radius_) v += engine::limits::particle_volume(dim_, 2.0 * r);
  return v / vol;
}

template <int Dim, class F>
[[gnu::always_inline]] inline void EventChain::for_around(const std::array<int, 3>& c, F&& f) const {
  // per axis the coordinates c - 1, c, c + 1 (wrapped) and the image shifts of their wraps
  std::array<std::array<int, 3>, 3> nc{};
  std::array<std::array<double, 3>, 3> ns{};
  for (int a = 0; a < Dim; ++a) {
    const int lo = c[a] - 1, hi = c[a] + 1;
    nc[a] = {lo < 0 ? lo + m_[a] : lo, c[a], hi >= m_[a] ? hi - m_[a] : hi};
    ns[a] = {lo < 0 ? -box_[a] : 0.0, 0.0, hi >= m_[a] ? box_[a] : 0.0};
  }
  constexpr int n1 = Dim >= 2 ? 3 : 1, n2 = Dim >= 3 ? 3 : 1;
  std::array<double, 3> shift{0, 0, 0};
  for (int o2 = 0; o2 < n2; ++o2) {
    shift[2] = ns[2][o2];
    for (int o1 = 0; o1 < n1; ++o1) {
      shift[1] = ns[1][o1];
      const std::size_t row = (static_cast<std::size_t>(nc[2][o2]) * m_[1] + nc[1][o1]) * m_[0];
      for (int o0 = 0; o0 < 3; ++o0) {
        shift[0] = ns[0][o0];
        const std::size_t cell = row + nc[0][o0];
        const int* mem = &members_[cell * cap_];
        for (int t = 0, count = count_[cell]; t < count; ++t) f(mem[t], shift);
      }
    }
  }
}

void EventChain::insert(int i, std::size_t cell) {
  if (count_[cell] == cap_) {  // a full cell: every cell's capacity doubles, members kept in order
    const int cap = 2 * cap_;
    std::vector<int> wider(count_.size() * static_cast<std::size_t>(cap), -1);
    for (std::size_t c = 0; c < count_.size(); ++c)
      std::copy_n(&members_[c * cap_], count_[c], &wider[c * cap]);
    members_ = std::move(wider);
    cap_ = cap;
  }
  slot_[i] = count_[cell];
  members_[cell * cap_ + count_[cell]++] = i;
}

void EventChain::remove(int i, std::size_t cell) {
  int* mem = &members_[cell * cap_];
  const int back = mem[--count_[cell]];
  mem[slot_[i]] = back;
  slot_[back] = slot_[i];
}

template <int Dim>
double EventChain::min_distance_d() const {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n_; ++i)
    for_around<Dim>(cell_[i], [&](int j, const std::array<double, 3>& shift) {
      if (static_cast<std::size_t>(j) <= i) return;
      double r2 = 0;
      for (int k = 0; k < Dim; ++k) {
        const double r = x_[j * Dim + k] + shift[k] - x_[i * Dim + k];
        r2 += r * r;
      }
      best = std::min(best, std::sqrt(r2) / (radius_.empty() ? diameter_ : radius_[i] + radius_[j]));
    });
  return best;
}

double EventChain::min_distance() const {
  return dim_ == 1 ? min_distance_d<1>() : dim_ == 2 ? min_distance_d<2>() : min_distance_d<3>();
}

ChainSums EventChain::run(std::uint64_t chains, double ell, const InterruptCheck& check) {
  double lmax = 0;
  for (int k = 0; k < dim_; ++k) lmax = std::max(lmax, box_[k]);
  require(std::isfinite(ell) && ell > 0 && ell <= 1e6 * lmax,
          [&] { return "chain length must be positive, finite and at most 1e6 box lengths, got " + num(ell); });
  ChainSums sums;
  InterruptPoll poll(check, 256);
  for (std::uint64_t c = 0; c < chains && n_ > 0; ++c) {
    poll.tick();  // between chains: totals() always counts whole chains
    const ChainSums one = radius_.empty()
                              ? (dim_ == 1 ? run_chain<1, false>(ell) : dim_ == 2 ? run_chain<2, false>(ell)
                                                                      : run_chain<3, false>(ell))
                              : (dim_ == 1 ? run_chain<1, true>(ell) : dim_ == 2 ? run_chain<2, true>(ell)
                                                                     : run_chain<3, true>(ell));
    sums += one;
    totals_ += one;
  }
  return sums;
}

// One chain along axis axis_ % d: measure before changing (this loop is the whole cost). Mixed:
// each pair's contact distance is r_i + r_j (a one-size chain reads no radius).
template <int Dim, bool Mixed>
ChainSums EventChain::run_chain(double ell) {
  const int k = static_cast<int>(axis_ % Dim);
  int i = std::min(static_cast<int>(rng_.next() * static_cast<double>(n_)), static_cast<int>(n_) - 1);
  const double length = ell * (0.5 + rng_.next());
  ++axis_;
  const double D2 = diameter_ * diameter_, half = 0.5 * diameter_;
  int prev = -1;
  double remaining = length;
  double lift_dx = 0.0;
  std::uint64_t lifts = 0, crossings = 0;
  while (remaining > 0) {
    std::array<int, 3>& c = cell_[i];
    double* xi = &x_[static_cast<std::size_t>(i) * Dim];
    const double face = std::max((c[k] + 1) * w_[k] - xi[k], 0.0);
    const bool to_face = face <= remaining;
    double best = to_face ? face : remaining;
    int hit = -1;
    double hit_dx = 0.0;
    for_around<Dim>(c, [&](int j, const std::array<double, 3>& shift) [[gnu::always_inline]] {
      if (j == i) return;
      const double* xj = &x_[static_cast<std::size_t>(j) * Dim];
      const double rk = xj[k] + shift[k] - xi[k];
      double sig2 = D2, sig_half = half;
      if constexpr (Mixed) {
        const double sig = radius_[i] + radius_[j];
        sig2 = sig * sig;
        sig_half = 0.5 * sig;
      }
      if (rk <= 0.0 || (j == prev && rk < sig_half)) return;
      double b2 = 0.0;
      for (int a = 0; a < Dim; ++a) {
        if (a == k) continue;
        const double r = xj[a] + shift[a] - xi[a];
        b2 += r * r;
      }
      if (b2 >= sig2) return;
      const double step = std::max(rk - std::sqrt(sig2 - b2), 0.0);
      if (step < best) {
        best = step;
        hit = j;
        hit_dx = rk - step;
      }
    });
    remaining -= best;
    if (hit >= 0) {
      xi[k] += best;
      lift_dx += hit_dx;
      ++lifts;
      prev = i;
      i = hit;
    } else if (to_face) {
      // on the face: into the next cell along k (wrapping the coordinate at the box's end)
      const std::size_t from = cell_index(c);
      ++crossings;
      if (c[k] + 1 == m_[k]) {
        c[k] = 0;
        xi[k] = 0.0;
      } else {
        c[k] += 1;
        xi[k] = c[k] * w_[k];
      }
      remove(i, from);
      insert(i, cell_index(c));
    } else {
      xi[k] += best;
      remaining = 0.0;
    }
  }
  ChainSums one;
  one.chains = 1;
  one.displacement = length;
  one.lift_dx = lift_dx;
  one.lifts = lifts;
  one.crossings = crossings;
  return one;
}

}  // namespace revcol::ecmc
