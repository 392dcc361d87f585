// Tables that paper mode builds lazily, once per process, on the first collision that needs
// them: the calotte areas of the 3-particle 2D procedure (GSL quadrature, CalotteTable) and
// the ellipse-arc inverse of the 3-particle 1D procedure (GSL elliptic integrals,
// EllipseArc::paper_table). A scene without paper-mode triples never builds them; this
// count lets tests and benchmarks check it.
#pragma once

namespace revcol::paper {

/// How many lazily built GSL tables this process has built so far (0 to 3).
int tables_built() noexcept;

namespace detail {
/// Called by each table's one-time construction.
void note_table_built() noexcept;
}  // namespace detail

}  // namespace revcol::paper
