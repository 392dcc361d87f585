// The word stream of randomness.hpp: generators (good and bad), the forward chain over
// every operator signature, and the chart that maps a post state to words.
#include "revcol/randomness.hpp"

#include <algorithm>
#include <cstdio>
#include <functional>

#include "paper_adapt.hpp"
#include "revcol/collide/cases.hpp"
#include "revcol/collide/pair2d_exact.hpp"
#include "revcol/collide/pair2d_paper.hpp"
#include "revcol/error.hpp"
#include "revcol/rng/clcg4.hpp"
#include "revcol/rng/philox.hpp"
#include "revcol/rng/streams.hpp"

namespace revcol::randomness {
namespace {

// --- generators ------------------------------------------------------------------------

struct Uniforms {
  virtual ~Uniforms() = default;
  virtual double next() = 0;
};

template <class G>
struct Wrapped final : Uniforms {
  G g;
  explicit Wrapped(G gen) : g(std::move(gen)) {}
  double next() override { return g.next(); }
};

// RANDU: x <- 65539 x mod 2^31 from an odd start; G = x / 2^31 in (0, 1). Its outputs obey
// x_(k+2) = 6 x_(k+1) - 9 x_k (mod 2^31): every triple lies on one of 15 planes.
struct Randu final : Uniforms {
  std::uint32_t x;
  explicit Randu(std::uint64_t seed) : x(static_cast<std::uint32_t>((2 * seed + 1) & 0x7fffffffu)) {}
  double next() override {
    x = static_cast<std::uint32_t>((65539ull * x) & 0x7fffffffull);
    return x * 0x1.0p-31;
  }
};

// Philox whose every 100th draw repeats the draw before it (a subtle defect: 1% of draws).
struct Repeat100 final : Uniforms {
  rng::Philox g;
  std::uint64_t count = 0;
  double last = 0.5;
  explicit Repeat100(rng::Philox gen) : g(gen) {}
  double next() override {
    if (++count % 100 != 0) last = g.next();
    return last;
  }
};

std::unique_ptr<Uniforms> make_uniforms(const StreamConfig& c) {
  if (c.rng == "clcg4") return std::make_unique<Wrapped<rng::CLCG4>>(rng::make_generator<rng::CLCG4>(0, c.seed, 1));
  if (c.rng == "philox") return std::make_unique<Wrapped<rng::Philox>>(rng::make_generator<rng::Philox>(0, c.seed, 1));
  if (c.rng == "randu") return std::make_unique<Randu>(c.seed);
  if (c.rng == "philox-repeat100") return std::make_unique<Repeat100>(rng::make_generator<rng::Philox>(0, c.seed, 1));
  throw InvalidArgument("rng must be clcg4, philox, randu or philox-repeat100, got '" + c.rng + "'");
}

// --- sources: one collision (or one draw) per step, its coordinates in [0,1) ---------------

struct Source {
  virtual ~Source() = default;
  virtual int width() const = 0;
  virtual void step(Uniforms& gen, double* u) = 0;
  std::uint64_t restarts = 0;
};

struct Raw final : Source {
  int width() const override { return 1; }
  void step(Uniforms& gen, double* u) override { u[0] = gen.next(); }
};

template <int Dim>
void negate(PairV<Dim>& v) {
  for (int k = 0; k < Dim; ++k) { v.i[k] = -v.i[k]; v.j[k] = -v.j[k]; }
}
template <std::size_t Dim>
void negate(std::array<std::array<double, Dim>, 3>& v) {  // paper::Triple<Dim>
  for (auto& p : v)
    for (double& x : p) x = -x;
}
void negate(std::vector<double>& v) {
  for (double& x : v) x = -x;
}

// The paper's illustration forward only: draws, collision t, map the post state, negate it.
// forward(pre, g, post, t) throws InvalidArgument on a state it refuses; valid(post) says
// whether the post state separates. With may_fail (paper mode) a refused or invalid step
// restarts the chain from its start; otherwise the exception propagates.
template <class State>
class Chain final : public Source {
 public:
  using Forward = std::function<void(const State&, const double*, State&, std::uint64_t)>;
  using Valid = std::function<bool(const State&)>;
  using Map = std::function<void(const State&, double*)>;

