// verify() cases of the paper family (see verify.hpp, namespace detail).
#include "revcol/verify.hpp"

namespace revcol::detail {

bool run_paper_case(const VerifyConfig& config, VerifyResult& r) {
  (void)config;
  (void)r;
  return false;
}

std::vector<std::string> paper_case_names() { return {}; }

}  // namespace revcol::detail
