// The count of lazily built paper-mode tables (revcol/collide/tables.hpp).
#include "revcol/collide/tables.hpp"

#include <atomic>

namespace revcol::paper {
namespace {
std::atomic<int> g_built{0};
}  // namespace

int tables_built() noexcept { return g_built.load(std::memory_order_relaxed); }

void detail::note_table_built() noexcept { g_built.fetch_add(1, std::memory_order_relaxed); }

}  // namespace revcol::paper
