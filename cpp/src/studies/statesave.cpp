// The state-saving study (see statesave.hpp for the workload and its maths).
#include "revcol/studies/statesave.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "revcol/collide/pair.hpp"
#include "revcol/collide/pair2d_exact.hpp"
#include "revcol/collide/pair2d_paper.hpp"
#include "revcol/error.hpp"
#include "revcol/rng/clcg4.hpp"
#include "revcol/rng/philox.hpp"
#include "revcol/rng/streams.hpp"

namespace revcol::statesave {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

constexpr double kBox = 1.0;                    // positions start in [0, kBox)^2
constexpr double kTicksPerMean = 4294967296.0;  // 2^32 ticks per mean_dt
constexpr std::uint32_t kStartKey = 0x53544152U;  // "STAR": Philox key word 0 of the start
constexpr std::uint64_t kMaxCollisions = std::uint64_t{1} << 32;
constexpr std::uint64_t kGenBytes = 16, kClockBytes = 8, kPairBytes = 8;
static_assert(sizeof(rng::CLCG4) == kGenBytes && sizeof(rng::Philox) == kGenBytes,
              "record_bytes() counts 16 bytes of generator state");

// Decision log entries: step << 2 | kind.
constexpr std::uint64_t kGraze = 1, kPlus = 2, kMinus = 3;

// The start of particle k: a pure function of (seed, k), so the check regenerates it.
struct Start {
  rng::Philox g;
  explicit Start(std::uint64_t seed) : g({kStartKey, static_cast<std::uint32_t>(seed)}, 0) {}
  void at(std::uint64_t k, double& x, double& y, double& vx, double& vy) const {
    x = kBox * g.at(4 * k);
    y = kBox * g.at(4 * k + 1);
    vx = 2.0 * g.at(4 * k + 2) - 1.0;
    vy = 2.0 * g.at(4 * k + 3) - 1.0;
  }
};

// A pre log entry: the step and the pair's pre velocities, restored bit for bit.
struct PreEntry {
  std::uint64_t step;
  PairV<2> v;
};
static_assert(sizeof(PreEntry) == 40, "the pre log counts 40 bytes per entry");

// One run of the workload for one operator and one generator type.
template <class Op, class Gen>
class Workload {
 public:
  Workload(const Config& c, const Op& op, bool pre_log)
      : c_(c),
        op_(op),
        n_(c.particles),
        lazy_(c.transport == Transport::lazy),
        rc_(c.variant == Variant::rc),
        pre_log_on_(pre_log),
        tick_(c.mean_dt / kTicksPerMean),
        npairs_(c.particles * (c.particles - 1)),
        gen_(rng::make_generator<Gen>(0, c.seed, 1)),
        start_gen_(gen_) {
    px_.resize(n_);
    py_.resize(n_);
    vx_.resize(n_);
    vy_.resize(n_);
    const Start s(c.seed);
    for (std::uint64_t k = 0; k < n_; ++k) {
      s.at(k, px_[k], py_[k], vx_[k], vy_[k]);
      vmax0_ = std::max({vmax0_, std::fabs(vx_[k]), std::fabs(vy_[k])});
    }
    // the pre log bound in the form |w| |n||w| f > tol vmax0 |p| (flux) or |w| f > tol vmax0 (uniform)
    graze_factor_ = std::ldexp(c.law == Law::uniform ? 0.5 * 3.141592653589793 : 1.0, -(c.bits + 1));
    graze_limit_ = c.grazing_tol * vmax0_;
    allocate_records();
  }

  // N_c steps forward, saving what the variant saves.
  void forward(Result& r) {
    InterruptPoll poll(c_.interrupt, poll_every());
    const auto t0 = Clock::now();
    for (std::uint64_t k = 0; k < c_.collisions; ++k) {
      poll.tick();
      step_forward(k);
    }
    r.forward_s = seconds_since(t0);
    r.draws = draws_;
    r.grazes = grazes_;
    r.rare_log_entries = rare_.size();
    r.decision_log_entries = decisions_.size();
    r.pre_log_entries = pre_log_.size();
    r.log_bytes = rare_.bytes() + decisions_.size() * sizeof(std::uint64_t) + pre_log_.size() * sizeof(PreEntry);
    r.bytes_saved = rc_ ? r.log_bytes : saved_bytes();
  }

