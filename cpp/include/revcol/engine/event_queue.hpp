// The event queue of an event-driven engine: one scheduled event per id, keyed by
// (time, kind, tie), popped in key order. The tie is the id unless set() is given another
// (the float engine stores particles in slots and passes each slot's particle id, so that
// the order does not depend on where a particle is stored); ties must be distinct.
//
// Paul's O(1) queue (G. Paul, J. Comput. Phys. 221, 615 (2007)): the events of the current
// time bucket in a binary heap (the key copied into the node, so that sifting reads the heap
// array alone), the later buckets of a window (~n / 2 buckets of width w) as unsorted doubly
// linked lists, and the events beyond the window in an overflow list that is spread over the
// next window when this one is used up. Insert and update are O(1) outside the current
// bucket, O(log b) inside it (b ~ kPerBucket events), and a pop moves on bucket by bucket.
//
// The keys are distinct (the tie breaks every tie), so events leave in key order whatever the
// bucket width: the width is a speed setting only. It is set for ~kPerBucket events per
// bucket: `reset` takes a first width, and each new window takes one from the rate of top()
// calls in the last (an event-driven engine calls top() once per event), within a factor 8
// of the last width. (Measured in the float engine: a binary heap over all n particles took
// 15-25% of the time, most of it sifting new events down.)
//
// Time is `double` (the float engine: +infinity means "never") or a signed integer type
// (integer ticks: its max() means "never"). An event at never() is kept and comes last.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

namespace revcol::engine {

/// Paul's O(1) event queue over ids [0, n), one event per id, popped by (time, kind, id).
template <class Time>
class EventQueue {
  static_assert(std::is_floating_point_v<Time> || (std::is_integral_v<Time> && std::is_signed_v<Time>),
                "EventQueue: Time must be a floating-point or a signed integer type");

 public:
  /// The time of an event that never happens (+inf, or the integer type's max()).
  static constexpr Time never() {
    if constexpr (std::is_floating_point_v<Time>) return std::numeric_limits<Time>::infinity();
    else return std::numeric_limits<Time>::max();
  }

  /// Ids [0, n), all unscheduled; the first window starts at `now` with buckets of
  /// `bucket_width` (> 0; anything else, or a non-finite width, is taken as 1). `ties`: set()
  /// will be given tie breakers other than the ids (an array of n more; without it the id
  /// breaks ties and a given tie must equal it).
  void reset(std::size_t n, Time now, Time bucket_width, bool ties = false) {
    time_.assign(n, never());
    kind_.assign(n, 0);
    if (ties) tie_.assign(n, 0);
    else std::vector<std::int32_t>().swap(tie_);
    hpos_.assign(n, 0);
    next_.assign(n, -1);
    prev_.assign(n, -1);
    loc_.assign(n, kUnscheduled);
    heap_.clear();
    heap_.reserve(64);
    nbuckets_ = 64;
    while (nbuckets_ < static_cast<int>(std::min<std::size_t>(n, std::size_t{1} << 26) / 2)) nbuckets_ *= 2;
    bhead_.assign(nbuckets_, -1);
    ohead_ = -1;
    only_never_ = false;
    base_ = now;
    if constexpr (std::is_floating_point_v<Time>) {
      const bool ok = bucket_width > 0 && bucket_width < never();
      inv_ = 1.0 / (ok ? static_cast<double>(bucket_width) : 1.0);
    } else {
      width_ = bucket_width > 0 ? bucket_width : 1;
    }
    tops_ = 0;
    window_tops_ = 0;
    cur_ = 0;
  }

  /// (Re)schedules id's one event at time t with a kind (smaller kinds first at equal t), the
  /// id breaking ties.
  void set(int id, Time t, std::int32_t kind) { set(id, t, kind, id); }
  /// The same with another tie breaker (distinct over the ids; the smaller first at equal t
  /// and kind), for a queue reset with `ties`.
  void set(int id, Time t, std::int32_t kind, std::int32_t tie) {
    if (loc_[id] == kInHeap) {
      const int p = hpos_[id];
      const Node old = heap_[p];
      const Node e{t, kind, tie, id};
      time_[id] = t;
      kind_[id] = kind;
      if (!tie_.empty()) tie_[id] = tie;
      const int b = bucket_of(t);
      if (!only_never_ && b != kOverflow && b <= cur_) {  // stays in the current bucket
        heap_[p] = e;
        if (less(e, old)) sift_up(p);
        else sift_down(p);
        return;
      }
      heap_remove(p, old);
    } else if (loc_[id] != kUnscheduled) {
      list_pop(loc_[id] == kOverflow ? ohead_ : bhead_[loc_[id]], id);
    }
    time_[id] = t;
    kind_[id] = kind;
    if (!tie_.empty()) tie_[id] = tie;
    insert(id);
  }

