#pragma once

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
  template <typename U>
  struct rebind {
    using other =
        DefaultInitAllocator<U, typename std::allocator_traits<Base>::template rebind_alloc<U>>;
  };
  using Base::Base;

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

}  // namespace tetrefine