  // N_c steps back: restoring (ss) or reverse computation (rc). A step the reverse operator
  // refuses stops the rollback and is reported.
  void rollback(Result& r) {
    InterruptPoll poll(c_.interrupt, poll_every());
    const auto t0 = Clock::now();
    std::uint64_t k = c_.collisions;
    try {
      if (rc_) {
        for (; k > 0; --k) {
          poll.tick();
          step_reverse(k - 1);
        }
      } else {
        for (; k > 0; --k) {
          poll.tick();
          restore(k - 1);
        }
      }
    } catch (const InvalidArgument& e) {
      r.error = "rollback of step " + std::to_string(k - 1) + " failed: " + e.what();
    }
    r.rollback_s = seconds_since(t0);
    r.draws_undone = undone_;
  }

  // Positions at the current time (lazy: x0 + v t) and velocities.
  Snapshot snapshot() const {
    Snapshot s{px_, py_, vx_, vy_, ticks_};
    if (lazy_) {
      const double t = time();
      for (std::uint64_t k = 0; k < n_; ++k) {
        s.x[k] = px_[k] + vx_[k] * t;
        s.y[k] = py_[k] + vy_[k] * t;
      }
    }
    return s;
  }

  // Compares the state with the regenerated start.
  void check(Result& r) const {
    const Start s(c_.seed);
    double ex = 0.0, ev = 0.0;
    bool same = true;
    auto worse = [](double e, double d) { return std::isnan(d) ? std::numeric_limits<double>::infinity() : std::max(e, d); };
    for (std::uint64_t k = 0; k < n_; ++k) {
      double x, y, vx, vy;
      s.at(k, x, y, vx, vy);
      same = same && px_[k] == x && py_[k] == y && vx_[k] == vx && vy_[k] == vy;
      ex = worse(ex, std::max(std::fabs(px_[k] - x), std::fabs(py_[k] - y)));
      ev = worse(ev, std::max(std::fabs(vx_[k] - vx), std::fabs(vy_[k] - vy)));
    }
    r.max_rel_error_x = ex / kBox;
    r.max_rel_error_v = vmax0_ > 0.0 ? ev / vmax0_ : ev;
    r.max_rel_error = std::max(r.max_rel_error_x, r.max_rel_error_v);
    r.bit_exact = same;
    r.rng_restored = gen_ == start_gen_;
    r.clock_restored = ticks_ == 0;
    const bool logs_empty = rare_.size() == 0 && decisions_.empty() && pre_log_.empty();
    r.restored = r.error.empty() && r.rng_restored && r.clock_restored &&
                 (rc_ ? logs_empty && r.max_rel_error <= 1e-9 : same);
  }

 private:
  double time() const { return static_cast<double>(ticks_) * tick_; }
  // steps between interrupt checks: about 2^20 particle updates (an eager step moves all N)
  std::uint32_t poll_every() const {
    return static_cast<std::uint32_t>(std::max<std::uint64_t>(1, (std::uint64_t{1} << 20) / std::max<std::uint64_t>(1, lazy_ ? 1 : n_)));
  }

  // u_pair -> ordered pair i != j, uniform over the N(N-1) ordered pairs.
  void pair(double u, std::uint32_t& i, std::uint32_t& j) const {
    const double m = std::floor(u * static_cast<double>(npairs_));
    std::uint64_t k = m > 0.0 ? static_cast<std::uint64_t>(m) : 0;
    if (k >= npairs_) k = npairs_ - 1;  // u = 1 (CLCG4 can return it)
    i = static_cast<std::uint32_t>(k / (n_ - 1));
    j = static_cast<std::uint32_t>(k % (n_ - 1));
    if (j >= i) ++j;
  }
  // u_time -> ticks of an exponential time with mean 2^32 ticks.
  static std::uint64_t ticks_of(double u) {
    const double e = -std::log(std::max(u, 0x1p-53));
    return static_cast<std::uint64_t>(std::floor(e * kTicksPerMean));
  }

  // Eager transport: every particle, x += v dt. Measure before changing: this loop is the
  // whole cost of an eager RC step at large N.
  void transport(double dt) {
    double* __restrict x = px_.data();
    double* __restrict y = py_.data();
    const double* __restrict vx = vx_.data();
    const double* __restrict vy = vy_.data();
    for (std::uint64_t k = 0; k < n_; ++k) {
      x[k] += vx[k] * dt;
      y[k] += vy[k] * dt;
    }
  }

