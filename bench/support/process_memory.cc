#include "bench/support/process_memory.h"

#include <malloc.h>

#include <cstdio>
#include <cstring>

namespace tetrefine::bench {
namespace {

int64_t StatusField(const char* name) {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (f == nullptr) return -1;
  char line[256];
  int64_t kib = -1;
  const size_t len = std::strlen(name);
  while (std::fgets(line, sizeof line, f) != nullptr) {
    if (std::strncmp(line, name, len) == 0 && line[len] == ':') {
      long long v = 0;
      if (std::sscanf(line + len + 1, "%lld", &v) == 1) kib = v;
      break;
    }
  }
  std::fclose(f);
  return kib < 0 ? -1 : kib * 1024;
}

bool ResetPeakRss() {
  // "5" resets the peak RSS counter to the current RSS (Linux >= 4.0, proc(5)).
  std::FILE* f = std::fopen("/proc/self/clear_refs", "w");
  if (f == nullptr) return false;
  const bool ok = std::fputs("5", f) >= 0;
  return std::fclose(f) == 0 && ok;
}

}  // namespace

int64_t CurrentRssBytes() { return StatusField("VmRSS"); }
int64_t PeakRssBytes() { return StatusField("VmHWM"); }

PeakMemoryScope::PeakMemoryScope() {
  malloc_trim(0);
  reset_ok_ = ResetPeakRss();
  start_rss_ = CurrentRssBytes();
}

int64_t PeakMemoryScope::AddedPeakBytes() const {
  const int64_t peak = PeakRssBytes();
  if (!reset_ok_ || start_rss_ < 0 || peak < 0) return -1;
  return peak > start_rss_ ? peak - start_rss_ : 0;
}

}  // namespace tetrefine::bench
