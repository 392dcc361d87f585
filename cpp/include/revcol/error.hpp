// Error types of the core. The binding translates InvalidArgument to Python's ValueError.
#pragma once
#include <stdexcept>
#include <string>

namespace revcol {

/// Bad input: a clear message naming the problem; the operation changed nothing.
class InvalidArgument : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Throws InvalidArgument(msg) when cond is false.
inline void require(bool cond, const std::string& msg) {
  if (!cond) throw InvalidArgument(msg);
}

}  // namespace revcol