  Chain(State start, int draws, bool may_fail, Forward f, Valid valid, Map map)
      : start_(start), v_(start), post_(start), g_(draws), may_fail_(may_fail),
        forward_(std::move(f)), valid_(std::move(valid)), map_(std::move(map)) {}
  int width() const override { return static_cast<int>(g_.size()); }
  void step(Uniforms& gen, double* u) override {
    for (int fails = 0;; ++fails) {
      require(fails < 1000, "the chain failed 1000 times in a row: no valid collision from this start");
      for (double& g : g_) g = gen.next();
      bool ok = false;
      try {
        forward_(v_, g_.data(), post_, t_);
        ok = valid_(post_);
      } catch (const InvalidArgument&) {
        if (!may_fail_) throw;
      }
      require(ok || may_fail_, "exact-mode post state does not separate");
      if (!ok) {
        v_ = start_;
        t_ = 0;
        ++restarts;
        continue;
      }
      map_(post_, u);
      v_ = post_;
      negate(v_);  // reverse the velocities to create the next collision
      ++t_;
      return;
    }
  }

 private:
  State start_, v_, post_;
  std::vector<double> g_;
  bool may_fail_;
  Forward forward_;
  Valid valid_;
  Map map_;
  std::uint64_t t_ = 0;
};

// --- the cases -----------------------------------------------------------------------------

// pair2d in either mode: verify()'s start and normal (1, 1), invariants held; the words are
// the chart of `mapper` (the exact operator of the mapping law).
template <class Op>
std::unique_ptr<Source> pair2d(Op op, Law cdf_law, int bits, bool may_fail) {
  const PairV<2> v{{0.25, -0.5}, {1.0, 0.75}};
  const std::array<double, 2> n{1.0, 1.0};
  const Invariants<2> inv{{v.i[0] + v.j[0], v.i[1] + v.j[1]},
                          v.i[0] * v.i[0] + v.i[1] * v.i[1] + v.j[0] * v.j[0] + v.j[1] * v.j[1]};
  op.check_pre(v, n, &inv);
  const Frame2 f(n);
  const Pair2DExact mapper(cdf_law, bits);
  auto log = std::make_shared<RareLog>();
  return std::make_unique<Chain<PairV<2>>>(
      v, 1, may_fail,
      [op, n, inv, log](const PairV<2>& pre, const double* g, PairV<2>& post, std::uint64_t) {
        post = op.forward(pre, n, g[0], *log, &inv);
        log->clear();  // never reversed: nothing to keep
      },
      [f](const PairV<2>& post) { return f.normal_part(relative(post)) > 0.0; },
      [f, mapper](const PairV<2>& post, double* u) {
        const std::array<double, 2> w = relative(post);
        u[0] = mapper.chart(f.normal_part(w), f.tangent_part(w), std::hypot(w[0], w[1]));
      });
}

// Every named case in exact mode through the general operator (verify_exact.cpp's chain:
// the held momentum follows the sign of the negated velocities).
std::unique_ptr<Source> exact_case(const NamedCase& nc, const StreamConfig& c) {
  auto op = std::make_shared<const ExactCollision>(exact_operator(nc, c.law, c.bits));
  auto mapper = std::make_shared<const ExactCollision>(exact_operator(nc, c.cdf_law, c.bits));
  require(op->draws() >= 1, [&] { return nc.name + " has no free parameter (d_n = 0): no words"; });
  const std::vector<double> v = approaching_state(*op, 1);
  auto mp = std::make_shared<std::vector<double>>(nc.d, 0.0);
  auto mn = std::make_shared<std::vector<double>>(nc.d, 0.0);
  double e = 0.0;
  for (int i = 0; i < nc.n; ++i)
    for (int a = 0; a < nc.d; ++a) {
      (*mp)[a] += v[i * nc.d + a];
      e += v[i * nc.d + a] * v[i * nc.d + a];
    }
  for (int a = 0; a < nc.d; ++a) (*mn)[a] = -(*mp)[a];
  auto log = std::make_shared<RareLog>();
  return std::make_unique<Chain<std::vector<double>>>(
      v, op->draws(), false,
      [op, mp, mn, e, log](const std::vector<double>& pre, const double* g, std::vector<double>& post,
                           std::uint64_t t) {
        const Held h{t % 2 ? mn->data() : mp->data(), e};
        op->forward(pre.data(), g, post.data(), *log, &h);
        log->clear();
      },
      [op](const std::vector<double>& post) {
        for (double s : op->normal_speeds(post.data()))
          if (!(s > 0.0)) return op->logs(post.data());  // the rare log serves it
        return true;
      },
      [mapper](const std::vector<double>& post, double* u) {
        const std::vector<double> ch = mapper->chart(post.data());
        for (std::size_t k = 0; k < ch.size(); ++k) u[k] = ch[k];
      });
}

// A paper-mode case of paper_study (pair3d, triple1d, triple2d-c1..c4): verify_paper.cpp's
// chain, mapped by the exact operator's uniform chart of the same geometry.
template <class Op>
std::unique_ptr<Source> paper_chain(const paper::PaperCase& pc, const StreamConfig& c) {
  using A = paper::adapt::Adapter<Op>;
  const Op op = A::make(paper::StudyConfig{});
  const typename Op::Geometry x = A::geometry(pc.geometry);
  const typename Op::State v = A::state(pc.velocities);
  const typename Op::Inv inv = A::invariants(v);
  op.check_pre(v, x, &inv);
  const typename A::Pred pred(x);
  auto mapper = std::make_shared<const ExactCollision>(exact_operator(named_case(pc.name), c.cdf_law, c.bits));
  auto log = std::make_shared<RareLog>();
  using State = typename Op::State;
  return std::make_unique<Chain<State>>(
      v, Op::draws, true,
      [op, x, inv, log](const State& pre, const double* g, State& post, std::uint64_t) {
        typename Op::Draws d;
        for (std::size_t k = 0; k < d.size(); ++k) d[k] = g[k];
        post = op.forward(pre, x, d, *log, &inv);
        log->clear();
      },
      [pred](const State& post) { return pred.separates(post); },
      [mapper](const State& post, double* u) {
        const std::vector<double> f = A::flat(post);
        const std::vector<double> ch = mapper->chart(f.data());
        for (std::size_t k = 0; k < ch.size(); ++k) u[k] = ch[k];
      });
}

std::unique_ptr<Source> make_source(const StreamConfig& c) {
  FixedPoint check_bits(c.bits);  // validates K
  (void)check_bits;
  if (c.case_name == "raw") return std::make_unique<Raw>();
  if (c.mode == Mode::exact) {
    if (c.case_name == "pair2d") return pair2d(Pair2DExact(c.law, c.bits), c.cdf_law, c.bits, false);
    for (const NamedCase& nc : named_cases())
      if (nc.name == c.case_name) return exact_case(nc, c);
  } else if (c.mode == Mode::paper) {
    if (c.case_name == "pair2d") return pair2d(Pair2DPaper(), c.cdf_law, c.bits, true);
    for (const paper::PaperCase& pc : paper::paper_cases()) {
      if (pc.name != c.case_name) continue;
      if (pc.name == "pair3d") return paper_chain<Pair3DPaper>(pc, c);
      if (pc.name == "triple1d") return paper_chain<Triple1DPaper>(pc, c);
      return paper_chain<Triple2DPaper>(pc, c);
    }
  }
  std::string known;
  for (const std::string& n : stream_cases(c.mode)) known += (known.empty() ? "" : ", ") + n;
  throw InvalidArgument("no word stream for case '" + c.case_name + "' in mode " + to_string(c.mode) +
                        " (known: " + known + ")");
}

}  // namespace

std::vector<std::string> stream_cases(Mode mode) {
  std::vector<std::string> out{"raw", "pair2d"};
  if (mode == Mode::exact) {
    for (const NamedCase& nc : named_cases())
      if (nc.name != "pair2d" && (nc.n - 1) * nc.d >= 2) out.push_back(nc.name);
  } else if (mode == Mode::paper) {
    for (const paper::PaperCase& pc : paper::paper_cases()) out.push_back(pc.name);
  }
  return out;
}

struct WordStream::Impl {
  StreamConfig config;
  std::unique_ptr<Uniforms> gen;
  std::unique_ptr<Source> source;
  std::vector<double> pending;  // coordinates of the last step not yet emitted
  std::size_t next = 0;
  std::uint64_t steps = 0, words = 0;
};

WordStream::WordStream(const StreamConfig& config) : impl_(std::make_unique<Impl>()) {
  require(config.mode == Mode::exact || config.mode == Mode::paper, "mode must be exact or paper");
  impl_->config = config;
  impl_->gen = make_uniforms(config);
  impl_->source = make_source(config);
  impl_->pending.resize(impl_->source->width());
  impl_->next = impl_->pending.size();
}
WordStream::~WordStream() = default;
WordStream::WordStream(WordStream&&) noexcept = default;
WordStream& WordStream::operator=(WordStream&&) noexcept = default;

const StreamConfig& WordStream::config() const { return impl_->config; }
int WordStream::width() const { return impl_->source->width(); }
std::uint64_t WordStream::collisions() const { return impl_->steps; }
std::uint64_t WordStream::words() const { return impl_->words; }
std::uint64_t WordStream::restarts() const { return impl_->source->restarts; }

void WordStream::fill(std::uint32_t* out, std::size_t n, const InterruptCheck& interrupt) {
  Impl& s = *impl_;
  constexpr std::size_t kChunk = std::size_t{1} << 16;  // words between interrupt checks
  for (std::size_t at = 0; at < n;) {
    const std::size_t end = std::min(n, at + kChunk);
    for (std::size_t k = at; k < end; ++k) {
      if (s.next == s.pending.size()) {
        s.source->step(*s.gen, s.pending.data());
        ++s.steps;
        s.next = 0;
      }
      out[k] = to_word(s.pending[s.next++]);
    }
    s.words += end - at;
    at = end;
    if (at < n && interrupt && interrupt()) throw Interrupted{};
  }
}

void WordStream::write(const std::string& path, std::uint64_t n, const InterruptCheck& interrupt) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "ab"), &std::fclose);
  require(f != nullptr, [&] { return "cannot open '" + path + "' for writing"; });
  std::vector<std::uint32_t> buf(1 << 16);
  bool ok = true;
  while (n > 0 && ok) {
    const std::size_t k = n < buf.size() ? static_cast<std::size_t>(n) : buf.size();
    fill(buf.data(), k);  // may throw (a paper chain that cannot go on): the file is closed
    ok = std::fwrite(buf.data(), sizeof(std::uint32_t), k, f.get()) == k;
    n -= k;
    if (n > 0 && ok && interrupt && interrupt()) {
      ok = std::fclose(f.release()) == 0;
      require(ok, [&] { return "writing '" + path + "' failed (disk full?)"; });
      throw Interrupted{};  // the file holds every word the stream moved past
    }
  }
  ok = std::fclose(f.release()) == 0 && ok;
  require(ok, [&] { return "writing '" + path + "' failed (disk full?)"; });
}

}  // namespace revcol::randomness
