#pragma once

#include <cstdint>

namespace tetrefine::bench {

// Resident memory of this process from /proc/self/status (Linux), in bytes; -1 if unreadable.
int64_t CurrentRssBytes();  // VmRSS
int64_t PeakRssBytes();     // VmHWM: the high-water mark since start or the last reset

// Measures the peak resident memory a piece of work adds, from the kernel's own high-water mark
// (VmHWM), which sees every page the work touched however briefly: construct it just before the
// work, call AddedPeakBytes() just after. It returns free heap to the OS (malloc_trim) and resets
// the mark through /proc/self/clear_refs first. Heap pages the allocator keeps from earlier work
// can still be reused without showing up, so the figure is a lower bound unless the process is
// fresh; tools that need the exact figure measure in a fresh process.
class PeakMemoryScope {
 public:
  PeakMemoryScope();
  // Peak RSS since construction minus RSS at construction; -1 if the mark could not be reset.
  int64_t AddedPeakBytes() const;
  // RSS at construction (after returning free heap); -1 if unreadable.
  int64_t start_rss_bytes() const { return start_rss_; }

 private:
  int64_t start_rss_ = -1;
  bool reset_ok_ = false;
};

}  // namespace tetrefine::bench
