#pragma once
// A std::vector whose resize(n) leaves new elements of trivial types unwritten (default-initialised)
// instead of zeroing them: for large arrays that several threads then fill in place, so that each
// page is first touched, faulted in and zeroed by the kernel, on the thread that writes it, not in
// one serial pass of resize(). resize(n, value), push_back and assign write as usual. The BVH's
// arrays are such (bvh/bvh.h: the binary nodes, the leaf-ordered triangles, the 4- and 8-wide
// nodes and packets), filled by the build and the collapses on every thread.
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace raysort {

template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() noexcept = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
  // construct(p) with no value default-initialises (a trivial type stays unwritten); with a value,
  // as std::allocator.
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

template <class T>
using UninitVector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace raysort
