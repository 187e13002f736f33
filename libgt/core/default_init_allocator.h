// An allocator for buffers that are written in full right after they are sized: a
// std::vector<T, DefaultInitAllocator<T>> grown with resize() default-initialises its new
// elements (no zeroing of floats or integers), unlike std::vector<T>.
#pragma once

#include <memory>
#include <new>
#include <type_traits>
#include <utility>

namespace gt {

// std::allocator whose value-initialisation is default-initialisation.
template <typename T>
struct DefaultInitAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() = default;
  template <typename U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}  // NOLINT: implicit
  template <typename U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

}  // namespace gt
