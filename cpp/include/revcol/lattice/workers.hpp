// A pool of worker threads with a stop-the-world barrier (the parallel lattice engine's
// transport, timewarp.hpp): w workers, the calling thread worker 0, each turning over its share
// of k items; every so many turns, or when no worker finds anything to do, all of them stop at
// a barrier where worker 0 alone runs `settle`, which says whether the run is over.
#pragma once
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace revcol::lattice {

/// Runs w workers (the calling thread is worker 0), worker m calling turn(i) for each item i of
/// its share [m k / w, (m + 1) k / w) over and over (turn: whether it did anything). When a
/// worker has done `every` turns with work since the last barrier, or when every worker found
/// nothing to do since the last barrier, all of them stop at a barrier and worker 0 calls
/// settle(idle) (idle: every worker had found nothing) with the others waiting; true ends the
/// run. An exception in a turn or in settle ends the run at the next barrier and is rethrown here.
inline void run_workers(int w, int k, std::uint64_t every, const std::function<bool(int)>& turn, const std::function<bool(bool)>& settle) {
  std::mutex mx;
  std::condition_variable cv;
  int arrived = 0;
  std::uint64_t generation = 0;
  std::atomic<bool> want{false};
  std::atomic<int> idle{0};
  bool done = false;
  std::exception_ptr err;
  auto barrier = [&] {
    std::unique_lock<std::mutex> hold(mx);
    const std::uint64_t gen = generation;
    if (++arrived == w) {
      arrived = 0;
      ++generation;
      cv.notify_all();
    } else {
      cv.wait(hold, [&] { return generation != gen; });
    }
  };
  auto work = [&](int me) {
    const int lo = me * k / w, hi = (me + 1) * k / w;
    std::uint64_t since = 0;
    bool was_idle = false;
    for (;;) {
      if (want.load(std::memory_order_acquire)) {
        barrier();
        if (me == 0) {
          try {
            done = err != nullptr || settle(idle.load() == w);
          } catch (...) {
            if (!err) err = std::current_exception();
            done = true;
          }
          idle.store(0);  // (idle again only once every worker has found nothing since)
          want.store(false, std::memory_order_release);
        }
        barrier();
        if (done) return;
        since = 0;
        was_idle = false;
        continue;
      }
      bool any = false;
      try {
        for (int i = lo; i < hi; ++i)
          if (turn(i)) any = true, ++since;
      } catch (...) {
        {
          const std::lock_guard<std::mutex> hold(mx);
          if (!err) err = std::current_exception();
        }
        want.store(true, std::memory_order_release);
        continue;
      }
      if (any == was_idle) idle.fetch_add(any ? -1 : 1);
      was_idle = !any;
      if (since >= every || idle.load() == w) want.store(true, std::memory_order_release);
      if (!any) std::this_thread::yield();
    }
  };
  std::vector<std::thread> threads;
  for (int i = 1; i < w; ++i) threads.emplace_back(work, i);
  work(0);
  for (auto& t : threads) t.join();
  if (err) std::rethrow_exception(err);
}

/// The items [lo, hi) of the worker that run_workers(w, k, ...) gives item i.
inline std::pair<int, int> share_of(int i, int w, int k) {
  int me = 0;
  while ((me + 1) * k / w <= i) ++me;
  return {me * k / w, (me + 1) * k / w};
}

/// Calls make(i) for every i in [0, k) on w threads (the calling one among them), each its share
/// of the items; the first exception is rethrown here once every thread has finished.
inline void build_in_workers(int w, int k, const std::function<void(int)>& make) {
  std::vector<std::exception_ptr> err(static_cast<std::size_t>(w));
  auto share = [&](int me) {
    try {
      for (int i = me * k / w; i < (me + 1) * k / w; ++i) make(i);
    } catch (...) {
      err[static_cast<std::size_t>(me)] = std::current_exception();
    }
  };
  std::vector<std::thread> threads;
  for (int i = 1; i < w; ++i) threads.emplace_back(share, i);
  share(0);
  for (auto& t : threads) t.join();
  for (const auto& e : err)
    if (e) std::rethrow_exception(e);
}

}  // namespace revcol::lattice
