#pragma once

#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace tetrefine {

// An allocator whose value-construction default-initialises: FillLater<T>(n) and resize(n)
// leave trivial elements unwritten. For the core's large scratch arrays that a parallel pass
// fills anyway: std::vector would first zero them on one thread, which also makes that thread
// take every page fault, a serial step that showed in the 2-thread profile as kernel time.
template <typename T, typename Base = std::allocator<T>>
class DefaultInitAllocator : public Base {
 public:
  // Arrays of at least kHugeThreshold bytes are placed on 2 MiB boundaries, rounded up to whole
  // 2 MiB pages, and offered to the kernel for transparent huge pages (madvise MADV_HUGEPAGE; a
  // no-op where THP is off, and only a hint: the memory is ordinary memory either way). Why:
  // the first write of every 4 KiB page of a fresh array is a page fault, and the refinement's
  // scratch arrays are fresh on every call. On this project's 2-core VM, one thread, 1.08 M
  // tets (bench/core_bench, 2026-11-23), faults were 27% of ValidateMesh and 12% of a whole
  // Refine call; with huge pages the face check went from 117 to 18 ms, all of ValidateMesh from
  // 153 to 47 ms, and a whole one-iteration call without the lattice from 514 to 217 ms (paper)
  // and 646 to 337 ms (longest-edge). Below the threshold the rounding would waste more than it
  // saves. The bits computed do not change. The cost is memory: each array has up to one huge
  // page of slack, and resident memory is counted in 2 MiB pages, so the reproduction's peak
  // added memory (runs above 10 MB, docs/results, 2026-11-23) grew by 1.19x at the median and
  // 1.57x at most.
  static constexpr std::size_t kHugePage = std::size_t{2} << 20;
  static constexpr std::size_t kHugeThreshold = std::size_t{4} << 20;

  template <typename U>
  struct rebind {
    using other =
        DefaultInitAllocator<U, typename std::allocator_traits<Base>::template rebind_alloc<U>>;
  };
  using Base::Base;

  // n elements, uninitialised; throws std::bad_alloc as std::allocator does.
  T* allocate(std::size_t n) {
    if (n < kHugeThreshold / sizeof(T)) return Base::allocate(n);
    if (n > (SIZE_MAX - kHugePage) / sizeof(T)) throw std::bad_array_new_length();
    const std::size_t bytes = n * sizeof(T);
    const std::size_t rounded = (bytes + kHugePage - 1) / kHugePage * kHugePage;
    void* p = std::aligned_alloc(kHugePage, rounded);
    if (p == nullptr) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
    madvise(p, rounded, MADV_HUGEPAGE);  // a refusal (EINVAL where THP is not built) is harmless
#endif
    return static_cast<T*>(p);
  }
  // Frees what allocate(n) returned, by the same size rule.
  void deallocate(T* p, std::size_t n) {
    if (n < kHugeThreshold / sizeof(T)) return Base::deallocate(p, n);
    std::free(p);
  }

  template <typename U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    std::allocator_traits<Base>::construct(static_cast<Base&>(*this), p,
                                           std::forward<Args>(args)...);
  }
};

// A vector whose new elements are left for the caller to write (see DefaultInitAllocator).
template <typename T>
using FillLater = std::vector<T, DefaultInitAllocator<T>>;

// Makes `v` n elements long for a pass that overwrites every one, in the memory it already has
// when that is enough; else in a new array with an eighth more room, since a refinement's late
// iterations grow by a few percent. Why: fresh memory costs a page fault and the kernel's zeroing
// per page, and on this project's VM that was 0.18 s for the 95 MB tet-edge array of 3.95 M
// tets, a third of AddTetEdges (2026-11-24). Whatever `v` held is not kept.
template <typename T>
void ResizeForRefill(FillLater<T>& v, size_t n) {
  if (v.capacity() < n) {
    v = {};
    v.reserve(n + n / 8);
  }
  v.resize(n);
}

}  // namespace tetrefine
