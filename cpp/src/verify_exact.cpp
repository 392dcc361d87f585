// verify() cases of the exact family (see verify.hpp, namespace detail).
#include "revcol/verify.hpp"

namespace revcol::detail {

bool run_exact_case(const VerifyConfig& config, VerifyResult& r) {
  (void)config;
  (void)r;
  return false;
}

std::vector<std::string> exact_case_names() { return {}; }

}  // namespace revcol::detail
