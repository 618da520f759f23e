#include "core/huge_pages.h"

#include <sys/mman.h>

#include <cstdint>

namespace tetrefine {

void AdviseHugePages(const void* data, size_t bytes) {
  constexpr size_t kMin = size_t{4} << 20;
  constexpr uintptr_t kPage = 4096;
  if (data == nullptr || bytes < kMin) return;
  const uintptr_t start = (reinterpret_cast<uintptr_t>(data) + kPage - 1) & ~(kPage - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(data) + bytes) & ~(kPage - 1);
  if (end <= start) return;
  // Advice only: a kernel without THP answers EINVAL and nothing changes.
  madvise(reinterpret_cast<void*>(start), end - start, MADV_HUGEPAGE);
}

}  // namespace tetrefine
