// Error types of the core. The binding translates InvalidArgument to Python's ValueError.
#pragma once
#include <cstdio>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace revcol {

/// Bad input: a clear message naming the problem; the operation changed nothing.
class InvalidArgument : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Throws InvalidArgument(msg) when cond is false. Checks sit on hot paths, so a message
/// is never built unless it is thrown: pass a literal, or a callable returning the message.
inline void require(bool cond, const char* msg) {
  if (!cond) [[unlikely]] throw InvalidArgument(msg);
}
/// As above, for a message that has already been built (cold paths only).
inline void require(bool cond, const std::string& msg) {
  if (!cond) [[unlikely]] throw InvalidArgument(msg);
}
/// As above, with the message built by make_msg() only when cond is false.
template <class F>
  requires std::is_invocable_r_v<std::string, F>
inline void require(bool cond, F&& make_msg) {
  if (!cond) [[unlikely]] throw InvalidArgument(make_msg());
}

/// A double for a message: 6 significant digits in %g form (1e-130 stays 1e-130, where
/// std::to_string prints 0.000000).
inline std::string num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

}  // namespace revcol
