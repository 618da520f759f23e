#pragma once

#include <cstddef>

namespace tetrefine {

// Asks the kernel to back the untouched memory [data, data + bytes) with transparent huge pages
// (madvise MADV_HUGEPAGE), a no-op below 4 MiB or where the kernel says no. Debian's default THP
// mode is "madvise", so without the advice a 60 MB mesh buffer faults in 15 000 small pages;
// on the 2-core VM of bench/file_to_file.sh that made encoding an uncompressed 1.6 M-tet .vtu
// take 0.48 s instead of 0.03 s (bench/mesh_io_bench, with GLIBC_TUNABLES=glibc.malloc.hugetlb=1
// as the comparison). In the core, the edge table's buckets and the arrays a subdivision
// writes had the same cost: page faults were a third of a whole refinement call (see
// core/subdivide.cc). Call it after reserving and before writing; the bits written do not
// change. For arrays the core allocates itself, FillLater (core/fill_later.h) does the same.
void AdviseHugePages(const void* data, size_t bytes);

// Reserves room for `n` elements in a vector or string and advises huge pages for it.
template <typename Container>
void ReserveHuge(Container& c, size_t n) {
  c.reserve(n);
  AdviseHugePages(c.data(), c.capacity() * sizeof(*c.data()));
}

}  // namespace tetrefine
