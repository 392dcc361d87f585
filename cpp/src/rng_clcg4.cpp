// Cold parts of the CLCG4 generator (validation and its messages); the hot path is inline
// in revcol/rng/clcg4.hpp.
#include "revcol/rng/clcg4.hpp"

#include <string>

#include "revcol/error.hpp"

namespace revcol::rng {

void CLCG4::set_state(const State& s) {
  // Validate everything first: on error the state is untouched.
  for (int j = 0; j < 4; ++j) {
    require(s[j] >= 1 && s[j] < modulus[j],
            "CLCG4 state component s_" + std::to_string(j) + " = " + std::to_string(s[j]) +
                " is outside [1, " + std::to_string(modulus[j] - 1) + "]");
  }
  s_ = s;
}

}  // namespace revcol::rng