  /// Unschedules id (nothing if it is not scheduled).
  void erase(int id) {
    if (loc_[id] == kInHeap) {
      const Node old = heap_[hpos_[id]];
      heap_remove(hpos_[id], old);
    } else if (loc_[id] != kUnscheduled) list_pop(loc_[id] == kOverflow ? ohead_ : bhead_[loc_[id]], id);
    loc_[id] = kUnscheduled;
    time_[id] = never();
    kind_[id] = 0;
  }

  /// The id with the smallest (time, kind, tie), or -1 when nothing is scheduled; not removed.
  /// Moves on to the next non-empty bucket, and to the next window, while the current
  /// bucket is empty.
  [[gnu::always_inline]] int top() {
    ++tops_;
    if (!heap_.empty()) return heap_[0].id;  // the common case, inlined into the event loops
    return refill_top();
  }

  /// Calls f(id) for the current bucket's other events, heap_[1 .. k] (those after the top in
  /// heap order, not in key order): the likely next tops, for the caller to prefetch what it
  /// will read of them (with revcol::engine::prefetch: see there).
  template <class F>
  void for_next(int k, F&& f) const {
    const int m = std::min(k + 1, static_cast<int>(heap_.size()));
    for (int p = 1; p < m; ++p) f(heap_[p].id);
  }

  /// The id of the current bucket's second event in key order (the smaller of the top's two
  /// children in the heap), or -1: the next top once the top is rescheduled, unless an event
  /// set meanwhile comes before it or the bucket runs out.
  int second() const {
    const int m = static_cast<int>(heap_.size());
    if (m < 2) return -1;
    if (m == 2 || less(heap_[1], heap_[2])) return heap_[1].id;
    return heap_[2].id;
  }

  /// id's scheduled time (never() when unscheduled).
  Time time(int id) const { return time_[id]; }
  /// id's scheduled kind (0 when unscheduled).
  std::int32_t kind(int id) const { return kind_[id]; }
  /// Whether id has an event in the queue.
  bool scheduled(int id) const { return loc_[id] != kUnscheduled; }
  /// Number of ids.
  std::size_t size() const { return time_.size(); }

 private:
  // top() when the current bucket's heap is empty: the next non-empty bucket, or the next window
  int refill_top() {
    while (heap_.empty()) {
      if (++cur_ < nbuckets_) {
        for (int i = bhead_[cur_]; i >= 0;) {
          const int nx = next_[i];
          heap_.push_back(node(i));
          hpos_[i] = static_cast<int>(heap_.size()) - 1;
          loc_[i] = kInHeap;
          i = nx;
        }
        bhead_[cur_] = -1;
        for (int p = static_cast<int>(heap_.size()) / 2 - 1; p >= 0; --p) sift_down(p);
        continue;
      }
      if (!next_window()) return -1;
    }
    return heap_[0].id;
  }

 public:
  /// Bytes held by the queue's arrays.
  std::size_t memory_bytes() const {
    return time_.capacity() * sizeof(Time) + (kind_.capacity() + tie_.capacity()) * sizeof(std::int32_t) +
           (hpos_.capacity() + next_.capacity() + prev_.capacity() + loc_.capacity() + bhead_.capacity()) *
               sizeof(int) +
           heap_.capacity() * sizeof(Node);
  }