  void step_forward(std::uint64_t k) {
    const Gen before = gen_;
    const double up = gen_.next(), ut = gen_.next(), g = gen_.next();
    draws_ += draws_per_step;
    std::uint32_t i, j;
    pair(up, i, j);
    const std::uint64_t dt = ticks_of(ut);
    if (!rc_) save(k, before, i, j);
    ticks_ += dt;
    if (!lazy_) transport(static_cast<double>(dt) * tick_);
    collide_forward(k, i, j, g);
  }

  void step_reverse(std::uint64_t k) {
    const double g = gen_.prev(), ut = gen_.prev(), up = gen_.prev();
    undone_ += draws_per_step;
    std::uint32_t i, j;
    pair(up, i, j);
    const std::uint64_t dt = ticks_of(ut);
    collide_reverse(k, i, j, g);
    if (!lazy_) transport(-(static_cast<double>(dt) * tick_));  // x + v (-dt) == x - v dt exactly
    ticks_ -= dt;
  }

  // The pair's positions at the collision (eager: stored; lazy: x0 + v t) give the normal n.
  void normal_of(std::uint32_t i, std::uint32_t j, double t, double& nx, double& ny) const {
    if (lazy_) {
      nx = (px_[i] + vx_[i] * t) - (px_[j] + vx_[j] * t);
      ny = (py_[i] + vy_[i] * t) - (py_[j] + vy_[j] * t);
    } else {
      nx = px_[i] - px_[j];
      ny = py_[i] - py_[j];
    }
  }
  PairV<2> velocities(std::uint32_t i, std::uint32_t j) const {
    return {{vx_[i], vy_[i]}, {vx_[j], vy_[j]}};
  }
  // Writes the pair's new velocities; lazy transport keeps the positions: x0 += (v_old - v_new) t.
  void set_velocities(std::uint32_t i, std::uint32_t j, const PairV<2>& old_v, const PairV<2>& new_v, double t) {
    if (lazy_) {
      px_[i] += (old_v.i[0] - new_v.i[0]) * t;
      py_[i] += (old_v.i[1] - new_v.i[1]) * t;
      px_[j] += (old_v.j[0] - new_v.j[0]) * t;
      py_[j] += (old_v.j[1] - new_v.j[1]) * t;
    }
    vx_[i] = new_v.i[0];
    vy_[i] = new_v.i[1];
    vx_[j] = new_v.j[0];
    vy_[j] = new_v.j[1];
  }

  void collide_forward(std::uint64_t k, std::uint32_t i, std::uint32_t j, double g) {
    const double t = lazy_ ? time() : 0.0;
    double nx, ny;
    normal_of(i, j, t, nx, ny);
    const PairV<2> pre = velocities(i, j);
    const double wx = pre.i[0] - pre.j[0], wy = pre.i[1] - pre.j[1];
    const double n2 = nx * nx + ny * ny, w2 = wx * wx + wy * wy;
    const double p = nx * wx + ny * wy;
    const double nw = std::sqrt(n2 * w2);
    if (!(std::fabs(p) > grazing_band * nw)) {  // grazes (also a zero or non-finite n or w)
      ++grazes_;
      if (rc_ && std::fabs(p) > 0.5 * grazing_band * nw) decisions_.push_back(k << 2 | kGraze);
      return;
    }
    const double s = p < 0.0 ? 1.0 : -1.0;  // orient so that the pair approaches
    const PairV<2> post = op_.forward(pre, {s * nx, s * ny}, g, rare_);
    if (rc_) {
      if (pre_log_on_ && needs_pre_log(p, nw, std::sqrt(w2))) pre_log_.push_back({k, pre});
      const double qx = post.i[0] - post.j[0], qy = post.i[1] - post.j[1];
      const double pq = s * (nx * qx + ny * qy);
      if (!(pq > 2.0 * grazing_band * std::sqrt(n2 * (qx * qx + qy * qy))))
        decisions_.push_back(k << 2 | (s > 0.0 ? kPlus : kMinus));
    }
    set_velocities(i, j, pre, post, t);
  }

