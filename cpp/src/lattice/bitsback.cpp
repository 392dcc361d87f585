// The bits-back integer X (revcol/lattice/bitsback.hpp): schoolbook arithmetic by one word.
#include <algorithm>
#include <utility>

#include "revcol/error.hpp"
#include "revcol/lattice/bitsback.hpp"
#include "revcol/lattice/int128.hpp"

namespace revcol::lattice {
namespace {

// (hi:lo) div d and mod d for hi < d (one step of long division). On x86-64 the divq
// instruction does exactly this; elsewhere the compiler's 128-bit division gives the same bits.
inline u64 div_step(u64 hi, u64 lo, u64 d, u64& rem) {
#if defined(__x86_64__)
  u64 q, r;
  __asm__("divq %4" : "=a"(q), "=d"(r) : "a"(lo), "d"(hi), "rm"(d) : "cc");
  rem = r;
  return q;
#else
  const u128 n = (static_cast<u128>(hi) << 64) | lo;
  rem = static_cast<u64>(n % d);
  return static_cast<u64>(n / d);
#endif
}

}  // namespace

BitsBack::BitsBack(const std::vector<std::uint64_t>& words) {
  for (std::uint64_t w : words) push_word(w);
  trim();
}

void BitsBack::copy_words(const BitsBack& o) {
  const std::uint64_t* w = o.data();
  for (std::uint32_t k = 0; k < o.n_; ++k) push_word(w[k]);
}

BitsBack::BitsBack(BitsBack&& o) noexcept { steal(o); }

void BitsBack::steal(BitsBack& o) noexcept {  // (this holds no heap words)
  n_ = o.n_;
  cap_ = o.cap_;
  if (o.cap_ > kInline) {
    heap_ = o.heap_;
    o.cap_ = kInline;
    o.n_ = 0;
  } else {
    std::copy(o.inl_, o.inl_ + o.n_, inl_);
  }
}

BitsBack& BitsBack::operator=(BitsBack&& o) noexcept {
  if (this == &o) return *this;
  release();
  steal(o);
  return *this;
}

void BitsBack::release() noexcept {
  if (cap_ > kInline) delete[] heap_;
  cap_ = kInline;
  n_ = 0;
}

void BitsBack::grow_push(std::uint64_t w) {
  const std::uint32_t cap = 2 * cap_;
  auto* h = new std::uint64_t[cap];
  std::copy(data(), data() + n_, h);
  if (cap_ > kInline) delete[] heap_;
  heap_ = h;
  cap_ = cap;
  data()[n_++] = w;
}

bool operator==(const BitsBack& a, const BitsBack& b) noexcept {
  return a.n_ == b.n_ && std::equal(a.data(), a.data() + a.n_, b.data());
}

BitsBack BitsBack::from_hex(const std::string& hex) {
  std::size_t i = (hex.size() >= 2 && hex[0] == '0' && (hex[1] == 'x' || hex[1] == 'X')) ? 2 : 0;
  std::vector<std::uint64_t> w((hex.size() - i + 15) / 16 + 1, 0);
  std::size_t nibble = 0;
  for (std::size_t k = hex.size(); k > i; --k, ++nibble) {
    const char ch = hex[k - 1];
    int v = -1;
    if (ch >= '0' && ch <= '9') v = ch - '0';
    if (ch >= 'a' && ch <= 'f') v = ch - 'a' + 10;
    if (ch >= 'A' && ch <= 'F') v = ch - 'A' + 10;
    require(v >= 0, "BitsBack::from_hex: not a hexadecimal digit");
    w[nibble / 16] |= static_cast<std::uint64_t>(v) << (4 * (nibble % 16));
  }
  return BitsBack(std::move(w));
}

std::string BitsBack::to_hex() const {
  if (n_ == 0) return "0x0";
  static const char* digits = "0123456789abcdef";
  std::string s;
  const std::uint64_t* w = data();
  for (std::size_t k = n_; k-- > 0;)
    for (int n = 15; n >= 0; --n) s.push_back(digits[(w[k] >> (4 * n)) & 15]);
  const std::size_t first = s.find_first_not_of('0');
  return "0x" + s.substr(first);
}

void BitsBack::mul_add(std::uint64_t m, std::uint64_t a) {
  u64 carry = a;
  u64* w = data();
  for (std::uint32_t k = 0; k < n_; ++k) {
    const u128 t = static_cast<u128>(w[k]) * m + carry;
    w[k] = static_cast<u64>(t);
    carry = static_cast<u64>(t >> 64);
  }
  // no trim: a canonical X (no leading zero word) times m >= 1 plus a is at least X, so its top
  // word is not zero; every caller passes m >= 1
  if (carry != 0) push_word(carry);
}

std::uint64_t BitsBack::divmod(std::uint64_t d) noexcept {
  u64 rem = 0;
  u64* w = data();
  for (std::size_t k = n_; k-- > 0;) w[k] = div_step(rem, w[k], d, rem);
  trim();
  return rem;
}

void BitsBack::set_low48(std::uint64_t s) {
  if (n_ == 0) push_word(0);
  data()[0] = (data()[0] & ~rans_mask) | s;
  trim();
}

void BitsBack::push_uniform(std::uint64_t idx, std::uint64_t m) {
  require(m >= 1 && idx < m, "BitsBack::push_uniform: needs idx < m");
  mul_add(m, idx);
}

std::uint64_t BitsBack::pop_uniform(std::uint64_t m) {
  require(m >= 1, "BitsBack::pop_uniform: needs m >= 1");
  return divmod(m);
}

void BitsBack::push_rans(std::uint64_t c, std::uint64_t f) {
  require(f >= 1 && f <= rans_total && c <= rans_total - f, "BitsBack::push_rans: needs f >= 1 and c + f <= 2^48");
  const u64 r = divmod(f);  // X div f, r = X mod f
  // X = (X div f) * 2^48 + r + c: shift left by 48 bits, then r + c < 2^48 fills the gap.
  mul_add(1ULL << 48, r + c);
}

void BitsBack::pop_rans(std::uint64_t c, std::uint64_t f) {
  const u64 s = low48();
  require(f >= 1 && c <= s && s - c < f, "BitsBack::pop_rans: the low 48 bits are not in [c, c+f)");
  // X = f * (X >> 48) + s - c, in one pass: word k of X >> 48 is read (from words k and k + 1)
  // before word k is written
  const std::uint32_t n = n_;
  u64* w = data();
  u64 carry = s - c;
  for (std::uint32_t k = 0; k < n; ++k) {
    const u64 hi = (k + 1 < n) ? w[k + 1] : 0;
    const u128 t = static_cast<u128>((w[k] >> 48) | (hi << 16)) * f + carry;
    w[k] = static_cast<u64>(t);
    carry = static_cast<u64>(t >> 64);
  }
  if (carry != 0) push_word(carry);
  trim();
}

void BitsBack::add_low48(std::uint64_t g) {
  require(g < rans_total, "BitsBack::add_low48: needs g < 2^48");
  set_low48((low48() + g) & rans_mask);
}

void BitsBack::sub_low48(std::uint64_t g) {
  require(g < rans_total, "BitsBack::sub_low48: needs g < 2^48");
  set_low48((low48() + rans_total - g) & rans_mask);
}

std::size_t BitsBack::bit_length() const {
  if (n_ == 0) return 0;
  return 64 * (n_ - 1) + (64 - static_cast<std::size_t>(__builtin_clzll(data()[n_ - 1])));
}

}  // namespace revcol::lattice
