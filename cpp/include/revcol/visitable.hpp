// Structs that list their fields once: visit(f) calls f(name, field) for each, in order, so a
// binding or an archive loops over them instead of naming each field. Both engines' state
// and counters are Visitable (engine/engine.hpp: Snapshot, Counters; lattice/engine_core.hpp:
// SnapshotN, Counters), and the bindings write and read checkpoints with these loops.
#pragma once

namespace revcol {

/// visit(f): calls f(name, field) for each field of a struct that lists them in a static
/// visit_fields(self, f); const and non-const alike.
template <class Derived>
struct Visitable {
  /// Every field, writable.
  template <class F>
  void visit(F&& f) {
    Derived::visit_fields(static_cast<Derived&>(*this), f);
  }
  /// Every field, read-only.
  template <class F>
  void visit(F&& f) const {
    Derived::visit_fields(static_cast<const Derived&>(*this), f);
  }
};

}  // namespace revcol