  void collide_reverse(std::uint64_t k, std::uint32_t i, std::uint32_t j, double g) {
    const double t = lazy_ ? time() : 0.0;
    double nx, ny;
    normal_of(i, j, t, nx, ny);
    const PairV<2> post = velocities(i, j);
    double s;
    if (!decisions_.empty() && (decisions_.back() >> 2) == k) {
      const std::uint64_t kind = decisions_.back() & 3U;
      decisions_.pop_back();
      if (kind == kGraze) return;
      s = kind == kPlus ? 1.0 : -1.0;
    } else {
      const double wx = post.i[0] - post.j[0], wy = post.i[1] - post.j[1];
      const double p = nx * wx + ny * wy;
      if (!(std::fabs(p) > grazing_band * std::sqrt((nx * nx + ny * ny) * (wx * wx + wy * wy)))) return;
      s = p > 0.0 ? 1.0 : -1.0;  // the orientation along which the post state separates
    }
    PairV<2> pre = op_.reverse(post, {s * nx, s * ny}, g, rare_);
    if (!pre_log_.empty() && pre_log_.back().step == k) {
      pre = pre_log_.back().v;
      pre_log_.pop_back();
    }
    set_velocities(i, j, post, pre, t);
  }

  // Exact mode: would restoring this pre state at its cell centre move a velocity by more
  // than grazing_tol max|v_0|? Flux: |w| 2^-(K+1) / cos(eta), cos(eta) = |p| / (|n||w|).
  bool needs_pre_log(double p, double nw, double wn) const {
    if (c_.law == Law::uniform) return wn * graze_factor_ > graze_limit_;
    return wn * graze_factor_ * nw > graze_limit_ * std::fabs(p);
  }

  // --- state saving -------------------------------------------------------------------
  // Per step: bulk (ss1: 4N doubles, ss2: 2N), generator state, clock, and for ss2/ssp the
  // pair (2 indices, 4 velocities) and for ssp the pair's x0 (4 doubles).
  std::uint64_t bulk_per_step() const {
    if (c_.variant == Variant::ss1) return 4 * n_;
    if (c_.variant == Variant::ss2) return 2 * n_;
    return 0;
  }
  bool saves_pair() const { return c_.variant == Variant::ss2 || c_.variant == Variant::ssp; }
  template <class T>
  static std::unique_ptr<T[]> buffer(std::uint64_t count, bool prefault) {
    std::unique_ptr<T[]> b(new T[count]);  // uninitialized: no page is touched yet
    if (prefault && count > 0) std::memset(static_cast<void*>(b.get()), 0, count * sizeof(T));
    return b;
  }
  // Allocates every record before the clock starts. prefault touches every page now (the
  // records are resident, as in a simulator that recycles its state buffers); otherwise
  // pages are faulted in when first written, inside the forward time.
  void allocate_records() {
    if (rc_) return;
    const std::uint64_t nc = c_.collisions;
    const bool pf = c_.prefault;
    if (bulk_per_step() > 0) bulk_ = buffer<double>(bulk_per_step() * nc, pf);
    gens_ = buffer<unsigned char>(sizeof(Gen) * nc, pf);
    clocks_ = buffer<std::uint64_t>(nc, pf);
    if (saves_pair()) {
      pairs_ = buffer<std::uint32_t>(2 * nc, pf);
      pair_v_ = buffer<double>(4 * nc, pf);
    }
    if (c_.variant == Variant::ssp) pair_x_ = buffer<double>(4 * nc, pf);
  }
  // Bytes written into the records so far.
  std::uint64_t saved_bytes() const {
    std::uint64_t per = bulk_per_step() * sizeof(double) + sizeof(Gen) + sizeof(std::uint64_t);
    if (saves_pair()) per += 2 * sizeof(std::uint32_t) + 4 * sizeof(double);
    if (c_.variant == Variant::ssp) per += 4 * sizeof(double);
    return saved_steps_ * per;
  }
  void save(std::uint64_t k, const Gen& before, std::uint32_t i, std::uint32_t j) {
    const std::uint64_t nb = n_ * sizeof(double);
    if (bulk_) {
      double* rec = bulk_.get() + k * bulk_per_step();
      std::memcpy(rec, px_.data(), nb);
      std::memcpy(rec + n_, py_.data(), nb);
      if (c_.variant == Variant::ss1) {
        std::memcpy(rec + 2 * n_, vx_.data(), nb);
        std::memcpy(rec + 3 * n_, vy_.data(), nb);
      }
    }
    if (saves_pair()) {
      pairs_[2 * k] = i;
      pairs_[2 * k + 1] = j;
      double* v = &pair_v_[4 * k];
      v[0] = vx_[i];
      v[1] = vy_[i];
      v[2] = vx_[j];
      v[3] = vy_[j];
    }
    if (pair_x_) {
      double* x = &pair_x_[4 * k];
      x[0] = px_[i];
      x[1] = py_[i];
      x[2] = px_[j];
      x[3] = py_[j];
    }
    std::memcpy(&gens_[sizeof(Gen) * k], &before, sizeof(Gen));
    clocks_[k] = ticks_;
    ++saved_steps_;
  }
  void restore(std::uint64_t k) {
    const std::uint64_t nb = n_ * sizeof(double);
    if (bulk_) {
      const double* rec = bulk_.get() + k * bulk_per_step();
      std::memcpy(px_.data(), rec, nb);
      std::memcpy(py_.data(), rec + n_, nb);
      if (c_.variant == Variant::ss1) {
        std::memcpy(vx_.data(), rec + 2 * n_, nb);
        std::memcpy(vy_.data(), rec + 3 * n_, nb);
      }
    }
    if (saves_pair()) {
      const std::uint32_t i = pairs_[2 * k], j = pairs_[2 * k + 1];
      const double* v = &pair_v_[4 * k];
      vx_[i] = v[0];
      vy_[i] = v[1];
      vx_[j] = v[2];
      vy_[j] = v[3];
      if (pair_x_) {
        const double* x = &pair_x_[4 * k];
        px_[i] = x[0];
        py_[i] = x[1];
        px_[j] = x[2];
        py_[j] = x[3];
      }
    }
    std::memcpy(&gen_, &gens_[sizeof(Gen) * k], sizeof(Gen));
    ticks_ = clocks_[k];
  }

