// A stand-in for revcol::engine::EventQueue<Time> (the engine architecture issue's event queue),
// with exactly its interface, used by the lattice engine until that header is on this branch:
// an indexed binary heap of one event per id, ordered by (time, kind, id). O(log n) per set,
// erase and top. The lead swaps it for engine/event_queue.hpp (same interface).
#pragma once
#include <cstddef>
#include <cstdint>
#include <tuple>
#include <vector>

namespace revcol::lattice {

/// One scheduled event per id, the smallest (time, kind, id) on top.
template <class Time>
class EventQueueFallback {
 public:
  /// Ids [0, n), all unscheduled; now and bucket_width are hints (unused by a heap).
  void reset(std::size_t n, Time /*now*/, Time /*bucket_width*/) {
    time_.assign(n, Time{});
    kind_.assign(n, 0);
    pos_.assign(n, -1);
    heap_.clear();
    heap_.reserve(n);
  }
  /// (Re)schedules id's one event at (t, kind).
  void set(int id, Time t, std::int32_t kind) {
    time_[id] = t;
    kind_[id] = kind;
    if (pos_[id] < 0) {
      pos_[id] = static_cast<int>(heap_.size());
      heap_.push_back(id);
    }
    sift_up(pos_[id]);
    sift_down(pos_[id]);
  }
  /// Unschedules id (no-op when not scheduled).
  void erase(int id) {
    const int p = pos_[id];
    if (p < 0) return;
    const int last = heap_.back();
    heap_.pop_back();
    pos_[id] = -1;
    if (last != id) {
      heap_[p] = last;
      pos_[last] = p;
      sift_up(p);
      sift_down(pos_[last]);
    }
  }
  /// The id with the smallest (time, kind, id), -1 if none; not removed.
  int top() const noexcept { return heap_.empty() ? -1 : heap_[0]; }
  /// Scheduled time of id.
  Time time(int id) const noexcept { return time_[id]; }
  /// Scheduled kind of id.
  std::int32_t kind(int id) const noexcept { return kind_[id]; }
  /// Whether id has an event.
  bool scheduled(int id) const noexcept { return pos_[id] >= 0; }
  /// Bytes held.
  std::size_t memory_bytes() const noexcept {
    return time_.capacity() * sizeof(Time) + kind_.capacity() * 4 + pos_.capacity() * 4 + heap_.capacity() * 4;
  }

 private:
  bool less(int a, int b) const noexcept {
    return std::tie(time_[a], kind_[a], a) < std::tie(time_[b], kind_[b], b);
  }
  void sift_up(int p) {
    const int id = heap_[p];
    while (p > 0) {
      const int parent = (p - 1) / 2;
      if (!less(id, heap_[parent])) break;
      heap_[p] = heap_[parent];
      pos_[heap_[p]] = p;
      p = parent;
    }
    heap_[p] = id;
    pos_[id] = p;
  }
  void sift_down(int p) {
    const int n = static_cast<int>(heap_.size());
    const int id = heap_[p];
    for (;;) {
      int c = 2 * p + 1;
      if (c >= n) break;
      if (c + 1 < n && less(heap_[c + 1], heap_[c])) ++c;
      if (!less(heap_[c], id)) break;
      heap_[p] = heap_[c];
      pos_[heap_[p]] = p;
      p = c;
    }
    heap_[p] = id;
    pos_[id] = p;
  }
  std::vector<Time> time_;
  std::vector<std::int32_t> kind_;
  std::vector<int> pos_, heap_;
};

}  // namespace revcol::lattice
