#include "server/log_rate_limit.h"

#include "absl/strings/str_cat.h"

namespace tetrefine::server {

bool LogRateLimit::Allow(int64_t* suppressed, Clock::time_point now) {
  std::lock_guard<std::mutex> lock(mu_);
  if (now - window_start_ >= std::chrono::seconds(1)) {
    window_start_ = now;
    in_window_ = 0;
  }
  if (in_window_ >= per_second_) {
    ++dropped_;
    return false;
  }
  ++in_window_;
  *suppressed = dropped_;
  dropped_ = 0;
  return true;
}

std::string LogRateLimit::SuppressedNote(int64_t suppressed) {
  if (suppressed <= 0) return "";
  return absl::StrCat(" (", suppressed, " calls refused since the last such line were not logged)");
}

}  // namespace tetrefine::server
