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

BitsBack::BitsBack(std::vector<std::uint64_t> words) : words_(std::move(words)) { trim(); }

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
  if (words_.empty()) return "0x0";
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (std::size_t k = words_.size(); k-- > 0;)
    for (int n = 15; n >= 0; --n) s.push_back(digits[(words_[k] >> (4 * n)) & 15]);
  const std::size_t first = s.find_first_not_of('0');
  return "0x" + s.substr(first);
}

void BitsBack::trim() {
  while (!words_.empty() && words_.back() == 0) words_.pop_back();
}

void BitsBack::mul_add(std::uint64_t m, std::uint64_t a) {
  u64 carry = a;
  for (u64& w : words_) {
    const u128 t = static_cast<u128>(w) * m + carry;
    w = static_cast<u64>(t);
    carry = static_cast<u64>(t >> 64);
  }
  if (carry != 0) words_.push_back(carry);
  trim();
}

std::uint64_t BitsBack::divmod(std::uint64_t d) {
  u64 rem = 0;
  for (std::size_t k = words_.size(); k-- > 0;) words_[k] = div_step(rem, words_[k], d, rem);
  trim();
  return rem;
}

void BitsBack::set_low48(std::uint64_t s) {
  if (words_.empty()) words_.push_back(0);
  words_[0] = (words_[0] & ~rans_mask) | s;
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
  // X = f * (X >> 48) + s - c
  const std::size_t n = words_.size();
  for (std::size_t k = 0; k < n; ++k) {
    const u64 hi = (k + 1 < n) ? words_[k + 1] : 0;
    words_[k] = (words_[k] >> 48) | (hi << 16);
  }
  trim();
  mul_add(f, s - c);
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
  if (words_.empty()) return 0;
  return 64 * (words_.size() - 1) + (64 - static_cast<std::size_t>(__builtin_clzll(words_.back())));
}

}  // namespace revcol::lattice
