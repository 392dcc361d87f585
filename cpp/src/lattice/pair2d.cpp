// The exact lattice pair operator (revcol/lattice/pair2d.hpp): forward, reverse, pair level.
#include <algorithm>

#include "revcol/error.hpp"
#include "revcol/lattice/pair2d.hpp"

namespace revcol::lattice {
namespace {

constexpr i64 kMaxComp = LatticePair2D::max_component;
constexpr i64 kMaxVel = 1LL << 61;

inline i128 norm2(i64 x, i64 y) { return static_cast<i128>(x) * x + static_cast<i128>(y) * y; }
inline bool small(i64 v, i64 bound) { return v > -bound && v < bound; }
inline bool small(const Vec2& v, i64 bound) { return small(v[0], bound) && small(v[1], bound); }
inline i64 iabs(i64 v) { return v < 0 ? -v : v; }
inline Vec2 to_vec(IVec v) { return {v.x, v.y}; }
// Wrapping (mod 2^64) arithmetic for positions: no signed overflow, two's complement result.
inline i64 wadd(i64 a, i64 b) { return static_cast<i64>(static_cast<std::uint64_t>(a) + static_cast<std::uint64_t>(b)); }
inline i64 wsub(i64 a, i64 b) { return static_cast<i64>(static_cast<std::uint64_t>(a) - static_cast<std::uint64_t>(b)); }

// A state seen in its face frame: the inside point P = (xc, py), the velocity W.
struct Frame {
  int face;
  int strict;
  i64 xc, py;
  IVec w;
  i64 yin;   // the highest inside point of the column
  std::int64_t jn;  // the normal cell of the column (ND / 2^shift cells per turn)
};

// The face frame of an inside point p with velocity w (the phase column and its top).
Frame make_frame(i64 px, i64 py, const Vec2& w, i128 sigma2, std::int64_t sigma, int shift) {
  Frame fr;
  fr.face = face_of(px, py);
  const IVec p = rot90({px, py}, fr.face);
  fr.w = rot90({w[0], w[1]}, fr.face);
  fr.strict = fr.face & 1;
  fr.xc = p.x;
  fr.py = p.y;
  fr.yin = static_cast<i64>(isqrt(static_cast<u128>(sigma2 - static_cast<i128>(p.x) * p.x - 1)));
  fr.jn = normal_cell(p.x, sigma, shift);
  return fr;
}

}  // namespace

const char* to_string(Refusal r) {
  switch (r) {
    case Refusal::none: return "none";
    case Refusal::cell_readback: return "cell_readback";
    case Refusal::not_approaching: return "not_approaching";
    case Refusal::empty_post: return "empty_post";
    case Refusal::out_of_domain: return "out_of_domain";
  }
  return "?";
}

int face_of(i64 px, i64 py) {
  if (py > 0 && iabs(px) <= py) return 0;
  if (px > 0 && iabs(py) < px) return 1;
  if (py < 0 && iabs(px) <= -py) return 2;
  return 3;
}

std::optional<i64> lo_pre(i128 sigma2, i64 xc, int strict, i64 wx, i64 wy) {
  i128 lo = std::max<i128>(1, static_cast<i128>(iabs(xc)) + strict);
  const i128 dx = static_cast<i128>(xc) - wx;
  const i128 d = sigma2 - dx * dx;
  if (d > 0) {
    const i128 z = isqrt_ceil(static_cast<u128>(d));
    if (wy - z >= 1) return std::nullopt;  // points below the circle too: not an interval
    lo = std::max(lo, wy + z);
  }
  return static_cast<i64>(lo);
}

std::optional<i64> lo_post(i128 sigma2, i64 xc, int strict, i64 wx, i64 wy) {
  i128 lo = std::max<i128>(1, static_cast<i128>(iabs(xc)) + strict);
  const i128 dx = static_cast<i128>(xc) + wx;
  const i128 d = sigma2 - dx * dx;
  if (d > 0) {
    const i128 z = isqrt_ceil(static_cast<u128>(d));
    if (-z - wy >= 1) return std::nullopt;
    lo = std::max(lo, z - wy);
  }
  return static_cast<i64>(lo);
}

LatticePair2D::LatticePair2D(std::int64_t sigma, Law law, int cell_bits)
    : sigma_(sigma), sigma2_(static_cast<i128>(sigma) * sigma), law_(law), shift_(kCellBits - cell_bits) {
  require(sigma >= 2 && sigma <= (1LL << 61), "LatticePair2D: sigma must be in [2, 2^61] lattice units");
  require(cell_bits >= min_cell_bits && cell_bits <= max_cell_bits,
          "LatticePair2D: cell_bits must be in [12, 20] (2^cell_bits direction cells per turn)");
  mask_ = (std::int64_t{1} << cell_bits) - 1;
  half_ = std::int64_t{1} << (cell_bits - 1);
  quarter_ = std::int64_t{1} << (cell_bits - 2);
  ufreq_ = std::uint64_t{1} << (kRansBits - (cell_bits - 1));
}

std::uint64_t LatticePair2D::cum(std::int64_t a) const {
  return law_ == Law::flux ? flux_cum(a << shift_) : static_cast<std::uint64_t>(a) * ufreq_;
}

std::int64_t LatticePair2D::decode(std::uint64_t s) const {
  std::uint64_t c, f;
  return decode(s, c, f);
}

std::int64_t LatticePair2D::decode(std::uint64_t s, std::uint64_t& c, std::uint64_t& f) const {
  if (law_ == Law::flux) {
    std::int64_t b = flux_decode(s, c, f);
    if (shift_ == 0) return b;
    b >>= shift_;  // the coarse cell holding the fine one; its frequency sums its fine cells'
    c = flux_cum(b << shift_);
    f = flux_cum((b + 1) << shift_) - c;
    return b;
  }
  const std::int64_t b = static_cast<std::int64_t>(s / ufreq_);
  c = static_cast<std::uint64_t>(b) * ufreq_;
  f = ufreq_;
  return b;
}

Refusal LatticePair2D::check_pre(const Vec2& q, const Vec2& w) const {
  require(small(q, kMaxComp) && small(w, kMaxComp), "LatticePair2D: |q|, |w| components must be below 2^62");
  const i64 px = q[0] + w[0], py = q[1] + w[1];
  require(norm2(q[0], q[1]) >= sigma2_, "LatticePair2D::forward: q must be outside (|q|^2 >= sigma^2)");
  require(norm2(px, py) < sigma2_, "LatticePair2D::forward: q + w must be inside (|q+w|^2 < sigma^2)");
  if (px == 0 && py == 0) return Refusal::out_of_domain;  // coinciding centres: no face
  const Frame fr = make_frame(px, py, w, sigma2_, sigma_, shift_);
  if (!lo_pre(sigma2_, fr.xc, fr.strict, fr.w.x, fr.w.y)) return Refusal::out_of_domain;
  const std::int64_t jpre = ((dir(fr.w.x, fr.w.y) - fr.jn) & mask_) - half_;
  if (jpre < -quarter_ || jpre >= quarter_) return Refusal::not_approaching;
  return Refusal::none;
}

Refusal LatticePair2D::forward(const Vec2& q, const Vec2& w, std::uint64_t g, const BitsBack& X,
                               Vec2& q2, Vec2& w2, BitsBack& X_out, Trace* trace) const {
  require(g < BitsBack::rans_total, "LatticePair2D::forward: g must be below 2^48");
  require(&X != &X_out, "LatticePair2D::forward: X_out must not be X");
  require(small(q, kMaxComp) && small(w, kMaxComp), "LatticePair2D: |q|, |w| components must be below 2^62");
  const i64 px = q[0] + w[0], py = q[1] + w[1];
  require(norm2(q[0], q[1]) >= sigma2_, "LatticePair2D::forward: q must be outside (|q|^2 >= sigma^2)");
  require(norm2(px, py) < sigma2_, "LatticePair2D::forward: q + w must be inside (|q+w|^2 < sigma^2)");
  if (px == 0 && py == 0) {  // coinciding centres at tick a: no face, no column
    X_out = X;
    return Refusal::out_of_domain;
  }
  const Frame fr = make_frame(px, py, w, sigma2_, sigma_, shift_);
  Trace tr;
  tr.face = fr.face;
  tr.jn = fr.jn;
  // 2. pre phase interval
  const auto lo = lo_pre(sigma2_, fr.xc, fr.strict, fr.w.x, fr.w.y);
  auto refuse = [&](Refusal r) {
    X_out = X;
    if (trace) *trace = tr;
    return r;
  };
  if (!lo) return refuse(Refusal::out_of_domain);
  tr.m = fr.yin - *lo + 1;
  // 3. pre direction about the quantized normal
  const std::int64_t jd = dir(fr.w.x, fr.w.y);
  tr.jpre = ((jd - fr.jn) & mask_) - half_;
  if (tr.jpre < -quarter_ || tr.jpre >= quarter_) return refuse(Refusal::not_approaching);
  X_out = X;
  X_out.push_uniform(static_cast<std::uint64_t>(fr.py - *lo), static_cast<std::uint64_t>(tr.m));
  const std::int64_t a = tr.jpre + quarter_;
  const std::uint64_t ca = cum(a);
  X_out.push_rans(ca, cum(a + 1) - ca);
  // 4. torus shift, 5. post direction
  X_out.add_low48(g);
  std::uint64_t cb, fb;
  const std::int64_t b = decode(X_out.low48(), cb, fb);
  X_out.pop_rans(cb, fb);
  tr.jpost = b - quarter_;
  const std::int64_t k = (fr.jn + tr.jpost - jd) & mask_;
  const IVec W2 = rotate(fr.w, rot_coef(k << shift_));
  if (!small(W2.x, kMaxComp) || !small(W2.y, kMaxComp)) return refuse(Refusal::out_of_domain);
  // 6. post phase (the refusals in the prototype's order: interval, empty, then read-back)
  const auto lo2 = lo_post(sigma2_, fr.xc, fr.strict, W2.x, W2.y);
  if (!lo2) return refuse(Refusal::out_of_domain);
  tr.m2 = fr.yin - *lo2 + 1;
  if (tr.m2 <= 0) return refuse(Refusal::empty_post);
  if (!in_coarse_cell(W2.x, W2.y, (fr.jn + tr.jpost) & mask_, shift_)) return refuse(Refusal::cell_readback);
  const std::uint64_t idx2 = X_out.pop_uniform(static_cast<std::uint64_t>(tr.m2));
  const i128 qx = static_cast<i128>(fr.xc) + W2.x;
  const i128 qy = static_cast<i128>(*lo2) + static_cast<i128>(idx2) + W2.y;
  if (!(qx > -kMaxComp && qx < kMaxComp && qy > -kMaxComp && qy < kMaxComp)) return refuse(Refusal::out_of_domain);
  q2 = to_vec(rot90({static_cast<i64>(qx), static_cast<i64>(qy)}, -fr.face));
  w2 = to_vec(rot90(W2, -fr.face));
  if (trace) *trace = tr;
  return Refusal::none;
}

void LatticePair2D::reverse(const Vec2& q2, const Vec2& w2, std::uint64_t g, BitsBack& X, Vec2& q, Vec2& w) const {
  require(g < BitsBack::rans_total, "LatticePair2D::reverse: g must be below 2^48");
  require(small(q2, kMaxComp) && small(w2, kMaxComp), "LatticePair2D: |q2|, |w2| components must be below 2^62");
  const i64 px = q2[0] - w2[0], py = q2[1] - w2[1];
  require(norm2(q2[0], q2[1]) >= sigma2_, "LatticePair2D::reverse: q2 must be outside (|q2|^2 >= sigma^2)");
  require(norm2(px, py) < sigma2_, "LatticePair2D::reverse: q2 - w2 must be inside (|q2-w2|^2 < sigma^2)");
  const Frame fr = make_frame(px, py, w2, sigma2_, sigma_, shift_);
  const auto lo2 = lo_post(sigma2_, fr.xc, fr.strict, fr.w.x, fr.w.y);
  require(lo2.has_value(), "LatticePair2D::reverse: post phases do not form an interval (not a forward's output)");
  const i64 m2 = fr.yin - *lo2 + 1;
  const i64 idx2 = fr.py - *lo2;
  require(idx2 >= 0 && idx2 < m2, "LatticePair2D::reverse: post phase outside its interval");
  const std::int64_t jpost = ((dir(fr.w.x, fr.w.y) - fr.jn + half_) & mask_) - half_;
  require(jpost >= -quarter_ && jpost < quarter_, "LatticePair2D::reverse: w2 is not outgoing about the normal");
  const std::int64_t b = jpost + quarter_;
  const std::uint64_t cb = cum(b), fb = cum(b + 1) - cb;
  X.push_uniform(static_cast<std::uint64_t>(idx2), static_cast<std::uint64_t>(m2));
  X.push_rans(cb, fb);
  X.sub_low48(g);
  std::uint64_t ca, fa;
  const std::int64_t a = decode(X.low48(), ca, fa);
  X.pop_rans(ca, fa);
  const std::int64_t jd = (a - quarter_ + fr.jn + half_) & mask_;
  const IVec W = rotate_inv(fr.w, rot_coef(((fr.jn + jpost - jd) & mask_) << shift_));
  const auto lo = lo_pre(sigma2_, fr.xc, fr.strict, W.x, W.y);
  const i64 m = lo ? fr.yin - *lo + 1 : 0;
  if (m <= 0 || !small(W.x, kMaxComp) || !small(W.y, kMaxComp)) {
    X.push_rans(ca, fa);  // undo: X is left as it came in
    X.add_low48(g);
    X.pop_rans(cb, fb);
    X.pop_uniform(static_cast<std::uint64_t>(m2));
    require(false, "LatticePair2D::reverse: no pre state maps to this post state (not a forward's output)");
  }
  const std::uint64_t idx = X.pop_uniform(static_cast<std::uint64_t>(m));
  const i64 pre_py = *lo + static_cast<i64>(idx);
  q = to_vec(rot90({fr.xc - W.x, pre_py - W.y}, -fr.face));
  w = to_vec(rot90(W, -fr.face));
}

Refusal LatticePair2D::pair_forward(const Vec2& xi, const Vec2& xj, const Vec2& vi, const Vec2& vj,
                                    std::uint64_t g, const BitsBack& X, Vec2& xi2, Vec2& xj2, Vec2& vi2,
                                    Vec2& vj2, BitsBack& X_out, Trace* trace) const {
  require(small(vi, kMaxVel) && small(vj, kMaxVel), "LatticePair2D::pair_forward: velocity components must be below 2^61");
  Vec2 r, c, d, s, r2, d2;
  for (int e = 0; e < 2; ++e) {
    r[e] = wsub(xi[e], xj[e]);
    c[e] = wadd(xj[e], r[e] >> 1);
    d[e] = vi[e] - vj[e];
    s[e] = vj[e] + (d[e] >> 1);
  }
  const Refusal why = forward(r, d, g, X, r2, d2, X_out, trace);
  if (why != Refusal::none) return why;
  Vec2 nvi, nvj;
  for (int e = 0; e < 2; ++e) {
    nvj[e] = s[e] - (d2[e] >> 1);
    nvi[e] = nvj[e] + d2[e];
  }
  if (!small(nvi, kMaxVel) || !small(nvj, kMaxVel)) {  // the reverse would refuse these velocities
    X_out = X;
    return Refusal::out_of_domain;
  }
  for (int e = 0; e < 2; ++e) {
    xj2[e] = wsub(wadd(c[e], s[e]), r2[e] >> 1);
    xi2[e] = wadd(xj2[e], r2[e]);
  }
  vi2 = nvi;
  vj2 = nvj;
  return Refusal::none;
}

void LatticePair2D::pair_reverse(const Vec2& xi2, const Vec2& xj2, const Vec2& vi2, const Vec2& vj2,
                                 std::uint64_t g, BitsBack& X, Vec2& xi, Vec2& xj, Vec2& vi, Vec2& vj) const {
  require(small(vi2, kMaxVel) && small(vj2, kMaxVel), "LatticePair2D::pair_reverse: velocity components must be below 2^61");
  Vec2 r2, c, d2, s, r, d;
  for (int e = 0; e < 2; ++e) {
    r2[e] = wsub(xi2[e], xj2[e]);
    d2[e] = vi2[e] - vj2[e];
    s[e] = vj2[e] + (d2[e] >> 1);
    c[e] = wsub(wadd(xj2[e], r2[e] >> 1), s[e]);
  }
  reverse(r2, d2, g, X, r, d);
  for (int e = 0; e < 2; ++e) {
    xj[e] = wsub(c[e], r[e] >> 1);
    xi[e] = wadd(xj[e], r[e]);
    vj[e] = s[e] - (d[e] >> 1);
    vi[e] = vj[e] + d[e];
  }
}

}  // namespace revcol::lattice