  /// Checks the queue's invariants (heap order, every id in exactly one place, each list
  /// member in its bucket); returns false at the first violation. For tests and
  /// REVCOL_VALIDATE builds: O(n).
  bool valid() const {
    const int n = static_cast<int>(time_.size());
    std::vector<int> seen(n, 0);
    for (int p = 0; p < static_cast<int>(heap_.size()); ++p) {
      const Node& e = heap_[p];
      if (e.id < 0 || e.id >= n || loc_[e.id] != kInHeap || hpos_[e.id] != p) return false;
      if (e.t != time_[e.id] || e.kind != kind_[e.id] || e.tie != tie_of(e.id)) return false;
      if (p > 0 && less(e, heap_[(p - 1) / 2])) return false;
      ++seen[e.id];
    }
    auto walk = [&](int head, int loc) {
      int before = -1;
      for (int i = head; i >= 0; i = next_[i]) {
        if (i >= n || loc_[i] != loc || prev_[i] != before) return false;
        if (loc >= 0 && (bucket_of(time_[i]) != loc || loc <= cur_)) return false;
        if (loc == kOverflow && bucket_of(time_[i]) != kOverflow) return false;
        ++seen[i];
        before = i;
      }
      return true;
    };
    for (int b = 0; b < nbuckets_; ++b)
      if (!walk(bhead_[b], b)) return false;
    if (!walk(ohead_, kOverflow)) return false;
    for (int i = 0; i < n; ++i)
      if (seen[i] != (loc_[i] == kUnscheduled ? 0 : 1)) return false;
    return true;
  }

 private:
  struct Node {
    Time t;
    std::int32_t kind;
    std::int32_t tie;
    std::int32_t id;
  };
  static bool less(const Node& a, const Node& b) {
    if (a.t != b.t) return a.t < b.t;
    if (a.kind != b.kind) return a.kind < b.kind;
    return a.tie < b.tie;
  }
  std::int32_t tie_of(int i) const { return tie_.empty() ? i : tie_[i]; }
  Node node(int i) const { return Node{time_[i], kind_[i], tie_of(i), i}; }
  static constexpr int kInHeap = -1, kOverflow = -2, kUnscheduled = -3;
  static constexpr double kPerBucket = 8.0;  // measured: 2 to 16 within the noise

  void sift_up(int p) {
    const Node e = heap_[p];
    while (p > 0) {
      const int q = (p - 1) / 2;
      if (!less(e, heap_[q])) break;
      heap_[p] = heap_[q];
      hpos_[heap_[p].id] = p;
      p = q;
    }
    heap_[p] = e;
    hpos_[e.id] = p;
  }
  void sift_down(int p) {
    const Node e = heap_[p];
    const int m = static_cast<int>(heap_.size());
    for (;;) {
      int c = 2 * p + 1;
      if (c >= m) break;
      if (c + 1 < m && less(heap_[c + 1], heap_[c])) ++c;
      if (!less(heap_[c], e)) break;
      heap_[p] = heap_[c];
      hpos_[heap_[p].id] = p;
      p = c;
    }
    heap_[p] = e;
    hpos_[e.id] = p;
  }
  // Removes the node at p (whose key was old, a copy): the last node takes its place.
  void heap_remove(int p, const Node old) {
    const Node last = heap_.back();
    heap_.pop_back();
    if (p < static_cast<int>(heap_.size())) {
      heap_[p] = last;
      hpos_[last.id] = p;
      if (less(last, old)) sift_up(p);
      else sift_down(p);
    }
  }

  // The bucket of time t in the window (kOverflow beyond it, or for never()).
  int bucket_of(Time t) const {
    if constexpr (std::is_floating_point_v<Time>) {
      const double q = (static_cast<double>(t) - static_cast<double>(base_)) * inv_;
      if (!(q < static_cast<double>(nbuckets_))) return kOverflow;
      return q > 0.0 ? static_cast<int>(q) : 0;
    } else {
      if (t == never()) return kOverflow;
      if (t <= base_) return 0;
      using U = std::make_unsigned_t<Time>;
      const U q = (static_cast<U>(t) - static_cast<U>(base_)) / static_cast<U>(width_);  // t > base: no overflow
      return q < static_cast<U>(nbuckets_) ? static_cast<int>(q) : kOverflow;
    }
  }
  void list_push(int& head, int i) {
    next_[i] = head;
    prev_[i] = -1;
    if (head >= 0) prev_[head] = i;
    head = i;
  }
  void list_pop(int& head, int i) {
    if (prev_[i] >= 0) next_[prev_[i]] = next_[i];
    else head = next_[i];
    if (next_[i] >= 0) prev_[next_[i]] = prev_[i];
  }
  void heap_push(int i) {
    heap_.push_back(node(i));
    loc_[i] = kInHeap;
    sift_up(static_cast<int>(heap_.size()) - 1);
  }
  void insert(int i) {
    if (only_never_) {
      // the heap holds events at never() only (see next_window): another joins them; a
      // finite one sends them back to the overflow and the window restarts at it
      if (!(time_[i] < never())) {
        heap_push(i);
        return;
      }
      for (const Node& e : heap_) {
        list_push(ohead_, e.id);
        loc_[e.id] = kOverflow;
      }
      heap_.clear();
      only_never_ = false;
      base_ = time_[i];
      cur_ = 0;
    }
    const int b = bucket_of(time_[i]);
    if (b == kOverflow) {
      list_push(ohead_, i);
      loc_[i] = kOverflow;
    } else if (b <= cur_) {
      heap_push(i);
    } else {
      list_push(bhead_[b], i);
      loc_[i] = b;
    }
  }

