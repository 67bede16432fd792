#pragma once
// Large host buffers on 2 MiB pages where the kernel lends them (Linux transparent huge pages in
// "madvise" mode, Debian's default). A buffer's first touch faults in every 4 KiB page, and on a
// virtual machine a fault costs microseconds: the BVH build fills tens of MB fresh on every
// build, and on a 322 K-triangle scene the 4-wide collapse took 124-135 ms with 4 KiB pages
// against 19-27 ms with 2 MiB pages, six builds each (docs/trace.md, "BVH build"). Embree asks
// for huge pages for its own build memory too. Elsewhere (another OS, THP "never") the advice is
// a no-op.
#include <cstddef>
#include <memory>
#include <vector>

namespace raysort {

// Asks the kernel to back [p, p + bytes) with huge pages (the whole 4 KiB pages inside it). Call
// before the memory is first written; pages already touched stay as they are.
void advise_huge_pages(void* p, std::size_t bytes);

// v.reserve(n), then the advice on the reserved storage, for an empty vector about to be filled.
template <class T, class Alloc>
void reserve_huge(std::vector<T, Alloc>& v, std::size_t n) {
  v.reserve(n);
  advise_huge_pages(v.data(), v.capacity() * sizeof(T));
}

// A vector of n elements whose storage was advised before it was written: value-initialised for
// std::vector, unwritten for an UninitVector (util/uninit_vector.h) that threads then fill.
template <class T, class Alloc = std::allocator<T>>
std::vector<T, Alloc> huge_vector(std::size_t n) {
  std::vector<T, Alloc> v;
  reserve_huge(v, n);
  v.resize(n);
  return v;
}

}  // namespace raysort