  const Config& c_;
  const Op& op_;
  const std::uint64_t n_;
  const bool lazy_, rc_, pre_log_on_;
  const double tick_;
  const std::uint64_t npairs_;
  Gen gen_;
  const Gen start_gen_;
  std::vector<double> px_, py_, vx_, vy_;  // eager: positions at time t; lazy: x0 = x - v t
  std::uint64_t ticks_ = 0;
  double vmax0_ = 0.0, graze_factor_ = 0.0, graze_limit_ = 0.0;
  RareLog rare_;                       // the exact operator's rare log
  std::vector<std::uint64_t> decisions_;  // rc: the decision log
  std::vector<PreEntry> pre_log_;      // rc, exact mode: the pre log
  std::uint64_t draws_ = 0, undone_ = 0, grazes_ = 0, saved_steps_ = 0;
  // state saving records, one slot per step
  std::unique_ptr<double[]> bulk_, pair_v_, pair_x_;
  std::unique_ptr<unsigned char[]> gens_;  // generator states (trivially copyable)
  std::unique_ptr<std::uint64_t[]> clocks_;
  std::unique_ptr<std::uint32_t[]> pairs_;
  static_assert(std::is_trivially_copyable_v<Gen>, "records copy the generator's bytes");
};

template <class Op, class Gen>
void run_with(const Config& c, const Op& op, bool pre_log, Result& r) {
  Workload<Op, Gen> w(c, op, pre_log);
  if (c.capture) r.start = w.snapshot();
  w.forward(r);
  if (c.capture) r.turn = w.snapshot();
  w.rollback(r);
  if (c.capture) r.end = w.snapshot();
  w.check(r);
  r.peak_rss_bytes = peak_rss_bytes();
}

template <class Gen>
void run_gen(const Config& c, Result& r) {
  if (c.mode == Mode::exact) {
    const Pair2DExact op(c.law, c.bits);
    run_with<Pair2DExact, Gen>(c, op, std::isfinite(c.grazing_tol), r);
  } else {
    const Pair2DPaper op;
    run_with<Pair2DPaper, Gen>(c, op, false, r);
  }
}

// The value after `key` in /proc/self/status, in bytes (0 if absent).
std::uint64_t proc_status_bytes(const char* key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  const std::size_t len = std::strlen(key);
  while (std::getline(f, line)) {
    if (line.compare(0, len, key) == 0) return std::stoull(line.substr(len)) * 1024;  // "  123 kB"
  }
  return 0;
}

}  // namespace

