// Lists that parallel workers append to, one per worker (or per block), each alone on its cache
// lines.
//
// Why: a std::vector<std::vector<T>> keeps the lists' headers (begin, end, capacity: 24 bytes
// each) next to each other, so two threads appending to neighbouring lists write the same cache
// line on every push_back, and the line moves between the cores each time (false sharing). The
// narrow phase's per-worker contact lists were such a pair: base-100 pyramid at 2 threads, the
// narrow phase took 0.93 ms of thread time against 0.64 ms on one thread, and 0.64 ms with the
// lists apart (narrow phase 0.48 -> 0.33 ms a step, the step 1.89 -> 1.51 ms; 2-core VM,
// quadrant_bench --scenes pyramid --counts 5050 --threads 1,2).
#pragma once

#include <cstddef>
#include <vector>

namespace quadrant {

// The size of the unit of cache coherence on the machines this runs on (x86-64 and ARMv8: 64
// bytes; std::hardware_destructive_interference_size is not stable across GCC versions).
inline constexpr size_t kCacheLine = 64;

template <class T>
class WorkerLists {
 public:
  /// `count` empty lists (their capacity kept from earlier use).
  void Reset(int count) {
    slots_.resize(static_cast<size_t>(count));
    for (Slot& s : slots_) s.items.clear();
  }
  int Count() const { return static_cast<int>(slots_.size()); }
  std::vector<T>& operator[](int i) { return slots_[static_cast<size_t>(i)].items; }
  const std::vector<T>& operator[](int i) const { return slots_[static_cast<size_t>(i)].items; }
  size_t TotalSize() const {
    size_t total = 0;
    for (const Slot& s : slots_) total += s.items.size();
    return total;
  }

 private:
  struct alignas(kCacheLine) Slot {
    std::vector<T> items;
  };
  std::vector<Slot> slots_;
};

}  // namespace quadrant