  // The window is used up (every bucket empty): the next one starts where it ended, with a
  // width from the rate of top() calls in it, and the overflow is spread over it. With
  // nothing in reach it starts at the earliest finite event instead; with none, the rest
  // (events at never()) go to the heap. Returns false when nothing is scheduled at all.
  bool next_window() {
    if (ohead_ < 0) {  // nothing scheduled: restart at bucket 0 (no order to keep)
      cur_ = 0;
      only_never_ = false;
      return false;
    }
    const double popped = static_cast<double>(tops_ - window_tops_);
    if constexpr (std::is_floating_point_v<Time>) {
      const double span = static_cast<double>(nbuckets_) / inv_;
      base_ += static_cast<Time>(span);
      if (popped > 0.0) inv_ = std::clamp(popped / (kPerBucket * span), inv_ / 8.0, inv_ * 8.0);
    } else {
      const Time span = sat_mul(width_, static_cast<Time>(nbuckets_));
      base_ = sat_add(base_, span);
      if (popped > 0.0) {
        const double w = kPerBucket * static_cast<double>(span) / popped;
        const double lo = static_cast<double>(width_) / 8.0, hi = static_cast<double>(width_) * 8.0;
        const double c = std::clamp(w, lo, hi);
        width_ = c < 1.0 ? 1 : c > 9.0e15 ? static_cast<Time>(9.0e15) : static_cast<Time>(c);
      }
    }
    window_tops_ = tops_;
    cur_ = -1;
    for (;;) {
      bool any = false;
      Time tmin = never();
      int i = ohead_;
      ohead_ = -1;
      while (i >= 0) {
        const int nx = next_[i];
        const int b = bucket_of(time_[i]);
        if (b == kOverflow) {
          list_push(ohead_, i);
          loc_[i] = kOverflow;
          tmin = std::min(tmin, time_[i]);
        } else {
          list_push(bhead_[b], i);
          loc_[i] = b;
          any = true;
        }
        i = nx;
      }
      if (any || ohead_ < 0) return true;
      if (!(tmin < never())) break;
      base_ = tmin;  // bucket 0 next time round
    }
    for (int j = ohead_; j >= 0;) {
      const int nx = next_[j];
      heap_push(j);
      j = nx;
    }
    ohead_ = -1;
    only_never_ = true;  // until a finite event is inserted
    return true;
  }
  static Time sat_add(Time a, Time b) {
    if constexpr (std::is_floating_point_v<Time>) return a + b;
    else return a > std::numeric_limits<Time>::max() - b ? std::numeric_limits<Time>::max() - 1 : a + b;
  }
  static Time sat_mul(Time a, Time b) {
    if constexpr (std::is_floating_point_v<Time>) return a * b;
    else return a > (std::numeric_limits<Time>::max() - 1) / b ? std::numeric_limits<Time>::max() - 1 : a * b;
  }

  std::vector<Time> time_;             // each id's key: time, kind and tie
  std::vector<std::int32_t> kind_;
  std::vector<std::int32_t> tie_;      // each id's tie when reset with `ties`; empty otherwise (the id is the tie)
  std::vector<int> hpos_, next_, prev_, loc_, bhead_;  // heap positions; bucket and overflow lists; where
  std::vector<Node> heap_;             // the current bucket's heap
  int ohead_ = -1, nbuckets_ = 64, cur_ = 0;  // overflow list, buckets in the window, current bucket
  Time base_{};                        // the window's start
  double inv_ = 1.0;                   // floating Time: 1 / bucket width
  Time width_ = 1;                     // integer Time: the bucket width
  bool only_never_ = false;            // the heap holds events at never() only, the rest is empty
  std::uint64_t tops_ = 0, window_tops_ = 0;  // top() calls, and their count when the window started
};

}  // namespace revcol::engine