const char* to_string(Variant v) {
  switch (v) {
    case Variant::ss1: return "ss1";
    case Variant::ss2: return "ss2";
    case Variant::ssp: return "ssp";
    case Variant::rc: return "rc";
  }
  return "?";
}

const char* to_string(Transport t) { return t == Transport::lazy ? "lazy" : "eager"; }

Variant parse_variant(const std::string& s) {
  if (s == "ss1") return Variant::ss1;
  if (s == "ss2") return Variant::ss2;
  if (s == "ssp") return Variant::ssp;
  if (s == "rc") return Variant::rc;
  throw InvalidArgument("variant must be 'ss1', 'ss2', 'ssp' or 'rc', got '" + s + "'");
}

Transport parse_transport(const std::string& s) {
  if (s == "eager") return Transport::eager;
  if (s == "lazy") return Transport::lazy;
  throw InvalidArgument("transport must be 'eager' or 'lazy', got '" + s + "'");
}

std::vector<std::string> variant_names(Transport t) {
  if (t == Transport::lazy) return {"ss1", "ss2", "ssp", "rc"};
  return {"ss1", "ss2", "rc"};
}

void validate(const Config& c) {
  require(c.particles >= 2 && c.particles <= max_particles, [&] {
    return "particles must be in [2, 2^26 = " + std::to_string(max_particles) + "], got " + std::to_string(c.particles);
  });
  require(c.collisions >= 1 && c.collisions <= kMaxCollisions, [&] {
    return "collisions must be in [1, 2^32], got " + std::to_string(c.collisions);
  });
  require(c.variant != Variant::ssp || c.transport == Transport::lazy,
          "variant 'ssp' (save the pair only) needs lazy transport: eager transport moves every particle");
  require(c.rng == "clcg4" || c.rng == "philox", [&] { return "rng must be 'clcg4' or 'philox', got '" + c.rng + "'"; });
  require(c.seed <= std::numeric_limits<std::uint32_t>::max(), [&] {
    return "seed must be in [0, 2^32 - 1], got " + std::to_string(c.seed);
  });
  require(std::isfinite(c.mean_dt) && c.mean_dt > 0.0, [&] {
    return "mean_dt must be positive and finite, got " + std::to_string(c.mean_dt);
  });
  require(c.grazing_tol > 0.0, [&] {  // NaN fails too; inf turns the pre log off
    return "grazing_tol must be positive (inf turns the pre log off), got " + std::to_string(c.grazing_tol);
  });
  const FixedPoint bits(c.bits);  // validates K
  (void)bits;
}

std::uint64_t record_bytes(const Config& c) {
  const std::uint64_t n = c.particles;
  switch (c.variant) {
    case Variant::ss1: return 32 * n + kClockBytes + kGenBytes;
    case Variant::ss2: return 16 * n + kPairBytes + 32 + kClockBytes + kGenBytes;
    case Variant::ssp: return kPairBytes + 64 + kClockBytes + kGenBytes;
    case Variant::rc: return 0;
  }
  return 0;
}

std::uint64_t projected_bytes(const Config& c) {
  validate(c);
  return record_bytes(c) * c.collisions;  // < 2^31 * 2^32: no overflow
}

Result run(const Config& c) {
  validate(c);
  Result r;
  r.config = c;
  r.record_bytes = record_bytes(c);
  r.projected_bytes = projected_bytes(c);
  r.state_bytes = 32 * c.particles;
  r.rss_before_bytes = current_rss_bytes();
  if (r.projected_bytes > c.budget_bytes) {
    r.skipped = true;
    r.peak_rss_bytes = peak_rss_bytes();
    return r;
  }
  if (c.rng == "clcg4") run_gen<rng::CLCG4>(c, r);
  else run_gen<rng::Philox>(c, r);
  return r;
}

std::uint64_t peak_rss_bytes() {
  const std::uint64_t hwm = proc_status_bytes("VmHWM:");
  if (hwm > 0) return hwm;
  struct rusage u {};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<std::uint64_t>(u.ru_maxrss) * 1024;  // Linux: KiB
}

std::uint64_t current_rss_bytes() { return proc_status_bytes("VmRSS:"); }

}  // namespace revcol::statesave
